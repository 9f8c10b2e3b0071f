//! Fingerprints of a scene: 64-bit FNV-1a hashes over its data (bit patterns, counts, indices),
//! never over formatted text, so they change exactly when the data does. A bake records both
//! and is refused for a scene whose fingerprints differ.

use glam::Vec3;
use twopass_scene::Scene;

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
    fn vec3(&mut self, v: Vec3) {
        for c in v.to_array() {
            self.u32(c.to_bits());
        }
    }
}

/// Fingerprint of what the element mesh is built on: every triangle's position and normal
/// indices, every position and normal (bit patterns), and each triangle's object. A bake is
/// refused for a scene whose fingerprint differs.
pub fn geometry_fingerprint(scene: &Scene) -> u64 {
    let m = &scene.mesh;
    let mut h = Fnv::new();
    h.u64(m.positions.len() as u64);
    m.positions.iter().for_each(|&p| h.vec3(p));
    h.u64(m.normals.len() as u64);
    m.normals.iter().for_each(|&n| h.vec3(n));
    h.u64(m.triangles.len() as u64);
    for t in 0..m.triangles.len() {
        m.triangles[t].iter().for_each(|&i| h.u32(i));
        m.normal_indices[t].iter().for_each(|&i| h.u32(i));
        h.u32(m.triangle_object[t]);
    }
    h.0
}

/// Fingerprint of what the radiosity values depend on besides geometry: each object's emitted
/// radiance and its material's diffuse reflectance (bit patterns), in object order.
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
    h.0
}
