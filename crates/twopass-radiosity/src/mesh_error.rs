//! Why the parts of an element mesh do not fit together ([`ElementMesh::from_parts`] checks a
//! mesh built outside the solver, such as one read from a bake file).
//!
//! [`ElementMesh::from_parts`]: crate::element::ElementMesh::from_parts

use std::fmt;

/// Which part of an element mesh failed validation (see [`InvalidMesh`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum MeshPart {
    /// An entry of `ElementMesh::vertices`.
    Vertex,
    /// An entry of `ElementMesh::nodes`.
    Node,
    /// An entry of `ElementMesh::roots` (indexed by scene triangle).
    Root,
    /// An entry of `ElementMesh::patches` (indexed by patch id).
    Patch,
}

/// An element mesh whose parts do not fit together
/// ([`ElementMesh::from_parts`](crate::element::ElementMesh::from_parts)).
#[derive(Debug, Clone, PartialEq, Eq)]
#[non_exhaustive]
pub struct InvalidMesh {
    /// Which array holds the offending entry.
    pub part: MeshPart,
    /// Its index in that array.
    pub index: usize,
    /// What is wrong with it.
    pub problem: &'static str,
}

impl InvalidMesh {
    /// An invalid entry `index` of `part`.
    pub fn new(part: MeshPart, index: usize, problem: &'static str) -> Self {
        Self {
            part,
            index,
            problem,
        }
    }
}

impl fmt::Display for InvalidMesh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let part = match self.part {
            MeshPart::Vertex => "vertex",
            MeshPart::Node => "node",
            MeshPart::Root => "root of scene triangle",
            MeshPart::Patch => "patch",
        };
        write!(f, "element mesh {part} {}: {}", self.index, self.problem)
    }
}

impl std::error::Error for InvalidMesh {}
