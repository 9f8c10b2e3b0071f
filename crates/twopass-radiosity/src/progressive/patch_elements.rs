//! Every patch's elements in one flat list ([`PatchElements`]), what each shot reads.

use crate::element::ElementMesh;

/// Every patch's elements (leaves) in one flat list, patch by patch in the mesh's leaf order:
/// patch `p` owns entries `start[p]..start[p + 1]`. Each shot reads every element, so their
/// vertices and areas sit here side by side rather than in the mesh's nodes.
#[derive(Default)]
pub(super) struct PatchElements {
    pub(super) start: Vec<usize>,
    pub(super) leaf: Vec<u32>,
    pub(super) vertices: Vec<[u32; 3]>,
    /// Scene units squared.
    pub(super) area: Vec<f64>,
    /// Per mesh vertex: a patch on the vertex's own scene triangle whose elements use it (so
    /// the vertex lies on that patch), `u32::MAX` for none. Shaft culling between patches
    /// clears a vertex through it.
    pub(super) vertex_patch: Vec<u32>,
}

impl PatchElements {
    /// Groups the mesh's leaves by patch (a stable counting sort: within a patch, the order of
    /// [`ElementMesh::leaves`]).
    pub(super) fn new(mesh: &ElementMesh) -> Self {
        let leaves: Vec<u32> = mesh.leaves().collect();
        let mut start = vec![0usize; mesh.patches.len() + 1];
        for &l in &leaves {
            start[mesh.nodes[l as usize].patch as usize + 1] += 1;
        }
        for p in 0..mesh.patches.len() {
            start[p + 1] += start[p];
        }
        let mut next = start.clone();
        let mut leaf = vec![0u32; leaves.len()];
        for &l in &leaves {
            let p = mesh.nodes[l as usize].patch as usize;
            leaf[next[p]] = l;
            next[p] += 1;
        }
        let vertices = leaf
            .iter()
            .map(|&l| mesh.nodes[l as usize].vertices)
            .collect();
        let area = leaf
            .iter()
            .map(|&l| f64::from(mesh.nodes[l as usize].area))
            .collect();
        let mut vertex_patch = vec![u32::MAX; mesh.vertices.len()];
        for (p, &node) in mesh.patches.iter().enumerate() {
            let triangle = mesh.nodes[node as usize].scene_triangle;
            for &l in &leaf[start[p]..start[p + 1]] {
                for v in mesh.nodes[l as usize].vertices {
                    if mesh.vertices[v as usize].triangle == triangle {
                        vertex_patch[v as usize] = p as u32;
                    }
                }
            }
        }
        Self {
            start,
            leaf,
            vertices,
            area,
            vertex_patch,
        }
    }

    /// Entries of patch `p`.
    pub(super) fn range(&self, p: usize) -> std::ops::Range<usize> {
        self.start[p]..self.start[p + 1]
    }

    /// The leaves of patch `p`.
    pub(super) fn leaves(&self, p: usize) -> &[u32] {
        &self.leaf[self.range(p)]
    }
}
