//! Fingerprints of a scene: 64-bit FNV-1a hashes over its data (bit patterns, counts, indices),
//! never over formatted text, so they change exactly when the data does. A bake records the
//! geometry and lighting fingerprints and is refused for a scene whose fingerprints differ;
//! [`scene_fingerprint`] covers everything that changes a rendered image (the tradeoff sweep's
//! reference cache is keyed by it).

use glam::Vec3;
use twopass_brdf::{ComplexIor, FresnelModel, Lobe};
use twopass_composite::Image;
use twopass_scene::{LampKind, Scene};

/// Which scene fingerprint a bake file disagrees with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fingerprint {
    /// The triangles, positions and normals ([`geometry_fingerprint`]).
    Geometry,
    /// The objects' emission and diffuse reflectance ([`lighting_fingerprint`]).
    Lighting,
}

/// 64-bit FNV-1a: a stable, platform-independent hash for fingerprints (not for security).
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn u32(&mut self, x: u32) {
        self.bytes(&x.to_le_bytes());
    }
    fn u64(&mut self, x: u64) {
        self.bytes(&x.to_le_bytes());
    }
    fn f32(&mut self, x: f32) {
        self.u32(x.to_bits());
    }
    fn vec3(&mut self, v: Vec3) {
        for c in v.to_array() {
            self.f32(c);
        }
    }
    fn ior(&mut self, ior: &ComplexIor) {
        self.vec3(ior.n);
        self.vec3(ior.k);
    }
    /// A material's non-diffuse lobe: a tag per variant, then its parameters.
    fn lobe(&mut self, lobe: Option<&Lobe>) {
        match lobe {
            None => self.u32(0),
            Some(
                lobe @ (Lobe::Phong {
                    specular,
                    exponent,
                    normalized,
                }
                | Lobe::BlinnPhong {
                    specular,
                    exponent,
                    normalized,
                }),
            ) => {
                self.u32(if matches!(lobe, Lobe::Phong { .. }) {
                    1
                } else {
                    2
                });
                self.vec3(*specular);
                self.f32(*exponent);
                self.u32(u32::from(*normalized));
            }
            Some(Lobe::CookTorrance {
                specular,
                roughness,
                ior,
                fresnel,
            }) => {
                self.u32(3);
                self.vec3(*specular);
                self.f32(*roughness);
                self.ior(ior);
                self.u32(match fresnel {
                    FresnelModel::Exact => 0,
                    FresnelModel::Schlick => 1,
                });
            }
            Some(Lobe::Mirror { reflectance }) => {
                self.u32(4);
                self.vec3(*reflectance);
            }
            Some(Lobe::Dielectric { ior }) => {
                self.u32(5);
                self.f32(*ior);
            }
            Some(Lobe::Conductor { ior }) => {
                self.u32(6);
                self.ior(ior);
            }
            // `Lobe` is non-exhaustive: a lobe added to twopass-brdf later is told apart by
            // its printed parameters until it gets its own arm here.
            Some(other) => {
                self.u32(u32::MAX);
                self.bytes(format!("{other:?}").as_bytes());
            }
        }
    }
}

/// Fingerprint of what the element mesh is built on: every triangle's position and normal
/// indices, every position and normal (bit patterns), and each triangle's object. A bake is
/// refused for a scene whose fingerprint differs.
pub fn geometry_fingerprint(scene: &Scene) -> u64 {
    let m = &scene.mesh;
    let mut h = Fnv::new();
    h.u64(m.vertex_count() as u64);
    m.positions().for_each(|p| h.vec3(p));
    h.u64(m.normal_count() as u64);
    (0..m.normal_count() as u32).for_each(|n| h.vec3(m.normal(n)));
    h.u64(m.triangle_count() as u64);
    for t in 0..m.triangle_count() {
        m.triangle(t as u32).iter().for_each(|&i| h.u32(i));
        m.normal_indices(t as u32).iter().for_each(|&i| h.u32(i));
        h.u32(m.object_of(t as u32));
    }
    h.0
}

/// Fingerprint of what the radiosity values depend on besides geometry: each object's emitted
/// radiance and its material's diffuse reflectance (bit patterns), in object order, in a scene
/// with textures every material's texture reference, every texture's texels and every
/// triangle's texture coordinates, then the lamps (kind, aim, position, intensity) when there
/// are any.
pub fn lighting_fingerprint(scene: &Scene) -> u64 {
    let mut h = Fnv::new();
    h.u64(scene.objects.len() as u64);
    for o in &scene.objects {
        h.vec3(o.emission);
        let rho = scene
            .materials
            .get(o.material as usize)
            .map_or(Vec3::ZERO, |m| m.material.diffuse_albedo());
        h.vec3(rho);
    }
    // Base colour textures: only a textured scene hashes them, so an untextured scene's
    // fingerprint is what it was before textures were read.
    if scene.has_textures() {
        for m in &scene.materials {
            match &m.albedo_texture {
                Some(a) => {
                    h.u32(a.texture + 1);
                    h.bytes(format!("{:?}{:?}{:?}", a.wrap_u, a.wrap_v, a.filter).as_bytes());
                    [a.scale, a.offset]
                        .into_iter()
                        .for_each(|v| h.vec3(v.extend(0.0)));
                }
                None => h.u32(0),
            }
        }
        for t in &scene.textures {
            let base = &t.levels[0];
            h.u32(base.width);
            h.u32(base.height);
            base.texels.iter().for_each(|&c| h.vec3(c));
        }
        let m = &scene.mesh;
        for uv in (0..m.triangle_count() as u32)
            .filter(|_| m.has_albedo_uvs())
            .map(|t| m.albedo_uv(t))
        {
            match uv {
                Some(c) => c.iter().for_each(|p| h.vec3(p.extend(1.0))),
                None => h.u32(u32::MAX),
            }
        }
    }
    // The lamps: kind, aim, position and intensity. Hashed only when there are any, so a
    // scene without lamps keeps the fingerprint its bakes were written with.
    if !scene.lamps.is_empty() {
        h.u64(scene.lamps.len() as u64);
        for l in &scene.lamps {
            match l.kind {
                LampKind::Point => h.u32(0),
                LampKind::Spot {
                    direction,
                    cos_inner,
                    cos_outer,
                } => {
                    h.u32(1);
                    h.vec3(direction);
                    h.f32(cos_inner);
                    h.f32(cos_outer);
                }
                LampKind::Directional { direction } => {
                    h.u32(2);
                    h.vec3(direction);
                }
            }
            h.vec3(l.position);
            h.vec3(l.intensity);
        }
    }
    // The sky: its kind, parameters and portals (their `Debug` text prints every float
    // exactly). Hashed only when there is one, as the lamps.
    if let Some(sky) = &scene.sky {
        h.bytes(b"sky");
        h.bytes(format!("{sky:?}").as_bytes());
    }
    h.0
}

/// Fingerprint of everything in a scene that changes a rendered image: the geometry and
/// lighting fingerprints, every material (diffuse and ambient reflectance, the non-diffuse lobe
/// and its parameters), each object's material, and the camera (position, frame, field of view,
/// resolution), all as bit patterns.
pub fn scene_fingerprint(scene: &Scene) -> u64 {
    let mut h = Fnv::new();
    h.u64(geometry_fingerprint(scene));
    h.u64(lighting_fingerprint(scene));
    h.u64(scene.materials.len() as u64);
    for m in &scene.materials {
        h.vec3(m.material.diffuse_albedo());
        h.vec3(m.material.ambient());
        h.lobe(m.material.lobe());
    }
    scene.objects.iter().for_each(|o| h.u32(o.material));
    let c = &scene.camera;
    [c.position, c.forward, c.right, c.up]
        .into_iter()
        .for_each(|v| h.vec3(v));
    h.f32(c.fov_y);
    h.u32(c.width);
    h.u32(c.height);
    h.0
}

/// Name of the EXR header attribute that holds [`lightmap_fingerprint`] of the lightmap's
/// texels (also in the `.glb`'s `asset.extras.twopass.exr_fingerprint`), as 16 hex digits.
pub const LIGHTMAP_FINGERPRINT: &str = "twopassLightmapFingerprint";

/// Fingerprint of a lightmap's texels: its size and every value, as bit patterns. Written into
/// both the lightmap `.glb` and its EXR, so that an EXR is read only beside the `.glb` of its
/// own bake (an atlas of the same size from another bake holds other charts' texels).
pub fn lightmap_fingerprint(image: &Image) -> u64 {
    let mut h = Fnv::new();
    h.u32(image.width());
    h.u32(image.height());
    for p in image.pixels() {
        h.vec3(*p);
    }
    h.0
}
