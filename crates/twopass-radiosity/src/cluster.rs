//! Clusters for hierarchical radiosity (Smits, Arvo & Greenberg 1994; Sillion 1994): a binary
//! tree of bounding volumes over the participating scene triangles, so that distant groups of
//! surfaces exchange light through one link and the initial linking is not all-pairs.
//!
//! The tree is obvhs's PLOC-built `Bvh2` over the triangles' bounding boxes (one triangle per
//! leaf), which groups triangles by surface-area cost: large triangles (walls) end up near the
//! root on their own, small objects form compact clusters. A node of the radiosity hierarchy
//! is then either a cluster or a surface node (a node of a triangle's bisection tree), named
//! by a [`NodeRef`].

use std::ops::Range;
use std::time::Duration;

use glam::{DVec3, Vec3A};
use obvhs::BvhBuildParams;
use obvhs::aabb::Aabb;
use obvhs::bvh2::builder::build_bvh2;
use twopass_scene::build_coincident;

use crate::element::ElementMesh;

/// A node of the radiosity hierarchy: a surface node of the element mesh (its index in
/// [`ElementMesh::nodes`]) or a cluster (its index in [`Clusters::nodes`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct NodeRef(u32);

/// What a [`NodeRef`] names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A node of a scene triangle's bisection tree.
    Surface(u32),
    /// A cluster.
    Cluster(u32),
}

impl NodeRef {
    const CLUSTER: u32 = 1 << 31;

    /// The surface node `n` of the element mesh.
    pub fn surface(n: u32) -> Self {
        debug_assert!(n < Self::CLUSTER);
        Self(n)
    }

    /// Cluster `c`.
    pub fn cluster(c: u32) -> Self {
        debug_assert!(c < Self::CLUSTER);
        Self(c | Self::CLUSTER)
    }

    /// What this names.
    pub fn kind(self) -> Kind {
        if self.0 & Self::CLUSTER == 0 {
            Kind::Surface(self.0)
        } else {
            Kind::Cluster(self.0 & !Self::CLUSTER)
        }
    }

    /// A number unique to this node (for seeding its random streams).
    pub fn id(self) -> u32 {
        self.0
    }
}

/// A cluster: a bounding sphere around a group of triangles.
#[derive(Debug, Clone, PartialEq)]
pub struct Cluster {
    /// Centre of the bounding box, scene units.
    pub center: DVec3,
    /// Half the bounding box's diagonal, scene units.
    pub radius: f64,
    /// One-sided area of the triangles inside, scene units squared.
    pub area: f64,
    /// The two halves.
    pub children: [NodeRef; 2],
    /// The triangles inside, as a range of [`Clusters::triangles`].
    pub triangles: Range<u32>,
    /// Largest diffuse reflectance luminance of a triangle inside.
    pub rho_max: f64,
    /// The enclosing cluster, `u32::MAX` for the root.
    pub parent: u32,
}

/// The cluster tree over the participating scene triangles.
#[derive(Debug, Clone)]
pub struct Clusters {
    /// All clusters; the root is the first when there is any.
    pub nodes: Vec<Cluster>,
    /// The root of the whole hierarchy (a surface node when one triangle takes part).
    pub root: NodeRef,
    /// Participating scene triangles in tree order: each cluster's are contiguous.
    pub triangles: Vec<u32>,
    /// Running sum of the triangles' areas in that order (for area-uniform sampling).
    pub area_cdf: Vec<f64>,
    /// Per scene triangle: the cluster directly above its bisection tree (`u32::MAX` when it
    /// does not take part or is the whole hierarchy).
    pub triangle_parent: Vec<u32>,
}

impl Clusters {
    /// Builds the tree over the mesh's root nodes; `rho_lum[t]` is scene triangle `t`'s
    /// diffuse reflectance luminance, `emitting[t]` whether it emits. Returns `None` when no
    /// triangle takes part.
    ///
    /// Emitting and other triangles get a subtree each, joined only at the root: a cluster
    /// that mixed a light with the wall beside it would send the light's power from the
    /// pair's centre and by the pair's orientation (a strip light under a ceiling, its
    /// far-field links to the far side of a room half as strong as the light's own), while a
    /// cluster of emitters alone is as uniform a source as its far-field estimate assumes.
    pub fn build(mesh: &ElementMesh, rho_lum: &[f64], emitting: &[bool]) -> Option<Self> {
        let tris: Vec<u32> = (0..mesh.roots.len() as u32)
            .filter(|&t| mesh.roots[t as usize] != u32::MAX)
            .collect();
        if tris.is_empty() {
            return None;
        }
        let mut out = Self {
            nodes: Vec::new(),
            root: NodeRef::surface(mesh.roots[tris[0] as usize]),
            triangles: Vec::with_capacity(tris.len()),
            area_cdf: Vec::with_capacity(tris.len()),
            triangle_parent: vec![u32::MAX; mesh.roots.len()],
        };
        let (lit, dark): (Vec<u32>, Vec<u32>) = tris
            .iter()
            .partition(|&&t| emitting.get(t as usize).copied().unwrap_or(false));
        if lit.is_empty() || dark.is_empty() {
            out.root = out.grow(mesh, rho_lum, &tris, None).0;
            return Some(out);
        }
        // The root first (a parent comes before its children), then the two subtrees.
        out.nodes.push(Cluster {
            center: DVec3::ZERO,
            radius: 0.0,
            area: 0.0,
            children: [NodeRef::surface(0); 2],
            triangles: 0..0,
            rho_max: 0.0,
            parent: u32::MAX,
        });
        let (first, a) = out.grow(mesh, rho_lum, &lit, Some((0, 0)));
        let (second, b) = out.grow(mesh, rho_lum, &dark, Some((0, 1)));
        let (min, max) = (a.min.min(b.min).as_dvec3(), a.max.max(b.max).as_dvec3());
        let end = out.triangles.len() as u32;
        let rho_max = tris
            .iter()
            .map(|&t| rho_lum[t as usize])
            .fold(0.0, f64::max);
        out.nodes[0] = Cluster {
            center: (min + max) * 0.5,
            radius: (max - min).length() * 0.5,
            area: out.area_cdf[end as usize - 1],
            children: [first, second],
            triangles: 0..end,
            rho_max,
            parent: u32::MAX,
        };
        out.root = NodeRef::cluster(0);
        Some(out)
    }

    /// Appends the subtree over triangles `tris` below `parent` (cluster index, child slot)
    /// and returns its root and bounding box.
    fn grow(
        &mut self,
        mesh: &ElementMesh,
        rho_lum: &[f64],
        tris: &[u32],
        parent: Option<(usize, usize)>,
    ) -> (NodeRef, Aabb) {
        let boxes: Vec<Aabb> = tris
            .iter()
            .map(|&t| {
                let c = mesh.corners(mesh.roots[t as usize]).map(|p| p.as_vec3());
                let min = c[0].min(c[1]).min(c[2]);
                let max = c[0].max(c[1]).max(c[2]);
                Aabb::new(Vec3A::from(min), Vec3A::from(max))
            })
            .collect();
        if tris.len() == 1 {
            self.push_triangle(mesh, tris[0]);
            if let Some((p, k)) = parent {
                self.triangle_parent[tris[0] as usize] = p as u32;
                self.nodes[p].children[k] = NodeRef::surface(mesh.roots[tris[0] as usize]);
            }
            return (NodeRef::surface(mesh.roots[tris[0] as usize]), boxes[0]);
        }
        let params = BvhBuildParams {
            max_prims_per_leaf: 1,
            ..BvhBuildParams::medium_build()
        };
        // Copies of one box (coincident triangles) are built as one and expanded into a
        // balanced subtree: PLOC alone chains them, one level per copy.
        let bvh = build_coincident(&boxes, |boxes| {
            build_bvh2(boxes, params, &mut Duration::default())
        });
        // Depth-first, children before parents are finished: an explicit stack of
        // (bvh node, cluster slot) so deep trees cannot overflow the call stack.
        enum Step {
            Enter(u32, Option<(usize, usize)>),
            Leave(usize, u32),
        }
        let mut stack = vec![Step::Enter(0, parent)];
        let mut root = None;
        while let Some(step) = stack.pop() {
            match step {
                Step::Enter(b, parent) => {
                    let node = &bvh.nodes[b as usize];
                    let r = if node.prim_count > 0 {
                        debug_assert_eq!(node.prim_count, 1, "one triangle per leaf");
                        let t = tris[bvh.primitive_indices[node.first_index as usize] as usize];
                        self.push_triangle(mesh, t);
                        if let Some((p, _)) = parent {
                            self.triangle_parent[t as usize] = p as u32;
                        }
                        NodeRef::surface(mesh.roots[t as usize])
                    } else {
                        let c = self.nodes.len();
                        let start = self.triangles.len() as u32;
                        self.nodes.push(Cluster {
                            center: DVec3::ZERO,
                            radius: 0.0,
                            area: 0.0,
                            children: [NodeRef::surface(0); 2],
                            triangles: start..start,
                            rho_max: 0.0,
                            parent: parent.map_or(u32::MAX, |(p, _)| p as u32),
                        });
                        stack.push(Step::Leave(c, node.first_index));
                        stack.push(Step::Enter(node.first_index + 1, Some((c, 1))));
                        stack.push(Step::Enter(node.first_index, Some((c, 0))));
                        NodeRef::cluster(c as u32)
                    };
                    if b == 0 {
                        root = Some(r);
                    }
                    if let Some((p, k)) = parent {
                        self.nodes[p].children[k] = r;
                    }
                }
                Step::Leave(c, first) => {
                    let end = self.triangles.len() as u32;
                    let range = self.nodes[c].triangles.start..end;
                    let (l, r) = (&bvh.nodes[first as usize], &bvh.nodes[first as usize + 1]);
                    let min = l.aabb.min.min(r.aabb.min).as_dvec3();
                    let max = l.aabb.max.max(r.aabb.max).as_dvec3();
                    let lo = if range.start == 0 {
                        0.0
                    } else {
                        self.area_cdf[range.start as usize - 1]
                    };
                    let area = self.area_cdf[end as usize - 1] - lo;
                    let rho_max = self.triangles[range.start as usize..end as usize]
                        .iter()
                        .map(|&t| rho_lum[t as usize])
                        .fold(0.0, f64::max);
                    let cl = &mut self.nodes[c];
                    cl.center = (min + max) * 0.5;
                    cl.radius = (max - min).length() * 0.5;
                    cl.area = area;
                    cl.triangles = range;
                    cl.rho_max = rho_max;
                }
            }
        }
        (root.expect("the tree has a root"), bvh.nodes[0].aabb)
    }

    fn push_triangle(&mut self, mesh: &ElementMesh, t: u32) {
        let last = self.area_cdf.last().copied().unwrap_or(0.0);
        self.triangles.push(t);
        self.area_cdf
            .push(last + f64::from(mesh.nodes[mesh.roots[t as usize] as usize].area));
    }

    /// The triangle (scene index) of cluster `c` that holds the area fraction `u` in [0, 1)
    /// of the cluster's area, and `u` rescaled to [0, 1) within that triangle.
    pub fn pick_triangle(&self, c: u32, u: f64) -> (u32, f64) {
        let range = &self.nodes[c as usize].triangles;
        let lo = if range.start == 0 {
            0.0
        } else {
            self.area_cdf[range.start as usize - 1]
        };
        let hi = self.area_cdf[range.end as usize - 1];
        let target = lo + u * (hi - lo);
        let cdf = &self.area_cdf[range.start as usize..range.end as usize];
        let k = cdf.partition_point(|&x| x <= target).min(cdf.len() - 1);
        let before = if k == 0 { lo } else { cdf[k - 1] };
        let width = (cdf[k] - before).max(f64::MIN_POSITIVE);
        (
            self.triangles[range.start as usize + k],
            ((target - before) / width).clamp(0.0, 1.0 - f64::EPSILON),
        )
    }
}
