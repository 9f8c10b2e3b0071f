//! The transport of a link: exact point form factors between surfaces, the far-field
//! estimate with a cluster at either end (corrected for the ends' extent), and the visible
//! fraction.

use std::f64::consts::PI;

use glam::DVec3;
use twopass_brdf::random::hash;

use super::directions::Dir;
use super::link::Eval;
use super::links::RESOLVE_DEPTH;
use super::state::{HierarchicalSolver, SEPARATION};
use crate::cluster::{Kind, NodeRef};
use crate::form_factor;

/// Parts of an end of a far-field link are split until their bounding radius is at most this
/// share of the distance between the ends' centres: the far-field error falls with the square
/// of the parts' size, to about (1/8)^2 of the pair's.
const PART_RADIUS: f64 = 0.125;

/// Parts an end of a far-field link is taken in at most.
const MAX_PARTS: usize = 16;

/// The extent correction of a far-field link stays within this factor either way.
const MAX_RATIO: f64 = 4.0;

/// A part of an end of a far-field link: a cluster, or a flat triangle (a scene triangle or a
/// piece of one).
struct Part {
    center: DVec3,
    radius: f64,
    shape: Shape,
}

enum Shape {
    Cluster(u32),
    /// A triangle: its corners, unit normal and area (scene units squared).
    Flat {
        corners: [DVec3; 3],
        normal: DVec3,
        area: f64,
    },
}

impl Part {
    /// Node `x` as a part.
    fn of(solver: &HierarchicalSolver<'_>, x: NodeRef) -> Self {
        match x.kind() {
            Kind::Cluster(c) => {
                let cl = &solver.clusters.nodes[c as usize];
                Self {
                    center: cl.center,
                    radius: cl.radius,
                    shape: Shape::Cluster(c),
                }
            }
            Kind::Surface(n) => {
                let t = solver.mesh.nodes[n as usize].scene_triangle as usize;
                Self::flat(
                    solver.mesh.corners(n),
                    solver.scene.mesh.geometric_normal(t as u32).as_dvec3(),
                )
            }
        }
    }

    fn flat(corners: [DVec3; 3], normal: DVec3) -> Self {
        let center = (corners[0] + corners[1] + corners[2]) / 3.0;
        let radius = corners
            .iter()
            .map(|p| (*p - center).length())
            .fold(0.0, f64::max);
        let area = 0.5
            * (corners[1] - corners[0])
                .cross(corners[2] - corners[0])
                .length();
        Self {
            center,
            radius,
            shape: Shape::Flat {
                corners,
                normal,
                area,
            },
        }
    }

    /// Projected area toward unit direction `u`, scene units squared.
    fn projected(&self, solver: &HierarchicalSolver<'_>, u: DVec3) -> f64 {
        match self.shape {
            Shape::Cluster(c) => solver.projected_at(c, None, u, RESOLVE_DEPTH),
            Shape::Flat { normal, area, .. } => area * normal.dot(u).max(0.0),
        }
    }
}

/// The far-field estimate of the power part `s` sends to part `r` per unit uniform exitance,
/// from their centres: the projected area of each toward the other over d^2 (the 1 / pi
/// dropped: only ratios are taken).
fn centre_estimate(r: &Part, s: &Part, solver: &HierarchicalSolver<'_>) -> f64 {
    let d = r.center - s.center;
    let l2 = d.length_squared();
    if l2 <= 0.0 {
        return 0.0;
    }
    let u = d / l2.sqrt();
    s.projected(solver, u) * r.projected(solver, -u) / l2
}

impl HierarchicalSolver<'_> {
    /// Unoccluded transport from surface node `q` to surface node `p`, per unit exitance of
    /// `q`: the point form factors at `p`'s seven receiving points (corners first), the shift
    /// (area average less the corners' mean) and the form-factor error estimate (per unit
    /// receiver area).
    fn surface_transport(&self, p: u32, q: u32) -> ([f64; 7], f64, f64) {
        let (x, n) = self.receiving_points(p);
        let (source, ns) = self.source_polygon(q);
        let mut f = [0.0; 7];
        source.form_factors_into(&x, &n, Some(ns), &mut f);
        // The corners keep their exact point values; the receiver's area-averaged form factor
        // sets the light it gets (interpolating a curved F linearly would lose or add light
        // with a consistent sign), by the seven-point rule exact for cubics (corners 1/20, edge
        // midpoints 2/15, centroid 9/20). The error estimate: how far that average is from the
        // corners' and from the quadratic rule's (corners 1/12, centroid 3/4), plus a part of
        // the spread.
        let mean = (f[0] + f[1] + f[2]) / 3.0;
        let average =
            (f[0] + f[1] + f[2]) / 20.0 + (f[4] + f[5] + f[6]) * (2.0 / 15.0) + f[3] * (9.0 / 20.0);
        let quadratic = mean / 4.0 + f[3] * 0.75;
        let (lo, hi) = f
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        (
            f,
            average - mean,
            (average - mean).abs() + (average - quadratic).abs() + 0.25 * (hi - lo),
        )
    }

    /// Unoccluded point form factors from surface node `q` at surface node `p`'s three
    /// receiving corners.
    pub(super) fn corner_form_factors(&self, p: u32, q: u32) -> [f64; 3] {
        let (x, n) = self.receiving_points(p);
        let (source, ns) = self.source_polygon(q);
        let mut f = [0.0; 3];
        source.form_factors_into(&x[..3], &n[..3], Some(ns), &mut f);
        f
    }

    /// Surface node `q` as a source of point form factors (its corners, prepared) and its scene
    /// triangle's unit normal.
    fn source_polygon(&self, q: u32) -> (form_factor::SourceTriangle, DVec3) {
        let ns = self
            .scene
            .mesh
            .geometric_normal(self.mesh.nodes[q as usize].scene_triangle)
            .as_dvec3();
        (form_factor::SourceTriangle::new(self.mesh.corners(q)), ns)
    }

    /// How much the far-field estimate between the centres of `r` and `s` misses: the same
    /// estimate summed over parts of an end (split until its parts are small beside the
    /// distance, see [`Self::parts`]) over the estimate at the centres, for a source of
    /// uniform exitance; the two ends' ratios multiplied (their effects add to first order,
    /// and each end's parts are then counted once, not once per part of the other).
    ///
    /// Between the centres the inverse-square kernel and the cosines are taken at one point
    /// of each end; over an end a few radii wide they vary, and by how much depends on where
    /// the other end lies: under an extended source the estimate at the centre is too high,
    /// off to its side too low. Refinement splits the links that carry much light (those
    /// under the source) and keeps the far-field ones off to the side, so the error left
    /// would have one sign: a closed grey room under strip lights lost 2 % of their light
    /// that way.
    fn extent_ratio(&self, r: NodeRef, s: NodeRef) -> f64 {
        let (er, es) = (self.ends(r), self.ends(s));
        let limit = PART_RADIUS * (er.center - es.center).length();
        // An end small beside the distance is its own only part: its ratio is one. So is a
        // surface receiver's: its transport is taken at its corners, over its extent already.
        let split_r = er.radius > limit && matches!(r.kind(), Kind::Cluster(_));
        let split_s = es.radius > limit;
        if !split_r && !split_s {
            return 1.0;
        }
        let (whole_r, whole_s) = (Part::of(self, r), Part::of(self, s));
        let whole = centre_estimate(&whole_r, &whole_s, self);
        if !(whole > 0.0 && whole.is_finite()) {
            return 1.0;
        }
        let over_r: f64 = if split_r {
            self.parts(r, limit)
                .iter()
                .map(|p| centre_estimate(p, &whole_s, self))
                .sum()
        } else {
            whole
        };
        let over_s: f64 = if split_s {
            self.parts(s, limit)
                .iter()
                .map(|p| centre_estimate(&whole_r, p, self))
                .sum()
        } else {
            whole
        };
        // Bounded: where the centres see an end nearly edge-on and its parts do not, the ratio
        // of two small numbers is not worth trusting beyond a factor of a few (the link's
        // error estimate, its whole transport, still sends it to be refined when it matters).
        let ratio = (over_r / whole) * (over_s / whole);
        if ratio.is_finite() {
            ratio.clamp(1.0 / MAX_RATIO, MAX_RATIO)
        } else {
            1.0
        }
    }

    /// Node `x` in parts of bounding radius at most `limit` (scene units), or at most
    /// [`MAX_PARTS`] parts, the largest split first: a cluster into its children, a triangle
    /// into the four triangles between its edge midpoints.
    fn parts(&self, x: NodeRef, limit: f64) -> Vec<Part> {
        let mut parts = vec![Part::of(self, x)];
        while parts.len() + 3 <= MAX_PARTS {
            let Some((i, _)) = parts
                .iter()
                .enumerate()
                .filter(|(_, p)| p.radius > limit)
                .max_by(|a, b| a.1.radius.total_cmp(&b.1.radius))
            else {
                break;
            };
            let part = parts.swap_remove(i);
            match part.shape {
                Shape::Cluster(c) => {
                    for child in self.clusters.nodes[c as usize].children {
                        parts.push(Part::of(self, child));
                    }
                }
                Shape::Flat {
                    corners, normal, ..
                } => {
                    let [a, b, c] = corners;
                    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
                    for t in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]] {
                        parts.push(Part::flat(t, normal));
                    }
                }
            }
        }
        parts
    }

    /// Transport, error estimate and visibility of the link `s -> r`, with `rays` shadow rays.
    pub(super) fn evaluate(&self, r: NodeRef, s: NodeRef, rays: u32) -> Eval {
        let (er, es) = (self.ends(r), self.ends(s));
        let reach = SEPARATION * (er.radius + es.radius);
        let d2 = (es.center - er.center).length_squared();
        let near = d2 <= reach * reach;
        let far2 = d2.max(reach * reach).max(f64::MIN_POSITIVE);
        let dir = Dir::new(&self.dirs, (er.center - es.center).normalize_or(DVec3::Z));
        let mut near_cluster = false;
        let mut shift = 0.0;
        let (k, error) = match (r.kind(), s.kind()) {
            (Kind::Surface(p), Kind::Surface(q)) => {
                let (f, s, error) = self.surface_transport(p, q);
                shift = s;
                ([f[0], f[1], f[2]], er.area * error)
            }
            (Kind::Surface(p), Kind::Cluster(_)) => {
                // Irradiance at each corner per unit of the cluster's radiant table entry
                // toward it (intensity x pi): cos / (pi l^2).
                near_cluster = near;
                let (x, n) = self.receiving_points(p);
                let k: [f64; 3] = std::array::from_fn(|i| {
                    let d = es.center - x[i];
                    let l2 = d.length_squared().max(far2 * 0.25);
                    (n[i].dot(d) / l2.sqrt()).max(0.0) / (PI * l2)
                });
                (k, er.area * (k[0] + k[1] + k[2]) / 3.0)
            }
            (Kind::Cluster(c), Kind::Surface(q)) => {
                // Flux density at the cluster per unit source exitance: A cos / (pi l^2).
                near_cluster = near;
                let nq = self
                    .scene
                    .mesh
                    .geometric_normal(self.mesh.nodes[q as usize].scene_triangle)
                    .as_dvec3();
                let d = er.center - es.center;
                let cos = (nq.dot(d) / d2.sqrt().max(f64::MIN_POSITIVE)).max(0.0);
                let v = es.area * cos / (PI * far2);
                ([v; 3], v * self.cluster_projected(c, dir.opposite()))
            }
            (Kind::Cluster(c), Kind::Cluster(_)) => {
                // Flux density per unit of the source's radiant table entry: 1 / (pi l^2).
                near_cluster = near;
                let v = 1.0 / (PI * far2);
                ([v; 3], v * self.cluster_projected(c, dir.opposite()))
            }
        };
        // Far-field estimates are corrected for the ends' extent (near ones are split anyway).
        let (k, error) =
            if !near && !matches!((r.kind(), s.kind()), (Kind::Surface(_), Kind::Surface(_))) {
                let ratio = self.extent_ratio(r, s);
                (k.map(|v| v * ratio), error * ratio)
            } else {
                (k, error)
            };
        let mut e = Eval {
            transport: k,
            open: k,
            dir,
            area_correction: shift,
            error,
            near: near_cluster,
            partial: false,
            rays: 0,
        };
        // A near link is split whatever its visibility: no rays for it.
        if e.near || e.carries_nothing() || !self.options.occlusion {
            return e;
        }
        let seed = hash(self.options.seed ^ hash(u64::from(r.id()) << 32 | u64::from(s.id())));
        let (vis, cast) = self.visibility(r, s, rays, seed);
        e.rays = cast;
        // A few rays that all miss or all hit say little about a large pair: a blocked link is
        // counted as uncertain (its unoccluded transport is the error) so that it is refined
        // until its pieces are small or surely blocked, instead of dropped with its light.
        e.partial = vis < 1.0;
        // The light the receiver gets unoccluded: its area-averaged form factor (the corners
        // can all miss a source that the inside of a large element sees).
        let average =
            ((e.transport[0] + e.transport[1] + e.transport[2]) / 3.0 + e.area_correction).max(0.0);
        e.error = e.error * vis + if e.partial { er.area * average } else { 0.0 };
        e.transport = e.transport.map(|v| v * vis);
        e.area_correction *= vis;
        e
    }
}
