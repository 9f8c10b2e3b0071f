//! The geometry of hierarchy nodes: their bounding spheres and areas ([`Ends`]), normal cones
//! and the culling of pairs that face away, their children, random points on them and the
//! receiving points of surface nodes.

use std::f64::consts::PI;

use glam::{DVec2, DVec3, Vec2};
use twopass_brdf::colour::luminance_f64;
use twopass_scene::SurfacePoint;

use super::state::{CORNER_INSET, HierarchicalSolver};
use crate::cluster::{Kind, NodeRef};

/// The angle between two unit vectors, radians.
pub(super) fn angle(a: DVec3, b: DVec3) -> f64 {
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// The smallest cone (unit axis, half-angle) around two cones.
pub(super) fn merge_cones(a: (DVec3, f64), b: (DVec3, f64)) -> (DVec3, f64) {
    let between = angle(a.0, b.0);
    if between + b.1 <= a.1 {
        return a;
    }
    if between + a.1 <= b.1 {
        return b;
    }
    let half = (between + a.1 + b.1) / 2.0;
    if half >= PI || !(1e-12..=PI - 1e-6).contains(&between) {
        return (a.0, if between < 1e-12 { half } else { PI });
    }
    // Turn a's axis toward b's by (half - a's half-angle).
    let t = (half - a.1) / between;
    let axis = (a.0 * ((1.0 - t) * between).sin() + b.0 * (t * between).sin()) / between.sin();
    (axis.normalize_or(a.0), half)
}

/// Node geometry the link estimates need.
pub(super) struct Ends {
    pub(super) center: DVec3,
    pub(super) radius: f64,
    pub(super) area: f64,
}

impl HierarchicalSolver<'_> {
    /// The normal cone of a surface node: its geometric normal, widened to its corners'
    /// shading normals.
    pub(super) fn surface_cone(&self, n: u32) -> (DVec3, f64) {
        let node = &self.mesh.nodes[n as usize];
        let g = self
            .scene
            .mesh
            .geometric_normal(node.scene_triangle)
            .as_dvec3();
        let spread = node
            .vertices
            .iter()
            .map(|&v| angle(g, self.mesh.vertices[v as usize].normal.as_dvec3()))
            .fold(0.0, f64::max);
        (g, spread)
    }

    pub(super) fn cone(&self, r: NodeRef) -> (DVec3, f64) {
        match r.kind() {
            Kind::Cluster(c) => self.cones[c as usize],
            Kind::Surface(n) => self.surface_cone(n),
        }
    }

    /// Whether no surface of `s` can send light to any surface of `r` (normal-cone culling,
    /// Shirman & Abi-Ezzi 1993): every normal of the source points away from every direction
    /// toward the receiver, or every normal of the receiver away from the source. Two parts of
    /// one convex object are never linked.
    pub(super) fn faces_away(&self, r: NodeRef, s: NodeRef) -> bool {
        let (er, es) = (self.ends(r), self.ends(s));
        let d = er.center - es.center;
        let dist = d.length();
        let reach = er.radius + es.radius;
        if dist <= reach {
            return false;
        }
        let u = d / dist;
        let spread = (reach / dist).asin();
        let right = std::f64::consts::FRAC_PI_2;
        let (a_s, t_s) = self.cone(s);
        let (a_r, t_r) = self.cone(r);
        angle(a_s, u) - t_s - spread >= right || angle(a_r, -u) - t_r - spread >= right
    }

    pub(super) fn ends(&self, r: NodeRef) -> Ends {
        match r.kind() {
            Kind::Cluster(c) => {
                let cl = &self.clusters.nodes[c as usize];
                Ends {
                    center: cl.center,
                    radius: cl.radius,
                    area: cl.area,
                }
            }
            Kind::Surface(n) => {
                let (center, radius) = centre_and_radius(self.mesh.corners(n));
                Ends {
                    center,
                    radius,
                    area: f64::from(self.mesh.nodes[n as usize].area),
                }
            }
        }
    }

    /// Reflectance luminance of a receiver (the largest inside a cluster).
    pub(super) fn rho_lum(&self, r: NodeRef) -> f64 {
        match r.kind() {
            Kind::Cluster(c) => self.clusters.nodes[c as usize].rho_max,
            Kind::Surface(n) => luminance_f64(self.node_rho(n)),
        }
    }

    /// The diffuse reflectance of surface node `n`: the texture's mean over it in a scene with
    /// textures, its triangle's material's otherwise.
    pub(super) fn node_rho(&self, n: u32) -> DVec3 {
        match self.node_rho.get(n as usize) {
            Some(&rho) => rho,
            None => self.tri_rho[self.mesh.nodes[n as usize].scene_triangle as usize],
        }
    }

    pub(super) fn splittable(&self, r: NodeRef) -> bool {
        match r.kind() {
            Kind::Cluster(_) => true,
            Kind::Surface(n) => {
                self.mesh.nodes[n as usize].children.is_some()
                    || self.mesh.longest_edge_length(n) > self.min_size
            }
        }
    }

    pub(super) fn children(&self, r: NodeRef) -> [NodeRef; 2] {
        match r.kind() {
            Kind::Cluster(c) => self.clusters.nodes[c as usize].children,
            Kind::Surface(n) => self.mesh.nodes[n as usize]
                .children
                .expect("a split surface node has children")
                .map(NodeRef::surface),
        }
    }

    /// A point on node `r` for three uniform numbers: area-uniform over a surface node; over a
    /// cluster, a triangle picked by area and a uniform point on it. Also the leaf of the
    /// element mesh it lies on.
    pub(super) fn sample_point(&self, r: NodeRef, u: [f64; 3]) -> (SurfacePoint, u32) {
        let (t, uv, from) = match r.kind() {
            Kind::Surface(n) => {
                let node = &self.mesh.nodes[n as usize];
                let s = u[0].sqrt();
                let w = [1.0 - s, s * (1.0 - u[1]), s * u[1]];
                let b = node.uv[0].as_dvec2() * w[0]
                    + node.uv[1].as_dvec2() * w[1]
                    + node.uv[2].as_dvec2() * w[2];
                (node.scene_triangle, b, n)
            }
            Kind::Cluster(c) => {
                let (t, _) = self.clusters.pick_triangle(c, u[0]);
                let s = u[1].sqrt();
                let b = DVec2::new(s * (1.0 - u[2]), s * u[2]);
                (t, b, self.mesh.roots[t as usize])
            }
        };
        let point = self
            .scene
            .mesh
            .surface_point(t, [(1.0 - uv.x - uv.y) as f32, uv.x as f32, uv.y as f32]);
        (point, self.descend(from, uv.as_vec2()))
    }

    /// The leaf below surface node `n` that holds the point `uv` (triangle parameters).
    fn descend(&self, mut n: u32, uv: Vec2) -> u32 {
        while let Some([c0, c1]) = self.mesh.nodes[n as usize].children {
            // The first child is (a, m, c), cut from its sibling along m-c.
            let [a, m, c] = self.mesh.nodes[c0 as usize].uv;
            let side = |q: Vec2| (c - m).perp_dot(q - m);
            n = if side(uv) * side(a) >= 0.0 { c0 } else { c1 };
        }
        n
    }

    /// The receiving points of a surface node: its corners, a hair inside (junction vertices
    /// receive from just inside their own surface, as in progressive refinement), and their
    /// receiving normals; plus the centroid and its normal.
    pub(super) fn receiving_points(&self, n: u32) -> ([DVec3; 7], [DVec3; 7]) {
        seven_points(self.mesh.corners(n), self.corner_normals(n), CORNER_INSET)
    }

    /// The unit receiving normals at surface node `n`'s three corners (its vertices').
    pub(super) fn corner_normals(&self, n: u32) -> [DVec3; 3] {
        self.mesh.nodes[n as usize]
            .vertices
            .map(|v| self.mesh.vertices[v as usize].normal.as_dvec3())
    }
}

/// The centroid of the triangle `c` and its radius about it (the farthest corner), scene
/// units.
pub(super) fn centre_and_radius(c: [DVec3; 3]) -> (DVec3, f64) {
    let centre = (c[0] + c[1] + c[2]) / 3.0;
    let radius = c.iter().map(|p| (*p - centre).length()).fold(0.0, f64::max);
    (centre, radius)
}

/// The seven points of a triangle with corners `p` and corner normals `normals` that the
/// seven-point rule reads (corners, centroid, edge midpoints; corners and midpoints moved
/// `inset` of the way toward the centroid) and their normals (blended, unit).
pub(super) fn seven_points(
    p: [DVec3; 3],
    normals: [DVec3; 3],
    inset: f64,
) -> ([DVec3; 7], [DVec3; 7]) {
    let c = (p[0] + p[1] + p[2]) / 3.0;
    let blend = |a: DVec3, b: DVec3| (a + b).try_normalize().unwrap_or(a);
    let nc = blend(normals[0] + normals[1], normals[2]);
    let inset = |q: DVec3| q + (c - q) * inset;
    let mid = |i: usize, j: usize| inset((p[i] + p[j]) * 0.5);
    (
        [
            inset(p[0]),
            inset(p[1]),
            inset(p[2]),
            c,
            mid(0, 1),
            mid(1, 2),
            mid(2, 0),
        ],
        [
            normals[0],
            normals[1],
            normals[2],
            nc,
            blend(normals[0], normals[1]),
            blend(normals[1], normals[2]),
            blend(normals[2], normals[0]),
        ],
    )
}
