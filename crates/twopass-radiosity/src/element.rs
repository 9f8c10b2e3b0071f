//! The radiosity mesh: every scene triangle taking part is the root of a binary tree of
//! longest-edge bisections (Rivara). Nodes down to the patch size are *patches* (the shooters);
//! the leaves are *elements* (the receivers, displayed). Vertices are shared within a surface,
//! and every bisection also splits the neighbour across the bisected edge (refining along the
//! longest-edge propagation path first), so the mesh stays conforming: no T-vertices, no cracks.

use std::collections::HashMap;

use glam::{DVec3, Vec2, Vec3};
use twopass_scene::Scene;

use crate::mesh_error::{InvalidMesh, MeshPart};

/// A mesh vertex: where radiosity is computed and stored.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vertex {
    /// Position, scene units.
    pub position: Vec3,
    /// Unit normal the vertex receives with (the shading normal of smooth surfaces).
    pub normal: Vec3,
    /// A scene triangle the vertex lies on (for offsetting rays that leave it).
    pub triangle: u32,
    /// The scene object it belongs to.
    pub object: u32,
}

/// A node of a bisection tree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Node {
    /// Vertex indices, counter-clockwise seen from the front.
    pub vertices: [u32; 3],
    /// Barycentric coordinates (b1, b2) of the vertices in the scene triangle.
    pub uv: [Vec2; 3],
    /// The two halves, or `None` for a leaf (an element).
    pub children: Option<[u32; 2]>,
    /// The scene triangle this node subdivides.
    pub scene_triangle: u32,
    /// The patch this node belongs to (itself or an ancestor); `u32::MAX` above patch level.
    pub patch: u32,
    /// Area, scene units squared.
    pub area: f32,
}

/// Key of a scene vertex in the radiosity mesh: its position index plus which normal it
/// receives with, so creases split vertices and smooth or coplanar surfaces share them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum VertexKey {
    Smooth(u32, u32),
    Flat(u32, [i32; 3]),
}

/// The patch/element hierarchy over the participating scene triangles.
#[derive(Debug, Clone)]
pub struct ElementMesh {
    /// All vertices.
    pub vertices: Vec<Vertex>,
    /// All tree nodes; roots first, in scene-triangle order.
    pub nodes: Vec<Node>,
    /// Root node of each scene triangle, or `u32::MAX` when it does not take part.
    pub roots: Vec<u32>,
    /// Patch nodes, indexed by patch id.
    pub patches: Vec<u32>,
    midpoints: HashMap<(u32, u32), u32>,
    /// Leaves touching each undirected edge, keyed by the edge's end positions (two leaves on
    /// a manifold surface). Keyed by position, not vertex id, so that the two sides of a
    /// crease, which have vertices of their own, are still refined together: no T-vertex
    /// anywhere, no crack in an exported mesh.
    edge_leaves: HashMap<PositionEdge, Vec<u32>>,
}

/// An undirected edge between two positions, by their bits.
type PositionEdge = ([u32; 3], [u32; 3]);

fn edge(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl ElementMesh {
    /// The surface nodes from `n`'s scene triangle's root down to `n`, both included.
    pub fn path_to(&self, n: u32) -> Vec<u32> {
        let t = self.nodes[n as usize].scene_triangle;
        let uv = self.nodes[n as usize].uv;
        let centre = (uv[0] + uv[1] + uv[2]) / 3.0;
        let mut path = Vec::new();
        let mut at = self.roots[t as usize];
        loop {
            path.push(at);
            if at == n {
                break;
            }
            let Some([c0, c1]) = self.nodes[at as usize].children else {
                break;
            };
            // The child whose side of the split edge holds `n`'s centroid.
            let [a, m, c] = self.nodes[c0 as usize].uv;
            let side = |q: Vec2| (c - m).perp_dot(q - m);
            at = if side(centre) * side(a) >= 0.0 {
                c0
            } else {
                c1
            };
        }
        path
    }

    /// One root per participating scene triangle (`takes_part[object]`).
    pub fn new(scene: &Scene, takes_part: &[bool]) -> Self {
        let m = &scene.mesh;
        let mut keys: HashMap<VertexKey, u32> = HashMap::new();
        let mut mesh = Self {
            vertices: Vec::new(),
            nodes: Vec::new(),
            roots: vec![u32::MAX; m.triangle_count()],
            patches: Vec::new(),
            midpoints: HashMap::new(),
            edge_leaves: HashMap::new(),
        };
        for (t, tri) in m.triangles().enumerate() {
            let object = m.object_of(t as u32);
            if !takes_part[object as usize] {
                continue;
            }
            let gn = m.geometric_normal(t as u32);
            let ni = m.normal_indices(t as u32);
            // A corner is smooth when its shading normal is shared with other triangles.
            let smooth = ni.iter().any(|&n| m.normal(n) != gn) || ni[0] != ni[1];
            let vertices = [0, 1, 2].map(|k| {
                let key = if smooth {
                    VertexKey::Smooth(tri[k], ni[k])
                } else {
                    VertexKey::Flat(tri[k], (gn * 1e4).round().as_ivec3().to_array())
                };
                *keys.entry(key).or_insert_with(|| {
                    mesh.vertices.push(Vertex {
                        position: m.position(tri[k]),
                        normal: if smooth { m.normal(ni[k]) } else { gn },
                        triangle: t as u32,
                        object,
                    });
                    (mesh.vertices.len() - 1) as u32
                })
            });
            let id = mesh.nodes.len() as u32;
            mesh.nodes.push(Node {
                vertices,
                uv: [Vec2::ZERO, Vec2::X, Vec2::Y],
                children: None,
                scene_triangle: t as u32,
                patch: u32::MAX,
                area: m.area(t as u32),
            });
            mesh.roots[t] = id;
            mesh.link(id);
        }
        mesh
    }

    /// Rebuilds a mesh from its public parts (as stored in a bake file), checking everything a
    /// lookup or a further refinement relies on: indices in range, finite positions, normals
    /// and areas, non-degenerate barycentric corners, one tree per participating scene
    /// triangle (`roots.len()` is the scene's triangle count) whose children come after their
    /// parent and split it at a shared midpoint, and patches that point back at themselves.
    /// The private edge maps are rebuilt from the leaves and the bisections.
    pub fn from_parts(
        vertices: Vec<Vertex>,
        nodes: Vec<Node>,
        roots: Vec<u32>,
        patches: Vec<u32>,
    ) -> Result<Self, InvalidMesh> {
        let bad = |part, index: usize, problem| Err(InvalidMesh::new(part, index, problem));
        let (n_v, n_n, n_t) = (vertices.len(), nodes.len(), roots.len());
        for (i, v) in vertices.iter().enumerate() {
            if !(v.position.is_finite() && v.normal.is_finite()) {
                return bad(MeshPart::Vertex, i, "position or normal is not finite");
            }
            if v.triangle as usize >= n_t {
                return bad(MeshPart::Vertex, i, "scene triangle out of range");
            }
        }
        let mut parent = vec![u32::MAX; n_n];
        let mut midpoints = HashMap::new();
        for (i, node) in nodes.iter().enumerate() {
            if node.vertices.iter().any(|&v| v as usize >= n_v) {
                return bad(MeshPart::Node, i, "vertex index out of range");
            }
            if node.scene_triangle as usize >= n_t {
                return bad(MeshPart::Node, i, "scene triangle out of range");
            }
            if node.patch != u32::MAX && node.patch as usize >= patches.len() {
                return bad(MeshPart::Node, i, "patch index out of range");
            }
            if !(node.area.is_finite() && node.area >= 0.0) {
                return bad(MeshPart::Node, i, "area is negative or not finite");
            }
            let [a, b, c] = node.uv.map(Vec2::as_dvec2);
            let det = (b - a).perp_dot(c - a);
            if !(det.is_finite() && det > 0.0) {
                return bad(MeshPart::Node, i, "barycentric corners are degenerate");
            }
            let Some([c0, c1]) = node.children else {
                continue;
            };
            // Children are always appended after their parent: this also rules out cycles.
            if c0 as usize >= n_n || c1 as usize >= n_n || c0 as usize <= i || c1 as usize <= i {
                return bad(
                    MeshPart::Node,
                    i,
                    "child index out of range or not after parent",
                );
            }
            for ch in [c0, c1] {
                if parent[ch as usize] != u32::MAX || c0 == c1 {
                    return bad(MeshPart::Node, ch as usize, "node has two parents");
                }
                parent[ch as usize] = i as u32;
                if nodes[ch as usize].scene_triangle != node.scene_triangle {
                    return bad(
                        MeshPart::Node,
                        ch as usize,
                        "child of another scene triangle",
                    );
                }
            }
            // A bisection [a, b, c] -> [a, m, c], [m, b, c].
            let (h0, h1) = (nodes[c0 as usize].vertices, nodes[c1 as usize].vertices);
            if h0[1] != h1[0] || h0[2] != h1[2] {
                return bad(
                    MeshPart::Node,
                    i,
                    "children are not the halves of a bisection",
                );
            }
            midpoints.insert(edge(h0[0], h1[1]), h0[1]);
        }
        for (t, &r) in roots.iter().enumerate() {
            if r == u32::MAX {
                continue;
            }
            if r as usize >= n_n
                || parent[r as usize] != u32::MAX
                || nodes[r as usize].scene_triangle as usize != t
            {
                return bad(MeshPart::Root, t, "not the parentless root of its triangle");
            }
            parent[r as usize] = r;
        }
        if let Some(orphan) = parent.iter().position(|&p| p == u32::MAX) {
            return bad(MeshPart::Node, orphan, "node belongs to no tree");
        }
        for (p, &n) in patches.iter().enumerate() {
            if n as usize >= n_n || nodes[n as usize].patch as usize != p {
                return bad(
                    MeshPart::Patch,
                    p,
                    "patch node out of range or of another patch",
                );
            }
        }
        let mut mesh = Self {
            vertices,
            nodes,
            roots,
            patches,
            midpoints,
            edge_leaves: HashMap::new(),
        };
        let leaves: Vec<u32> = mesh.leaves().collect();
        for n in leaves {
            mesh.link(n);
        }
        Ok(mesh)
    }

    /// The position edge between vertices `a` and `b`.
    fn position_edge(&self, a: u32, b: u32) -> PositionEdge {
        let bits = |v: u32| {
            self.vertices[v as usize]
                .position
                .to_array()
                .map(f32::to_bits)
        };
        let (pa, pb) = (bits(a), bits(b));
        (pa.min(pb), pa.max(pb))
    }

    fn link(&mut self, n: u32) {
        let v = self.nodes[n as usize].vertices;
        for k in 0..3 {
            let e = self.position_edge(v[k], v[(k + 1) % 3]);
            self.edge_leaves.entry(e).or_default().push(n);
        }
    }

    fn unlink(&mut self, n: u32) {
        let v = self.nodes[n as usize].vertices;
        for k in 0..3 {
            let e = self.position_edge(v[k], v[(k + 1) % 3]);
            if let Some(list) = self.edge_leaves.get_mut(&e) {
                list.retain(|&x| x != n);
                if list.is_empty() {
                    self.edge_leaves.remove(&e);
                }
            }
        }
    }

    /// Index k of the node's longest edge (vertices k, k+1), ties broken by the positions so
    /// that neighbours (on both sides of a crease too) agree.
    fn longest_edge(&self, n: u32) -> usize {
        let v = self.nodes[n as usize].vertices;
        let len = |k: usize| {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            let d = self.vertices[a as usize].position.as_dvec3()
                - self.vertices[b as usize].position.as_dvec3();
            (d.length_squared(), self.position_edge(a, b))
        };
        (0..3)
            .max_by(|&i, &j| len(i).partial_cmp(&len(j)).expect("finite lengths"))
            .expect("three edges")
    }

    /// Length of the node's longest edge, scene units.
    pub fn longest_edge_length(&self, n: u32) -> f32 {
        let v = self.nodes[n as usize].vertices;
        let k = self.longest_edge(n);
        (self.vertices[v[k] as usize].position - self.vertices[v[(k + 1) % 3] as usize].position)
            .length()
    }

    fn midpoint(&mut self, a: u32, b: u32, triangle: u32) -> u32 {
        if let Some(&m) = self.midpoints.get(&edge(a, b)) {
            return m;
        }
        let (va, vb) = (self.vertices[a as usize], self.vertices[b as usize]);
        // The midpoint of a chord of the scene triangle lies in its plane; computed from the
        // ends alone, it is the same to the bit on both sides of a crease.
        let position = ((va.position.as_dvec3() + vb.position.as_dvec3()) * 0.5).as_vec3();
        let normal = (va.normal + vb.normal).try_normalize().unwrap_or(va.normal);
        self.vertices.push(Vertex {
            position,
            normal,
            triangle,
            object: va.object,
        });
        let m = (self.vertices.len() - 1) as u32;
        self.midpoints.insert(edge(a, b), m);
        m
    }

    /// Bisects leaf `n` across its longest edge. Does not keep conformity by itself.
    fn bisect(&mut self, n: u32) {
        let node = self.nodes[n as usize];
        let k = self.longest_edge(n);
        let (i, j, l) = (k, (k + 1) % 3, (k + 2) % 3);
        let (a, b, c) = (node.vertices[i], node.vertices[j], node.vertices[l]);
        let m = self.midpoint(a, b, node.scene_triangle);
        let uvm = (node.uv[i] + node.uv[j]) * 0.5;
        let area = node.area * 0.5;
        let first = self.nodes.len() as u32;
        self.unlink(n);
        for (vs, uv) in [
            ([a, m, c], [node.uv[i], uvm, node.uv[l]]),
            ([m, b, c], [uvm, node.uv[j], node.uv[l]]),
        ] {
            self.nodes.push(Node {
                vertices: vs,
                uv,
                children: None,
                area,
                ..node
            });
            let id = (self.nodes.len() - 1) as u32;
            self.link(id);
        }
        self.nodes[n as usize].children = Some([first, first + 1]);
    }

    /// Bisects leaf `n` and keeps the mesh conforming: every leaf across the bisected edge is
    /// first refined until that edge is its own longest, then split at the same midpoint.
    /// Returns how many leaves were split.
    pub fn refine(&mut self, n: u32) -> usize {
        let mut splits = 0;
        let mut stack = vec![n];
        while let Some(&t) = stack.last() {
            if self.nodes[t as usize].children.is_some() {
                stack.pop();
                continue;
            }
            let v = self.nodes[t as usize].vertices;
            let k = self.longest_edge(t);
            let e = self.position_edge(v[k], v[(k + 1) % 3]);
            let neighbours: Vec<u32> = self.edge_leaves.get(&e).map_or_else(Vec::new, |l| {
                l.iter().copied().filter(|&x| x != t).collect()
            });
            // A neighbour whose longest edge is another one must be split first (LEPP).
            if let Some(&blocker) = neighbours.iter().find(|&&x| {
                let w = self.nodes[x as usize].vertices;
                let kk = self.longest_edge(x);
                self.position_edge(w[kk], w[(kk + 1) % 3]) != e
            }) {
                stack.push(blocker);
                continue;
            }
            self.bisect(t);
            splits += 1;
            for x in neighbours {
                self.bisect(x);
                splits += 1;
            }
            stack.pop();
        }
        splits
    }

    /// Refines (conformingly) until every leaf's longest edge is at most `size`.
    pub fn refine_to(&mut self, size: f32) {
        loop {
            let coarse: Vec<u32> = self
                .leaves()
                .filter(|&n| self.longest_edge_length(n) > size)
                .collect();
            if coarse.is_empty() {
                return;
            }
            for n in coarse {
                self.refine(n);
            }
        }
    }

    /// Makes every current leaf a patch (in leaf order).
    pub fn mark_patches(&mut self) {
        let leaves: Vec<u32> = self.leaves().collect();
        for n in leaves {
            let id = self.patches.len() as u32;
            self.patches.push(n);
            self.nodes[n as usize].patch = id;
        }
    }

    /// All leaves (elements), in node order.
    pub fn leaves(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.nodes.len() as u32).filter(|&n| self.nodes[n as usize].children.is_none())
    }

    /// The leaf of scene triangle `t`'s tree containing barycentrics (b1, b2), and the point's
    /// barycentric weights in that leaf. `None` when the triangle does not take part.
    pub fn locate(&self, t: u32, b1: f32, b2: f32) -> Option<(u32, [f32; 3])> {
        let n = *self.roots.get(t as usize)?;
        if n == u32::MAX {
            return None;
        }
        Some(self.locate_from(n, b1, b2))
    }

    /// [`ElementMesh::locate`] starting at node `n` of the tree (the point must lie in it):
    /// a leaf found before a refinement is an ancestor of the leaf that holds the point after.
    pub fn locate_from(&self, mut n: u32, b1: f32, b2: f32) -> (u32, [f32; 3]) {
        let p = Vec2::new(b1, b2);
        loop {
            let node = &self.nodes[n as usize];
            match node.children {
                None => return (n, barycentric_2d(node.uv, p)),
                Some([c0, c1]) => {
                    // The halves (a, m, c) and (m, b, c) are split by the segment m-c: the point
                    // belongs to the first when it lies on a's side of that line.
                    let [a, m, c] = self.nodes[c0 as usize].uv;
                    let side = |q: Vec2| (c - m).perp_dot(q - m);
                    n = if side(p) * side(a) >= 0.0 { c0 } else { c1 };
                }
            }
        }
    }

    /// Area-weighted unit normal and centroid of a node.
    pub fn centroid(&self, n: u32) -> Vec3 {
        let v = self.nodes[n as usize]
            .vertices
            .map(|i| self.vertices[i as usize].position.as_dvec3());
        ((v[0] + v[1] + v[2]) / 3.0).as_vec3()
    }

    /// The node's corner positions in f64.
    pub fn corners(&self, n: u32) -> [DVec3; 3] {
        self.nodes[n as usize]
            .vertices
            .map(|i| self.vertices[i as usize].position.as_dvec3())
    }
}

/// The element trees laid out for point location, which a finished solution does once per
/// camera sample: each level of the descent reads one 32-byte split record instead of two mesh
/// nodes. Finds exactly the leaf [`ElementMesh::locate`] finds (the same arithmetic on the
/// same values), for the mesh it was built from.
#[derive(Debug, Clone, Default)]
pub struct Locator {
    /// Root node of each scene triangle, or `u32::MAX` when it does not take part.
    roots: Vec<u32>,
    /// Per node: how its point set splits.
    splits: Vec<Split>,
}

/// How an inner node splits: its halves `(a, m, c)` and `(m, b, c)` are divided by the
/// segment from `m` along `d = c - m`; a point on `a`'s side (`side_a`, the sign that
/// matters) is in the first. A leaf has `children` `[u32::MAX; 2]`.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(32))]
struct Split {
    children: [u32; 2],
    m: Vec2,
    d: Vec2,
    side_a: f32,
}

impl Locator {
    /// The locator of `mesh` as it is now (rebuild after a refinement).
    pub fn new(mesh: &ElementMesh) -> Self {
        let splits = mesh
            .nodes
            .iter()
            .map(|node| match node.children {
                None => Split {
                    children: [u32::MAX; 2],
                    m: Vec2::ZERO,
                    d: Vec2::ZERO,
                    side_a: 0.0,
                },
                Some([c0, c1]) => {
                    let [a, m, c] = mesh.nodes[c0 as usize].uv;
                    let d = c - m;
                    Split {
                        children: [c0, c1],
                        m,
                        d,
                        side_a: d.perp_dot(a - m),
                    }
                }
            })
            .collect();
        Self {
            roots: mesh.roots.clone(),
            splits,
        }
    }

    /// [`ElementMesh::locate`] on `mesh`, the mesh this was built from.
    pub fn locate(&self, mesh: &ElementMesh, t: u32, b1: f32, b2: f32) -> Option<(u32, [f32; 3])> {
        let mut n = *self.roots.get(t as usize)?;
        if n == u32::MAX {
            return None;
        }
        let p = Vec2::new(b1, b2);
        loop {
            let s = &self.splits[n as usize];
            if s.children[0] == u32::MAX {
                return Some((n, barycentric_2d(mesh.nodes[n as usize].uv, p)));
            }
            let side = s.d.perp_dot(p - s.m);
            n = if side * s.side_a >= 0.0 {
                s.children[0]
            } else {
                s.children[1]
            };
        }
    }
}

/// Barycentric weights of `p` in the 2-D triangle `t`.
pub(crate) fn barycentric_2d(t: [Vec2; 3], p: Vec2) -> [f32; 3] {
    let (a, b, c) = (t[0].as_dvec2(), t[1].as_dvec2(), t[2].as_dvec2());
    let p = p.as_dvec2();
    let det = (b - a).perp_dot(c - a);
    let w1 = (p - a).perp_dot(c - a) / det;
    let w2 = (b - a).perp_dot(p - a) / det;
    [(1.0 - w1 - w2) as f32, w1 as f32, w2 as f32]
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn quad_scene() -> Scene {
        let text = "version = 1\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov_y = 40\n\
                    [[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
                    [[object]]\nname = \"q\"\nmaterial = \"w\"\nemission = 1\n\
                    shape = { type = \"quad\", origin = [0, 0, 0], edge_u = [2, 0, 0], edge_v = [0, 1, 0] }\n";
        twopass_scene::load_toml(text, Path::new("q.toml"))
            .unwrap()
            .0
    }

    /// Every leaf edge is shared by two leaves or lies on the outer boundary, and no vertex
    /// lies inside another leaf's edge (no T-vertices).
    fn assert_conforming(mesh: &ElementMesh) {
        let leaves: Vec<u32> = mesh.leaves().collect();
        for &n in &leaves {
            let v = mesh.nodes[n as usize].vertices;
            for k in 0..3 {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                let (pa, pb) = (
                    mesh.vertices[a as usize].position,
                    mesh.vertices[b as usize].position,
                );
                for (i, q) in mesh.vertices.iter().enumerate() {
                    if i as u32 == a || i as u32 == b {
                        continue;
                    }
                    let t = (q.position - pa).dot(pb - pa) / (pb - pa).length_squared();
                    let off = (pa + (pb - pa) * t - q.position).length();
                    assert!(
                        !(t > 1e-4 && t < 1.0 - 1e-4 && off < 1e-6),
                        "vertex {i} hangs on edge ({a}, {b})"
                    );
                }
            }
        }
    }

    #[test]
    fn refinement_stays_conforming_and_keeps_area() {
        let scene = quad_scene();
        let mut mesh = ElementMesh::new(&scene, &[true]);
        assert_eq!(mesh.vertices.len(), 4, "the quad's diagonal is shared");
        mesh.refine_to(0.5);
        mesh.mark_patches();
        // Refine one corner deeply: propagation must keep neighbours conforming.
        for _ in 0..6 {
            let corner = mesh.leaves().min_by(|&a, &b| {
                mesh.centroid(a)
                    .length()
                    .partial_cmp(&mesh.centroid(b).length())
                    .unwrap()
            });
            mesh.refine(corner.unwrap());
        }
        assert_conforming(&mesh);
        let area: f32 = mesh.leaves().map(|n| mesh.nodes[n as usize].area).sum();
        assert!((area - 2.0).abs() < 1e-5);
        assert!(
            mesh.leaves()
                .all(|n| mesh.nodes[n as usize].patch != u32::MAX)
        );
    }

    #[test]
    fn locator_finds_what_the_mesh_finds() {
        let scene = quad_scene();
        let mut mesh = ElementMesh::new(&scene, &[true]);
        mesh.refine_to(0.05);
        // Refine unevenly too, so that trees of many depths are walked.
        let leaves: Vec<u32> = mesh.leaves().step_by(7).collect();
        for l in leaves {
            mesh.refine(l);
        }
        let locator = Locator::new(&mesh);
        let mut hits = std::collections::HashSet::new();
        for t in 0..2 {
            for i in 0..400u32 {
                for j in 0..(400 - i) {
                    let (b1, b2) = (i as f32 / 400.0, j as f32 / 400.0);
                    let found = locator.locate(&mesh, t, b1, b2);
                    assert_eq!(found, mesh.locate(t, b1, b2), "{t}: ({b1}, {b2})");
                    hits.insert(found.unwrap().0);
                }
            }
        }
        // The grids on the quad's two triangles reach most elements: most of the trees are
        // walked.
        let leaves = mesh.leaves().count();
        assert!(hits.len() * 2 > leaves, "{} of {leaves}", hits.len());
        assert_eq!(locator.locate(&mesh, 99, 0.1, 0.1), None);
    }

    #[test]
    fn locate_finds_the_leaf_holding_a_point() {
        let scene = quad_scene();
        let mut mesh = ElementMesh::new(&scene, &[true]);
        mesh.refine_to(0.3);
        for (b1, b2) in [(0.1f32, 0.2f32), (0.7, 0.25), (0.0, 0.0), (0.33, 0.33)] {
            let (leaf, w) = mesh.locate(0, b1, b2).unwrap();
            let p = scene
                .mesh
                .surface_point(0, [1.0 - b1 - b2, b1, b2])
                .position;
            let v = mesh.nodes[leaf as usize]
                .vertices
                .map(|i| mesh.vertices[i as usize].position);
            let q = v[0] * w[0] + v[1] * w[1] + v[2] * w[2];
            assert!(w.iter().all(|&x| x >= -1e-5), "{w:?}");
            assert!((p - q).length() < 1e-5, "{p} vs {q}");
        }
    }
}
