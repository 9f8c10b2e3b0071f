//! A glTF scene's own document and data, kept with the loaded [`Scene`](crate::Scene) so that
//! a bake can write the user's asset back: vocabulary that the scene and its glTF loader share.

/// Where a scene object loaded from a glTF comes from: its vertex `i` is vertex `i` of this
/// primitive, placed by this node.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GltfOrigin {
    /// Index of the node in the document's `nodes`.
    pub node: usize,
    /// Index of the mesh in the document's `meshes`.
    pub mesh: usize,
    /// Index of the primitive in the mesh's `primitives`.
    pub primitive: usize,
    /// Whether the node's world transform mirrors (the scene's triangles are wound the other
    /// way round than the primitive's, to keep their front side).
    pub flips: bool,
}

/// A glTF scene's own document and data, kept with the loaded [`Scene`](crate::Scene) so that a bake can
/// write the user's asset back with its lightmap, unchanged otherwise.
#[derive(Clone, Default)]
pub struct GltfSource {
    /// The document's JSON (a `.gltf` file, or a `.glb`'s JSON chunk).
    pub json: Vec<u8>,
    /// Each buffer's bytes in document order (a `.glb`'s binary chunk, a data URI decoded, an
    /// external file read).
    pub buffers: Vec<Vec<u8>>,
    /// Each image given by a URI (a data URI or a file): its bytes and MIME type; `None` for
    /// an image in a buffer view, or one that could not be read (a warning said so).
    pub images: Vec<Option<(Vec<u8>, String)>>,
    /// Per scene object, in [`Scene::objects`](crate::Scene::objects) order, where it comes from.
    pub origins: Vec<GltfOrigin>,
    /// The node in the document's `nodes` whose perspective camera is the scene's camera, or
    /// `None` when the scene is framed by the default camera (the document has none, or only
    /// orthographic ones).
    pub camera_node: Option<usize>,
}

impl std::fmt::Debug for GltfSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GltfSource")
            .field("json_bytes", &self.json.len())
            .field(
                "buffer_bytes",
                &self.buffers.iter().map(Vec::len).collect::<Vec<_>>(),
            )
            .field("images", &self.images.len())
            .field("origins", &self.origins)
            .field("camera_node", &self.camera_node)
            .finish()
    }
}
