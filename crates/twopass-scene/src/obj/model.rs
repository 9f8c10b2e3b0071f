//! What reading an OBJ gives: its groups as shapes, its MTL materials and where each was
//! defined, and what the statement scan learns on the way.

use std::collections::HashMap;
use std::path::PathBuf;

use crate::shape::ShapeMesh;

/// One OBJ group (tobj model) as a shape, with its MTL material index.
pub(crate) struct ObjModel {
    pub name: String,
    pub mesh: ShapeMesh,
    pub material: Option<usize>,
    /// The `usemtl` statement in force for this group (name, line), if any.
    pub usemtl: Option<(String, usize)>,
    /// The line of the group's first face, when the scan and tobj agree on the groups.
    pub first_face: Option<usize>,
}

/// Where an MTL material was defined: its library and the lines of its statements.
#[derive(Debug, Clone)]
pub(crate) struct MtlOrigin {
    pub path: PathBuf,
    /// Line of `newmtl`.
    pub line: usize,
    /// Line of each key (`Kd`, `Ke`, ...) within the material.
    pub keys: HashMap<String, usize>,
}

impl MtlOrigin {
    /// The line of `key` in this material, or of its `newmtl`.
    pub fn line_of(&self, key: &str) -> usize {
        self.keys.get(key).copied().unwrap_or(self.line)
    }
}

/// A loaded OBJ: its groups and its MTL materials (or why they failed).
pub(crate) struct ObjFile {
    pub models: Vec<ObjModel>,
    pub materials: Result<Vec<tobj::Material>, tobj::LoadError>,
    /// Where each of `materials` was defined (same order).
    pub origins: Vec<MtlOrigin>,
    /// The `mtllib` files it names, resolved against its folder.
    pub mtllibs: Vec<PathBuf>,
    /// The first library that could not be opened, if any.
    pub missing_mtl: Option<PathBuf>,
    /// The 1-based line of the first `v` statement with a coordinate beyond
    /// [`crate::MAX_COORDINATE`], if any: where a refusal of the positions points.
    pub range_line: Option<usize>,
}

/// What the statement scan learned about one tobj model.
#[derive(Debug, Default, Clone)]
pub(super) struct ScannedModel {
    /// Triangles its faces become (a polygon of n corners gives n - 2).
    pub(super) triangles: usize,
    /// Whether every corner of every face names a normal.
    pub(super) all_normals: bool,
    /// Whether every corner of every face names a texture coordinate.
    pub(super) all_texcoords: bool,
    pub(super) usemtl: Option<(String, usize)>,
    /// The line of its first face (0 before one is met).
    pub(super) first_face: usize,
    /// The `v` statements its faces use (0-based, file order), in the order of first use:
    /// tobj's order of the group's positions (it numbers them as the faces' corners first name
    /// them, a triangulated polygon's corners in their written order).
    pub(super) vertices: Vec<u32>,
    /// Whether each `v` statement is in [`ScannedModel::vertices`] already.
    pub(super) used: std::collections::HashSet<u32>,
}

/// One MTL library, read and checked by us, parsed by tobj.
pub(super) struct MtlLib {
    pub(super) written: String,
    pub(super) result: tobj::MTLLoadResult,
    pub(super) origins: Vec<MtlOrigin>,
}
