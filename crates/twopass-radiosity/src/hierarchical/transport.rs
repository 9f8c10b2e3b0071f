//! The transport of a link: exact point form factors between surfaces, the isotropic
//! far-field estimate with a cluster at either end, and the visible fraction.

use std::f64::consts::PI;

use glam::DVec3;
use twopass_brdf::random::hash;

use super::directions::Dir;
use super::link::Eval;
use super::state::{HierarchicalSolver, SEPARATION};
use crate::cluster::{Kind, NodeRef};
use crate::form_factor;

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
        let ns = self.scene.mesh.geometric_normals
            [self.mesh.nodes[q as usize].scene_triangle as usize]
            .as_dvec3();
        (form_factor::SourceTriangle::new(self.mesh.corners(q)), ns)
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
                let nq = self.scene.mesh.geometric_normals
                    [self.mesh.nodes[q as usize].scene_triangle as usize]
                    .as_dvec3();
                let d = er.center - es.center;
                let cos = (nq.dot(d) / d2.sqrt().max(f64::MIN_POSITIVE)).max(0.0);
                let v = es.area * cos / (PI * far2);
                ([v; 3], v * dir.opposite().read(&self.projected[c as usize]))
            }
            (Kind::Cluster(c), Kind::Cluster(_)) => {
                // Flux density per unit of the source's radiant table entry: 1 / (pi l^2).
                near_cluster = near;
                let v = 1.0 / (PI * far2);
                ([v; 3], v * dir.opposite().read(&self.projected[c as usize]))
            }
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
