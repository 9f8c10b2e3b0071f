//! Visibility between hierarchy nodes: stratified shadow rays between two nodes or from a point
//! to a node, each ray weighted by the light it carries.

use twopass_brdf::colour::luminance_f64;
use twopass_brdf::random::hash;
use twopass_brdf::random::unit_f64;
use twopass_scene::SurfacePoint;

use super::state::HierarchicalSolver;
use crate::cluster::NodeRef;

/// A random affine permutation `m -> (mult m + off) mod n` of `0..n` from hash `h`: `off`
/// uniform in `0..n`, `mult` coprime to `n`.
fn pairing(h: u64, n: u64) -> (u64, u64) {
    fn gcd(a: u64, b: u64) -> u64 {
        if b == 0 { a } else { gcd(b, a % b) }
    }
    let n = n.max(1);
    let mut mult = 1 + hash(h) % n;
    while gcd(mult, n) != 1 {
        mult = mult % n + 1;
    }
    (mult, h % n)
}

/// The visible fraction from weighted ray counts `[geometric, geometric x source exitance]`:
/// by the exitance-weighted sums when the source points sent anything, else by the geometric
/// ones; 0 when no weight at all (every pair at a grazing angle).
fn weighted_fraction(seen: [f64; 2], all: [f64; 2]) -> f64 {
    if all[1] > 0.0 {
        (seen[1] / all[1]).clamp(0.0, 1.0)
    } else if all[0] > 0.0 {
        (seen[0] / all[0]).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

impl HierarchicalSolver<'_> {
    /// How much a shadow ray from `to` (on the receiving end) to `from` (on the sending end,
    /// on `leaf`) stands for: the source's exitance luminance there (W/m^2, its last gathered
    /// value) times the pair's geometric term cos cos / d^2, the distance held above a tenth of
    /// the ends' size so that a pair of points at a shared edge does not take all the weight.
    /// Zero when the source point sends nothing yet (before the first gather); the caller then
    /// falls back to the geometric term alone.
    fn ray_weight(
        &self,
        to: &SurfacePoint,
        from: &SurfacePoint,
        leaf: u32,
        near2: f64,
    ) -> [f64; 2] {
        let d = (from.position - to.position).as_dvec3();
        let l2 = d.length_squared().max(f64::MIN_POSITIVE);
        let cos2 = (to.normal.as_dvec3().dot(d) * -from.normal.as_dvec3().dot(d)).max(0.0) / l2;
        let g = cos2 / l2.max(near2);
        let [e, r] = self.exitance[leaf as usize];
        [g, g * luminance_f64(e + r).max(0.0)]
    }

    /// The visible fraction between two nodes from about `count` stratified shadow rays
    /// between points on both, each ray weighted by what it carries: the geometric term of its
    /// two ends and the exitance of its source point (see [`Self::ray_weight`]), so that a
    /// bright part of the source that the receiver sees and a dark part it does not (the
    /// floor in a sphere's shadow, hidden by the same sphere) are not averaged into a
    /// uniform source half seen. Pairs of points that face away from each other do not count:
    /// orientation is the form factor's business, the rays only look for what stands between.
    /// When no pair faces, a grid four times as fine is drawn (a few samples can all land on
    /// the far side of a cluster by chance); when it finds none either, the two ends do not
    /// face each other and nothing passes.
    pub(super) fn visibility(&self, r: NodeRef, s: NodeRef, count: u32, seed: u64) -> (f64, u64) {
        let mut k = (f64::from(count).sqrt().round() as u32).max(1);
        let near = 0.1 * self.ends(r).radius.min(self.ends(s).radius);
        for _ in 0..2 {
            let mut total = 0u32;
            let (mut seen, mut all) = ([0.0f64; 2], [0.0f64; 2]);
            // Both ends are stratified k x k; receiver stratum `m` is paired with source
            // stratum `(mult m + off) mod k^2`, a permutation drawn per link. A fixed pairing
            // would tie one part of the receiver to one part of the source for every link, and
            // a blocker between those parts would be seen by all of them or none: a bias that
            // only finer strata remove. With a random permutation each pair is uniform over
            // both ends.
            let n = u64::from(k * k);
            let (mult, off) = pairing(hash(seed ^ 0x9e37_79b9), n);
            for m in 0..n {
                let (i, j) = ((m / u64::from(k)) as u32, (m % u64::from(k)) as u32);
                let p = (mult * m + off) % n;
                let (pi, pj) = ((p / u64::from(k)) as u32, (p % u64::from(k)) as u32);
                let h = hash(seed ^ (u64::from(k) << 48 | u64::from(i) << 24 | u64::from(j)));
                let kf = f64::from(k);
                let (a, _) = self.sample_point(
                    r,
                    [
                        (f64::from(i) + unit_f64(h)) / kf,
                        (f64::from(j) + unit_f64(hash(h))) / kf,
                        unit_f64(hash(h ^ 1)),
                    ],
                );
                let (b, leaf) = self.sample_point(
                    s,
                    [
                        (f64::from(pi) + unit_f64(hash(h ^ 2))) / kf,
                        (f64::from(pj) + unit_f64(hash(h ^ 3))) / kf,
                        unit_f64(hash(h ^ 4)),
                    ],
                );
                let d = b.position - a.position;
                if d.dot(a.normal) <= 0.0 || d.dot(b.normal) >= 0.0 {
                    continue;
                }
                total += 1;
                let w = self.ray_weight(&a, &b, leaf, near * near);
                if !self.scene.occluded_between(&a, &b) {
                    seen[0] += w[0];
                    seen[1] += w[1];
                }
                all[0] += w[0];
                all[1] += w[1];
            }
            if total > 0 {
                return (weighted_fraction(seen, all), u64::from(total));
            }
            k *= 2;
        }
        (0.0, 0)
    }

    /// The visible fraction of node `s` from surface point `from`, by about `count` stratified
    /// shadow rays to points of `s` that face it, weighted as in [`Self::visibility`]; 1 when
    /// none does (the form factor, which is zero then or nearly, has the last word).
    pub(super) fn point_visibility(
        &self,
        from: &SurfacePoint,
        s: NodeRef,
        count: u32,
        seed: u64,
    ) -> (f64, u64) {
        let k = (f64::from(count).sqrt().round() as u32).max(1);
        let near = 0.1 * self.ends(s).radius;
        let mut total = 0u32;
        let (mut seen, mut all) = ([0.0f64; 2], [0.0f64; 2]);
        for i in 0..k {
            for j in 0..k {
                let h = hash(seed ^ (u64::from(i) << 24 | u64::from(j)));
                let (fi, fj, kf) = (f64::from(i), f64::from(j), f64::from(k));
                let (b, leaf) = self.sample_point(
                    s,
                    [
                        (fi + unit_f64(h)) / kf,
                        (fj + unit_f64(hash(h))) / kf,
                        unit_f64(hash(h ^ 1)),
                    ],
                );
                if (b.position - from.position).dot(b.normal) >= 0.0 {
                    continue;
                }
                total += 1;
                let w = self.ray_weight(from, &b, leaf, near * near);
                if !self.scene.occluded_between(from, &b) {
                    seen[0] += w[0];
                    seen[1] += w[1];
                }
                all[0] += w[0];
                all[1] += w[1];
            }
        }
        if total == 0 {
            return (1.0, 0);
        }
        (weighted_fraction(seen, all), u64::from(total))
    }
}
