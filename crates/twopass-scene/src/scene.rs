//! The runtime scene: indexed triangle mesh, materials, objects, emitters, camera and the BVH,
//! with the ray queries every pass uses. Built only by [`crate::load`], so its data is valid.

use std::ops::Range;
use std::path::PathBuf;

use glam::{Vec2, Vec3};

pub use crate::mesh::Mesh;
use rayon::prelude::*;
use twopass_brdf::{Material, Rgb};

use crate::accel::{Accel, Ray, SHADOW_EPSILON, SurfacePoint, TriangleHit};
use crate::camera::Camera;
use crate::lamp::LampLight;

/// Rays one rayon job of [`Scene::intersect_batch`] and [`Scene::occluded_batch`] walks: enough
/// to keep an interleaved walk full, few enough to spread over the threads.
const BATCH_CHUNK: usize = 1024;

/// An axis-aligned bounding box, scene units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Bounds {
    /// The empty box (grows with [`Bounds::grow`]).
    pub const EMPTY: Self = Self {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The box grown to contain `p`.
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Length of the diagonal (0 for the empty box).
    pub fn diagonal(&self) -> f32 {
        if self.min.cmple(self.max).all() {
            (self.max - self.min).length()
        } else {
            0.0
        }
    }

    /// The centre.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
}

/// A material with its scene name.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneMaterial {
    /// Name in the scene file (MTL materials: `file.obj:name`).
    pub name: String,
    /// The validated model parameters; with a texture, its diffuse reflectance is the
    /// factor the texture's value multiplies.
    pub material: Material,
    /// The base colour texture, if any.
    pub albedo_texture: Option<crate::texture::AlbedoTexture>,
}

/// One object of the scene: a contiguous run of triangles and vertices with one material.
#[derive(Debug, Clone, PartialEq)]
pub struct Object {
    /// Name from the scene file (OBJ groups: `object/group`).
    pub name: String,
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// Emitted radiance L_e per channel, W/(m^2 sr) in scene units, from the front side (zero
    /// for non-emitters).
    pub emission: Rgb,
    /// Its triangles in [`Mesh::triangles`].
    pub triangles: Range<u32>,
    /// Its vertices in [`Mesh::positions`].
    pub vertices: Range<u32>,
}

/// An emitting object: a one-sided Lambertian area light of constant radiance.
#[derive(Debug, Clone, PartialEq)]
pub struct Emitter {
    /// Index into [`Scene::objects`].
    pub object: u32,
    /// Radiance L_e per channel, W/(m^2 sr) in scene units.
    pub radiance: Rgb,
    /// Total area, scene units squared.
    pub area: f32,
    /// Emitted power per channel, pi * L_e * area (W in scene units).
    pub power: Rgb,
    /// Cumulative triangle areas over the object's triangles, for area sampling.
    cdf: Vec<f32>,
}

impl Emitter {
    /// A point uniformly distributed over the emitter's area (density 1 / `area`), from three
    /// uniform numbers: `pick` chooses the triangle, `u` the point on it.
    pub fn sample(&self, scene: &Scene, pick: f32, u: Vec2) -> SurfacePoint {
        let target = pick * self.area;
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.cdf.len() - 1);
        let t = scene.objects[self.object as usize].triangles.start + i as u32;
        scene.mesh.sample_triangle(t, u)
    }
}

/// A closest hit with everything a shader needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (a distance for unit directions).
    pub t: f32,
    /// The hit point with its normal and error bound.
    pub point: SurfacePoint,
    /// Barycentric weights of the triangle's vertices.
    pub barycentric: [f32; 3],
    /// Interpolated unit shading normal (same side as the geometric normal).
    pub shading_normal: Vec3,
    /// Whether the ray arrived on the front side (against the geometric normal).
    pub front_face: bool,
    /// Index into [`Scene::objects`].
    pub object: u32,
    /// Index into [`Scene::materials`].
    pub material: u32,
}

/// A loaded, validated scene.
#[derive(Debug)]
pub struct Scene {
    /// The file it was loaded from.
    pub path: PathBuf,
    /// The length unit of every position (the scene file's `unit`; metres for a bare OBJ).
    pub unit: crate::unit::Unit,
    /// All geometry.
    pub mesh: Mesh,
    /// The material table.
    pub materials: Vec<SceneMaterial>,
    /// The objects, in file order.
    pub objects: Vec<Object>,
    /// The emitting objects.
    pub emitters: Vec<Emitter>,
    /// The lamps: point, spot and directional lights (delta lights, never hit by a ray).
    pub lamps: Vec<crate::lamp::Lamp>,
    /// The sky, lighting every ray that escapes the scene ([`crate::sky`]); `None`: black.
    pub sky: Option<crate::sky::Sky>,
    /// The camera.
    pub camera: Camera,
    /// The textures materials refer to ([`SceneMaterial::albedo_texture`]), each decoded once.
    pub textures: Vec<crate::texture::Texture>,
    /// Bounds of all geometry.
    pub bounds: Bounds,
    /// A glTF scene's own document and data (`None` for other inputs): what a bake needs to
    /// write the user's asset back.
    pub gltf: Option<Box<crate::gltf_source::GltfSource>>,
    accel: Accel,
}

impl Scene {
    /// Assembles a scene from validated parts and builds its BVH.
    pub(crate) fn assemble(
        path: PathBuf,
        unit: crate::unit::Unit,
        mesh: Mesh,
        materials: Vec<SceneMaterial>,
        objects: Vec<Object>,
        lamps: Vec<crate::lamp::Lamp>,
        camera: Camera,
    ) -> Self {
        let bounds = mesh.positions().fold(Bounds::EMPTY, |b, p| b.grow(p));
        let emitters = objects
            .iter()
            .enumerate()
            .filter(|(_, o)| o.emission.max_element() > 0.0)
            .map(|(i, o)| {
                let mut acc = 0.0_f64;
                let cdf: Vec<f32> = o
                    .triangles
                    .clone()
                    .map(|t| {
                        acc += f64::from(mesh.area(t));
                        acc as f32
                    })
                    .collect();
                let area = acc as f32;
                Emitter {
                    object: i as u32,
                    radiance: o.emission,
                    area,
                    power: o.emission * (std::f32::consts::PI * area),
                    cdf,
                }
            })
            .collect();
        let accel = mesh.accel();
        Self {
            path,
            unit,
            mesh,
            materials,
            objects,
            emitters,
            lamps,
            sky: None,
            camera,
            textures: Vec::new(),
            bounds,
            gltf: None,
            accel,
        }
    }

    /// The BVH (build statistics, raw queries).
    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    /// The material of triangle `t`.
    pub fn material_of(&self, t: u32) -> &Material {
        let o = &self.objects[self.mesh.object_of(t) as usize];
        &self.materials[o.material as usize].material
    }

    /// Total area of the scene's surfaces, scene units squared.
    pub fn total_area(&self) -> f64 {
        self.mesh.areas().map(f64::from).sum()
    }

    fn hit_from(&self, ray: &Ray, h: TriangleHit) -> Hit {
        // The hit carries the corners the accelerator just read: no second fetch from the mesh.
        let point = self
            .mesh
            .surface_point_on(h.triangle, h.corners, h.barycentric);
        let object = self.mesh.object_of(h.triangle);
        Hit {
            t: h.t,
            point,
            barycentric: h.barycentric,
            shading_normal: self.mesh.front_shading_normal(h.triangle, h.barycentric),
            front_face: ray.direction.dot(point.normal) < 0.0,
            object,
            material: self.objects[object as usize].material,
        }
    }

    /// The hit of triangle `t` at barycentrics `b` as a ray arriving on its front side would
    /// find it (at distance 0): where a point of the surface itself, a lightmap texel or a
    /// vertex, is shaded.
    pub fn surface_hit(&self, t: u32, b: [f32; 3]) -> Hit {
        let object = self.mesh.object_of(t);
        Hit {
            t: 0.0,
            point: self.mesh.surface_point(t, b),
            barycentric: b,
            shading_normal: self.mesh.front_shading_normal(t, b),
            front_face: true,
            object,
            material: self.objects[object as usize].material,
        }
    }

    /// The closest hit along `ray` with `0 < t < ray.t_max`.
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.accel
            .closest(ray.origin, ray.direction, ray.t_max)
            .map(|h| self.hit_from(ray, h))
    }

    /// The closest hit of a ray leaving surface point `from` in `direction`; the origin is
    /// offset inside, so the ray never hits `from`'s own surface at its start.
    pub fn intersect_from(&self, from: &SurfacePoint, direction: Vec3) -> Option<Hit> {
        let ray = Ray::new(from.spawn_origin(direction), direction);
        self.intersect(&ray)
    }

    /// Whether anything blocks the segment from surface point `from` to point `to` (a point in
    /// space, e.g. a light position). The target itself never counts as a blocker.
    pub fn occluded(&self, from: &SurfacePoint, to: Vec3) -> bool {
        let o = from.spawn_origin(to - from.position);
        self.accel.any_hit(o, to - o, 1.0 - SHADOW_EPSILON)
    }

    /// Whether anything blocks the segment between two surface points (visibility for shadow
    /// rays to emitter samples and radiosity form factors). Both ends are offset.
    pub fn occluded_between(&self, from: &SurfacePoint, to: &SurfacePoint) -> bool {
        let r = Self::segment_between(from, to);
        self.accel.any_hit(r.origin, r.direction, r.t_max)
    }

    /// The shadow ray [`Scene::occluded_between`] casts between two surface points: both ends
    /// offset off their surfaces, `t` in (0, `t_max`) covering the segment without its ends.
    /// Exposed so that other ray engines can be given exactly the same queries (`bench rays
    /// --export`).
    pub fn segment_between(from: &SurfacePoint, to: &SurfacePoint) -> Ray {
        let o = from.spawn_origin(to.position - from.position);
        let t = to.spawn_origin(o - to.position);
        Ray {
            origin: o,
            direction: t - o,
            t_max: 1.0 - SHADOW_EPSILON,
        }
    }

    /// [`Scene::intersect`] for many rays in parallel (rayon); results in input order. Each
    /// thread walks its rays through [`Accel::closest_many`] (interleaved on large trees,
    /// where that is faster: unless the rays are coherent, such as camera rays in pixel
    /// order).
    pub fn intersect_batch(&self, rays: &[Ray]) -> Vec<Option<Hit>> {
        let mut hits = vec![None; rays.len()];
        rays.par_chunks(BATCH_CHUNK)
            .zip(hits.par_chunks_mut(BATCH_CHUNK))
            .for_each(|(rays, out)| {
                let mut found = vec![None; rays.len()];
                self.accel.closest_many(rays, &mut found);
                for ((hit, h), ray) in out.iter_mut().zip(found).zip(rays) {
                    *hit = h.map(|h| self.hit_from(ray, h));
                }
            });
        hits
    }

    /// [`Scene::occluded_between`] for many pairs in parallel (rayon); results in input order.
    /// Each thread walks its segments through [`Accel::any_hit_many`] (interleaved on large
    /// trees).
    pub fn occluded_batch(&self, pairs: &[(SurfacePoint, SurfacePoint)]) -> Vec<bool> {
        let mut blocked = vec![false; pairs.len()];
        pairs
            .par_chunks(BATCH_CHUNK)
            .zip(blocked.par_chunks_mut(BATCH_CHUNK))
            .for_each(|(pairs, out)| {
                let rays: Vec<Ray> = pairs
                    .iter()
                    .map(|(a, b)| Self::segment_between(a, b))
                    .collect();
                self.accel.any_hit_many(&rays, out);
            });
        blocked
    }
}

/// The lamps' light at surface points (point, spot and directional lamps:
/// [`crate::lamp`]).
impl Scene {
    /// Whether anything blocks the light of `light` (found by [`Lamp::light_at`](crate::Lamp::light_at) at
    /// `from`'s position) before it reaches surface point `from`: a shadow ray to the lamp,
    /// or toward a directional lamp without end.
    pub fn lamp_occluded(&self, from: &SurfacePoint, light: &LampLight) -> bool {
        if light.distance.is_finite() {
            self.occluded(from, from.position + light.direction * light.distance)
        } else {
            let o = from.spawn_origin(light.direction);
            self.accel()
                .any_hit(o, light.direction, f32::INFINITY * (1.0 - SHADOW_EPSILON))
        }
    }

    /// The irradiance (W per scene unit squared per channel) that every lamp sends to the
    /// front of surface point `at` whose receiving normal is `normal` (unit), shadows
    /// included: the sum of I cos(theta) / r^2 and E cos(theta). Counts its shadow rays in
    /// `rays`.
    pub fn lamp_irradiance(&self, at: &SurfacePoint, normal: Vec3, rays: &mut u64) -> Rgb {
        let mut sum = Rgb::ZERO;
        for lamp in &self.lamps {
            let Some(light) = lamp.light_at(at.position) else {
                continue;
            };
            let cos = light.direction.dot(normal);
            if cos <= 0.0 || light.direction.dot(at.normal) <= 0.0 {
                continue;
            }
            *rays += 1;
            if !self.lamp_occluded(at, &light) {
                sum += light.irradiance * cos;
            }
        }
        sum
    }

    /// Whether anything lights the scene: an emitting surface, a lamp or a sky.
    pub fn has_light(&self) -> bool {
        !self.emitters.is_empty() || !self.lamps.is_empty() || self.sky.is_some()
    }

    /// Total power of the lamps, W per channel ([`Lamp::power`](crate::Lamp::power)).
    pub fn lamp_power(&self) -> Rgb {
        self.lamps
            .iter()
            .fold(Rgb::ZERO, |s, l| s + l.power(self.bounds.diagonal()))
    }
}
