//! The scene layer of twopass: the scene file format (TOML, with OBJ/MTL meshes through tobj),
//! validation once at load, the runtime [`Scene`] (indexed meshes, materials, objects,
//! emitters, lamps ([`lamp`]: point, spot and directional lights), the sky ([`sky`]: uniform
//! or Preetham daylight with a finite sun, portals), camera) and ray queries over an 8-wide BVH (obvhs builds a binary tree, collapsed
//! into 8-wide nodes with four-triangle leaves).
//!
//! After [`load`] returns `Ok`, every position and normal is finite, every triangle has a
//! non-zero area, every material parameter is in range and every emission is finite and
//! non-negative: the passes downstream cannot fail on the scene's data.
//!
//! Units: positions in the scene's own units, which the scene file states ([`Unit`], the
//! Cornell box is in millimetres; exporters to metre-based formats convert with it), emitted
//! radiance in W/(m^2 sr) per RGB channel with areas in scene units, angles in radians at
//! run time (degrees in files).
//!
//! ```no_run
//! let (scene, warnings) = twopass_scene::load("scenes/cornell-box.toml")?;
//! for w in &warnings {
//!     eprintln!("warning: {w}");
//! }
//! let ray = twopass_scene::Ray::new(scene.camera.position, scene.camera.forward);
//! if let Some(hit) = scene.intersect(&ray) {
//!     println!("hit object {} at distance {}", scene.objects[hit.object as usize].name, hit.t);
//! }
//! # Ok::<(), twopass_scene::SceneError>(())
//! ```

mod accel;
mod albedo;
mod camera;
pub mod description;
mod error;
mod gltf_source;
mod input;
pub mod lamp;
mod load;
mod mesh;
mod obj;
mod radiance;
mod scene;
pub mod shape;
pub mod sky;
pub mod targets;
pub mod texture;
mod transform;
mod unit;
pub mod workload;

pub use accel::{
    Accel, COHERENT_ANGLE, COHERENT_ORIGINS, INTERLEAVE_MIN_BYTES, Placement, Ray, SHAFT_TOLERANCE,
    SurfacePoint, TriangleHit, build_coincident,
};
pub use camera::{Camera, CameraProblem, CameraRays};
pub use error::{SceneError, Warning};
pub use gltf_source::{GltfOrigin, GltfSource};
pub use input::{
    MAX_GLTF_BYTES, MAX_MTL_BYTES, MAX_OBJ_BYTES, MAX_SCENE_BYTES, MAX_TEXTURE_BYTES, ReadPolicy,
    printable, read_bounded,
};
pub use lamp::{LUMINOUS_EFFICACY, Lamp, LampKind, LampLight, MAX_LAMP_INTENSITY, spot_falloff};
pub use load::{
    MAX_COORDINATE, MAX_EMITTED_POWER, MAX_PLACED_TRIANGLES, MAX_TRIANGLES, SMOOTH_ROUGHNESS,
    SPHERE_TOLERANCE, gltf_image_problem, load, load_toml, load_toml_with, load_with,
};
pub use mesh::Repeat;
pub use radiance::{DiffuseRadiance, RadianceEstimate, RadianceEstimator};
pub use scene::{Bounds, Emitter, Hit, Mesh, Object, Scene, SceneMaterial};
pub use sky::irradiance::SKY_GRID;
pub use sky::{
    Daylight, PORTAL_SHARE, Portal, SUN_DIAMETER_DEGREES, Sky, SkyKind, Sun, TURBIDITY_RANGE,
};
pub use targets::SpecularTargets;
pub use texture::{AlbedoTexture, MAX_TEXTURE_PIXELS, MAX_TEXTURE_SIDE, Texture};
pub use transform::Transform;
pub use unit::Unit;
