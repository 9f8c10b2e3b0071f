//! The transport of a link: exact point form factors between surfaces, the far-field
//! estimate with a cluster at either end (corrected for the ends' extent), and the visible
//! fraction.

use std::f64::consts::PI;

use glam::DVec3;
use twopass_brdf::random::hash;

use super::directions::Dir;
use super::geometry::{centre_and_radius, seven_points};
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

/// A source whose plane is closer to the receiver than this share of the receiver's radius,
/// the two facing each other, has its form factor's area average integrated adaptively
/// ([`adaptive_average`]).
const ADAPT_GAP: f64 = 0.5;

/// Gaps below this share of the scene's diagonal are not integrated adaptively: they near what
/// the shadow rays resolve (a hit farther than twice a surface point's rounding, about 1e-6 of
/// the coordinates; `twopass_scene`'s `near_t`), and integrated on some links but not on others
/// where the rays do not resolve them, the transport errs with one sign (with rays that passed
/// through the wall, a light 1e-6 of the room from it created a quarter of its power); there
/// the bound on what leaves send (`bound`) holds the solve.
const MIN_GAP: f64 = 1e-5;

/// Sub-triangles an adaptive average may split at most, per link.
const ADAPT_BUDGET: usize = 4096;

/// Depth an adaptive average splits to at most: pieces 1/1024 of the receiver's size.
const ADAPT_DEPTH: u32 = 14;

/// Absolute error in the form factor at which a piece's average is accepted: its four
/// children's mean and its own seven-point average agree to within it.
const ADAPT_TOLERANCE: f64 = 2e-3;

/// The seven-point average of a form factor over a triangle, exact for cubics (corners 1/20,
/// edge midpoints 2/15, centroid 9/20), from values at corners, centroid and edge midpoints.
fn seven_point_average(f: &[f64; 7]) -> f64 {
    (f[0] + f[1] + f[2]) / 20.0 + (f[4] + f[5] + f[6]) * (2.0 / 15.0) + f[3] * (9.0 / 20.0)
}

/// The seven-point average over the triangle `c` (corner normals `nc`) of the point form factor
/// from `source` (unit normal `ns`).
fn piece_average(
    source: &form_factor::SourceTriangle,
    ns: DVec3,
    c: [DVec3; 3],
    nc: [DVec3; 3],
) -> f64 {
    let (x, n) = seven_points(c, nc, 0.0);
    let mut f = [0.0; 7];
    source.form_factors_into(&x, &n, Some(ns), &mut f);
    seven_point_average(&f)
}

/// Whether source triangle `source` (unit normal `ns`) faces the receiver triangle `c` (unit
/// normal `n`) across a gap narrower than [`ADAPT_GAP`] of the receiver's radius (and at
/// least `min_gap`, scene units): the
/// receiver's points then see the source's footprint as a plateau with edges of the gap's
/// width, which seven points cannot average (a small source's footprint may fall between
/// them altogether).
fn facing_closely(
    source: &form_factor::SourceTriangle,
    ns: DVec3,
    c: [DVec3; 3],
    n: DVec3,
    min_gap: f64,
) -> bool {
    let (centre, radius) = centre_and_radius(c);
    let gap = source
        .corners
        .iter()
        .map(|p| (*p - centre).dot(n).abs())
        .fold(f64::MAX, f64::min);
    ns.dot(n) < -0.5 && gap < ADAPT_GAP * radius && gap >= min_gap
}

/// The three edges of a source triangle, for distances to its outline.
struct SourceEdges {
    edges: [(DVec3, DVec3); 3],
    /// The source's radius about its centroid, scene units.
    radius: f64,
}

impl SourceEdges {
    fn of(source: &form_factor::SourceTriangle) -> Self {
        let c = source.corners;
        Self {
            edges: [(c[0], c[1]), (c[1], c[2]), (c[2], c[0])],
            radius: centre_and_radius(c).1,
        }
    }

    /// Distance from `x` to the nearest point of the triangle's outline.
    fn distance(&self, x: DVec3) -> f64 {
        self.edges
            .iter()
            .map(|&(a, b)| {
                let ab = b - a;
                let t =
                    ((x - a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
                (x - (a + ab * t)).length()
            })
            .fold(f64::MAX, f64::min)
    }
}

/// The area average over triangle `c` (corner normals `nc`) of the point form factor from
/// `source`, integrated adaptively: a piece is split into its four midpoint triangles until it
/// is smaller than its distance to the source's outline (where the form factor changes over
/// the gap's width) and their mean agrees with its own seven-point average (`whole`) within
/// [`ADAPT_TOLERANCE`], down to [`ADAPT_DEPTH`] and within `budget` splits. The pieces split
/// are those along the outline's footprint.
#[allow(clippy::too_many_arguments)]
fn adaptive_average(
    source: &form_factor::SourceTriangle,
    ns: DVec3,
    edges: &SourceEdges,
    c: [DVec3; 3],
    nc: [DVec3; 3],
    whole: f64,
    depth: u32,
    budget: &mut usize,
) -> f64 {
    if depth >= ADAPT_DEPTH || *budget == 0 {
        return whole;
    }
    *budget -= 1;
    let mid = |i: usize, j: usize| {
        (
            (c[i] + c[j]) * 0.5,
            (nc[i] + nc[j]).try_normalize().unwrap_or(nc[i]),
        )
    };
    let ((ab, nab), (bc, nbc), (ca, nca)) = (mid(0, 1), mid(1, 2), mid(2, 0));
    let pieces = [
        ([c[0], ab, ca], [nc[0], nab, nca]),
        ([ab, c[1], bc], [nab, nc[1], nbc]),
        ([ca, bc, c[2]], [nca, nbc, nc[2]]),
        ([ab, bc, ca], [nab, nbc, nca]),
    ];
    let parts = pieces.map(|(p, n)| piece_average(source, ns, p, n));
    let split = parts.iter().sum::<f64>() / 4.0;
    let (centre, radius) = centre_and_radius(c);
    // A piece's error weighs in the receiver's average by its area, 4^-depth; about 2^depth
    // pieces lie along the outline at a depth, so each may err by 2^depth / 3 of the
    // tolerance. A piece near the source is also smaller than half the source, so that a
    // small source's footprint cannot fall between its points.
    let allowed = ADAPT_TOLERANCE * f64::from(1u32 << depth) / 3.0;
    if (split - whole).abs() <= allowed && radius < edges.distance(centre).max(0.5 * edges.radius) {
        return split;
    }
    pieces
        .iter()
        .zip(parts)
        .map(|(&(p, n), part)| adaptive_average(source, ns, edges, p, n, part, depth + 1, budget))
        .sum::<f64>()
        / 4.0
}

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
        let (center, radius) = centre_and_radius(corners);
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
        let average = seven_point_average(&f);
        let quadratic = mean / 4.0 + f[3] * 0.75;
        let (lo, hi) = f
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        // Where the form factor jumps inside the receiver (a source closer to it than it is
        // wide: the edge of the source's footprint crosses it), the seven points miss the area
        // average by up to a quarter either way; those errors cancel between neighbours, but
        // not once the bound cuts the leaves whose links sum above one, and a light a hair's
        // breadth from a wall lost a tenth of its power that way. The energy takes the
        // average integrated adaptively there; the error estimate stays the seven points'.
        let corners = self.mesh.corners(p);
        let exact = if facing_closely(
            &source,
            ns,
            corners,
            n[3],
            MIN_GAP * f64::from(self.scene.bounds.diagonal()),
        ) {
            let normals = self.corner_normals(p);
            let mut budget = ADAPT_BUDGET;
            let edges = SourceEdges::of(&source);
            adaptive_average(
                &source,
                ns,
                &edges,
                corners,
                normals,
                average,
                0,
                &mut budget,
            )
        } else {
            average
        };
        (
            f,
            exact - mean,
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
