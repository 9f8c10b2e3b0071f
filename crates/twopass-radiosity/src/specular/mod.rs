//! Specular transfer in the view-independent pass: light that leaves a shooting patch, bounces
//! off or through delta surfaces (mirror, smooth conductor, smooth dielectric) and lands on a
//! diffuse surface, in Heckbert's notation the paths L S+ D and D S+ D.
//!
//! When progressive refinement shoots a patch, the form factors carry its light to every
//! vertex the patch sees directly (with the specular objects as occluders, since they do not
//! take part). This module carries the rest: it traces rays from the shooter toward the
//! specular objects, follows them through the delta lobes of `twopass-brdf`
//! ([`twopass_brdf::delta::DeltaLobe::sample_flux`]: the power a refraction carries, not its
//! radiance) up to [`SpecularOptions::max_depth`] bounces, and hands back where they land on
//! a surface that takes part in radiosity, with the power they carry. A ray whose first hit is
//! not specular carries nothing here: that light is the form factors' (nothing is counted
//! twice). The solver splats the landed power onto the element vertices as irradiance, so it
//! is then reflected and shot again like any other light. Choice and justification:
//! ARCHITECTURE.md, "Specular transfer".
//!
//! Sampling: a point on the shooting patch stratified over a k x k grid, paired with a
//! direction from another k x k grid through a shuffle (the two 2-D strata are each covered
//! once), the direction drawn from the cones that the specular objects' bounding spheres
//! subtend (a mixture, one cone per object, chosen by solid angle), weighted by the patch's
//! cosine over the mixture density. Directions outside every cone cannot reach a specular
//! surface first, so they carry nothing here and need no ray. Every random number comes from
//! a SplitMix64 stream keyed by (seed, patch, shot, ray): the same seed gives the same
//! solution on any number of threads.

use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;
use twopass_brdf::colour::luminance_f64;
use twopass_brdf::frame::Frame;
use twopass_brdf::random::{SplitMix64, hash, unit_f32, unit_f64};
use twopass_scene::targets::specular_objects;
use twopass_scene::{Hit, LampKind, Ray, Scene, SpecularTargets};

use crate::element::ElementMesh;
use crate::options::{SpecularOptions, participating};

mod sky;

/// Probe rays cast from the specular surfaces by [`decide`].
pub const PROBE_RAYS: u32 = 4096;

/// Whether a scene needs the specular transfer, and why, in words: it runs when some object
/// has a delta material (mirror, conductor, dielectric), something emits, something reflects
/// diffusely, and at least one of [`PROBE_RAYS`] rays leaving the front of the specular
/// surfaces (cosine-distributed, stratified over their area; deterministic, whatever the seed)
/// first reaches the front of a diffusely reflecting surface: such a surface then both lights
/// the specular one and receives from it (the same ray read both ways). A scene without such a
/// pair solves exactly as it would without this module.
pub fn decide(scene: &Scene) -> (bool, String) {
    let specular: Vec<usize> = specular_objects(scene);
    if specular.is_empty() {
        return (
            false,
            "no mirror, conductor or dielectric surface: all transfer is diffuse".into(),
        );
    }
    if !scene.has_light() {
        return (false, "nothing emits light".into());
    }
    let takes_part = participating(scene);
    let diffuse = |o: usize| {
        scene.materials[scene.objects[o].material as usize]
            .material
            .reflects_diffusely()
    };
    if !(0..scene.objects.len()).any(|o| takes_part[o] && diffuse(o)) {
        return (false, "no surface reflects diffusely".into());
    }
    let names: Vec<&str> = specular
        .iter()
        .map(|&o| scene.objects[o].name.as_str())
        .collect();
    let per_object = (PROBE_RAYS / specular.len() as u32).max(1);
    let mut reached = 0u32;
    let mut cast = 0u32;
    for &o in &specular {
        let tris = scene.objects[o].triangles.clone();
        let mut cdf = Vec::with_capacity(tris.len());
        let mut acc = 0.0f64;
        for t in tris.clone() {
            acc += f64::from(scene.mesh.area(t));
            cdf.push(acc);
        }
        let k = f64::from(per_object).sqrt().ceil() as u32;
        for i in 0..k * k {
            let h = hash(0x5eec_0001 ^ ((o as u64) << 32 | u64::from(i)));
            let mut rng = SplitMix64::new(h);
            let u = stratum(i, k, Vec2::new(rng.next_f32(), rng.next_f32()));
            let target = f64::from(u.x) * acc;
            let j = cdf.partition_point(|&c| c <= target).min(cdf.len() - 1);
            let t = tris.start + j as u32;
            let point = scene
                .mesh
                .sample_triangle(t, Vec2::new(u.y, rng.next_f32()));
            let w = twopass_brdf::sample::square_to_cosine_hemisphere(Vec2::new(
                rng.next_f32(),
                rng.next_f32(),
            ));
            let dir = Frame::from_normal(point.normal).to_world(w);
            cast += 1;
            if let Some(hit) = scene.intersect_from(&point, dir)
                && hit.front_face
                && takes_part[hit.object as usize]
                && diffuse(hit.object as usize)
            {
                reached += 1;
            }
        }
    }
    if reached == 0 {
        return (
            false,
            format!(
                "{} is lit by and seen from no diffuse surface (none of {cast} probe rays from \
                 it reaches one)",
                names.join(", ")
            ),
        );
    }
    (
        true,
        format!(
            "{} face diffuse surfaces ({reached} of {cast} probe rays from them reach one): \
             light through them is carried to the elements",
            names.join(", ")
        ),
    )
}

/// Point `u` in [0, 1)^2 moved into stratum `i` of a `k` x `k` grid.
pub(crate) fn stratum(i: u32, k: u32, u: Vec2) -> Vec2 {
    let (x, y) = (i % k, i / k);
    Vec2::new(
        ((x as f32 + u.x) / k as f32).min(1.0 - f32::EPSILON / 2.0),
        ((y as f32 + u.y) / k as f32).min(1.0 - f32::EPSILON / 2.0),
    )
}

/// Power landed on a surface that takes part, after at least one specular bounce.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Deposit {
    /// Scene triangle.
    pub triangle: u32,
    /// Barycentrics (b1, b2) on it.
    pub b: Vec2,
    /// The element-mesh node it was last found in (`u32::MAX`: not looked up yet): the search
    /// after a refinement starts there.
    pub node: u32,
    /// Power per channel, W (with areas in scene units).
    pub power: Vec3,
    /// The part of `power` that left an emitter as emission and went through at least one
    /// refraction: the focused caustic a renderer may show per pixel instead
    /// ([`crate::Solution::focused_caustics`]), W per channel.
    pub focused: Vec3,
}

/// A shooting patch: its triangle `corners` on scene triangle `tri` (light leaves its front),
/// its unshot radiosity (W/m^2 per channel), the fraction of it per channel that is emission
/// (in [0, 1]) and its area (scene units squared).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Shooter {
    pub corners: [DVec3; 3],
    pub tri: u32,
    pub radiosity: DVec3,
    pub emitted: DVec3,
    pub area: f64,
}

/// The specular transfer of one solve: the targets, the deposits so far (kept so that they can
/// be splatted again onto a refined mesh), and the rays cast.
#[derive(Debug, Clone)]
pub(crate) struct Specular {
    settings: SpecularOptions,
    targets: SpecularTargets,
    /// Per object: whether it takes part (receives deposits).
    takes_part: Vec<bool>,
    /// Every deposit so far, in shot order.
    pub deposits: Vec<Deposit>,
    /// Rays cast so far.
    pub rays: u64,
}

impl Specular {
    /// The transfer for `scene`, or `None` when [`decide`] says it is not needed.
    pub fn new(scene: &Scene, settings: SpecularOptions, takes_part: &[bool]) -> Option<Self> {
        if settings.rays == 0 || !decide(scene).0 {
            return None;
        }
        let targets = SpecularTargets::new(scene);
        Some(Self {
            settings,
            targets,
            takes_part: takes_part.to_vec(),
            deposits: Vec::new(),
            rays: 0,
        })
    }

    /// Sends the exitance changes of element-mesh leaves through the specular surfaces:
    /// `changes` holds, per leaf, its (emitted, reflected) exitance change since it last sent
    /// (W/m^2, either sign). The rays of a shot of the whole emitted power
    /// ([`SpecularOptions::rays`], `emitted` its luminance) are spread over the leaves in
    /// proportion to the luminance of each change's magnitude times the leaf's area, by
    /// systematic sampling, so every ray carries the same share and the transfer is unbiased
    /// whatever the leaf count (at least [`SpecularOptions::MIN_RAYS`] in all); a decrease
    /// is sent as negative power, so what a leaf has sent always equals its exitance. Leaves
    /// are shot where the light leaves them, not as the uniform patch they belong to: a caustic
    /// spot sends its light through the glass again from the spot. Returns `None` when the
    /// changes total no more than `threshold` (luminance power, W): nothing is sent, the
    /// caller keeps them for later. Otherwise the deposits in leaf order and the rays cast.
    pub fn shoot_changes(
        &self,
        scene: &Scene,
        mesh: &ElementMesh,
        changes: &[(u32, [DVec3; 2])],
        emitted: f64,
        threshold: f64,
        key: u64,
    ) -> Option<(Vec<Deposit>, u64)> {
        let power = |n: u32, d: &[DVec3; 2]| {
            luminance_f64((d[0] + d[1]).abs()) * f64::from(mesh.nodes[n as usize].area)
        };
        let total: f64 = changes.iter().map(|(n, d)| power(*n, d)).sum();
        if total.is_nan() || total <= threshold || total <= 0.0 {
            return None;
        }
        let rays = (f64::from(self.settings.rays) * total / emitted.max(f64::MIN_POSITIVE))
            .ceil()
            .clamp(
                f64::from(SpecularOptions::MIN_RAYS),
                16.0 * f64::from(SpecularOptions::MAX_RAYS),
            ) as u64;
        // Systematic sampling: ray j sits at (j + u) / rays of the cumulative change.
        let u = unit_f64(hash(key ^ 0x5eec_0515));
        let mut shots: Vec<(u32, [DVec3; 2], u32)> = Vec::new();
        let mut acc = 0.0;
        for (n, d) in changes {
            let p = power(*n, d);
            if p <= 0.0 {
                continue;
            }
            let lo = acc / total * rays as f64;
            acc += p;
            let hi = acc / total * rays as f64;
            let count = ((hi - u).ceil() - (lo - u).ceil()).max(0.0) as u32;
            if count > 0 {
                shots.push((*n, *d, count));
            }
        }
        let per_ray = total / rays as f64;
        let results: Vec<(Vec<Deposit>, u64)> = shots
            .par_iter()
            .map(|&(n, d, count)| {
                let node = &mesh.nodes[n as usize];
                let area = f64::from(node.area);
                let change = d[0] + d[1];
                // Each ray carries the luminance per_ray: the shot's radiosity is the change's
                // magnitude scaled so that B A / count = |change| A per_ray / p.
                let scale = f64::from(count) * per_ray / power(n, &d);
                let emitted = DVec3::select(
                    change.cmpne(DVec3::ZERO),
                    (d[0] / change).clamp(DVec3::ZERO, DVec3::ONE),
                    DVec3::ZERO,
                );
                let shooter = Shooter {
                    corners: mesh.corners(n),
                    tri: node.scene_triangle,
                    radiosity: change.abs() * scale,
                    emitted,
                    area,
                };
                let (mut deposits, rays) =
                    self.shoot(scene, &shooter, count, hash(key ^ u64::from(n)));
                // The change's sign, per channel.
                let sign =
                    DVec3::select(change.cmplt(DVec3::ZERO), -DVec3::ONE, DVec3::ONE).as_vec3();
                if sign != Vec3::ONE {
                    for d in &mut deposits {
                        d.power *= sign;
                        d.focused *= sign;
                    }
                }
                (deposits, rays)
            })
            .collect();
        let mut deposits = Vec::new();
        let mut cast = 0;
        for (d, r) in results {
            deposits.extend(d);
            cast += r;
        }
        Some((deposits, cast))
    }

    /// Traces the specular paths of one shot of `shooter` with `n` rays (the first floor(sqrt(n))^2
    /// stratified, the rest uniform), random stream keyed by `key`. Returns the deposits in ray
    /// order and the rays cast. Parallel over rays; the result does not depend on scheduling.
    pub fn shoot(&self, scene: &Scene, shooter: &Shooter, n: u32, key: u64) -> (Vec<Deposit>, u64) {
        let Shooter {
            corners,
            tri,
            radiosity,
            emitted,
            area,
        } = *shooter;
        // The first k^2 rays are stratified, the rest (when n is not a square) uniform.
        let k = n.isqrt();
        // Direction strata paired with point strata through a shuffle (Fisher-Yates).
        let mut pairing: Vec<u32> = (0..k * k).collect();
        let mut rng = SplitMix64::new(hash(key ^ 0x5eec_5eec));
        for i in (1..(k * k) as usize).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            pairing.swap(i, j);
        }
        let corner_b = corners.map(|c| scene.mesh.barycentric(tri, c));
        let normal = scene.mesh.geometric_normal(tri).as_dvec3();
        // Power per ray before the cosine over the density: B A / n.
        let per_ray = radiosity * area / f64::from(n);
        let results: Vec<(Option<Deposit>, u64)> = (0..n)
            .into_par_iter()
            .with_min_len(64)
            .map(|i| {
                let mut rng = SplitMix64::new(hash(key ^ u64::from(i)));
                let (up, ud) = if i < k * k {
                    (
                        stratum(i, k, Vec2::new(rng.next_f32(), rng.next_f32())),
                        stratum(
                            pairing[i as usize],
                            k,
                            Vec2::new(rng.next_f32(), rng.next_f32()),
                        ),
                    )
                } else {
                    (
                        Vec2::new(rng.next_f32(), rng.next_f32()),
                        Vec2::new(rng.next_f32(), rng.next_f32()),
                    )
                };
                // Uniform point on the patch (triangle-square warp).
                let s = f64::from(up.x).sqrt();
                let (b1, b2) = (s * (1.0 - f64::from(up.y)), s * f64::from(up.y));
                let w = [1.0 - b1 - b2, b1, b2];
                let b = [0, 1, 2].map(|c| {
                    (corner_b[0][c] * w[0] + corner_b[1][c] * w[1] + corner_b[2][c] * w[2]) as f32
                });
                let from = scene.mesh.surface_point(tri, b);
                let x = from.position.as_dvec3();
                let Some((dir, pdf)) = self.targets.direction(x, ud) else {
                    return (None, 0);
                };
                let cos = dir.dot(normal);
                if cos <= 0.0 {
                    return (None, 0);
                }
                let power = per_ray * (cos / std::f64::consts::PI / pdf);
                let dir = dir.as_vec3();
                let first = scene.intersect_from(&from, dir);
                self.follow(scene, first, dir, power, emitted, &mut rng)
            })
            .collect();
        let rays = results.iter().map(|r| r.1).sum();
        (results.into_iter().filter_map(|r| r.0).collect(), rays)
    }

    /// Rays for a light of luminance power `power` (W): its share of [`SpecularOptions::rays`]
    /// by its share of `emitted` (the scene's whole emitted luminance power, W), within
    /// [`SpecularOptions::MIN_RAYS`] and [`SpecularOptions::MAX_RAYS`].
    fn rays_for(&self, power: f64, emitted: f64) -> u32 {
        (f64::from(self.settings.rays) * power / emitted.max(f64::MIN_POSITIVE))
            .ceil()
            .clamp(
                f64::from(SpecularOptions::MIN_RAYS),
                f64::from(SpecularOptions::MAX_RAYS),
            ) as u32
    }

    /// The lamps' and the sky's light through the specular surfaces (point and spot lamps
    /// from their position toward the targets' cones, directional lamps across their beam
    /// toward the targets' discs, [`SpecularTargets::parallel`]; the sky's sun and dome as
    /// beams direction by direction, the `sky` module), all of it emission. Each lamp gets the
    /// share of [`SpecularOptions::rays`] its power has of `emitted` (the scene's whole
    /// emitted luminance power, W), at least [`SpecularOptions::MIN_RAYS`]; its rays are
    /// stratified over the (cone or disc, direction or point) square. Returns the deposits in
    /// lamp and ray order and the rays cast; the same `key` gives the same deposits on any
    /// number of threads.
    pub fn shoot_lamps(&self, scene: &Scene, emitted: f64, key: u64) -> (Vec<Deposit>, u64) {
        let back = f64::from(scene.bounds.diagonal()) * 2.0;
        let mut deposits = Vec::new();
        let mut cast = 0;
        for (l, lamp) in scene.lamps.iter().enumerate() {
            let power = luminance_f64(lamp.power(scene.bounds.diagonal()).as_dvec3());
            if power.is_nan() || power <= 0.0 {
                continue;
            }
            let n = self.rays_for(power, emitted);
            let k = n.isqrt();
            let lamp_key = hash(key ^ 0x1a3b_0000_0000 ^ l as u64);
            let results: Vec<(Option<Deposit>, u64)> = (0..n)
                .into_par_iter()
                .with_min_len(64)
                .map(|i| {
                    let mut rng = SplitMix64::new(hash(lamp_key ^ u64::from(i)));
                    let u = Vec2::new(rng.next_f32(), rng.next_f32());
                    let u = if i < k * k { stratum(i, k, u) } else { u };
                    let (ray, power) = match lamp.kind {
                        LampKind::Directional { direction } => {
                            let dir = direction.as_dvec3().normalize();
                            let Some((point, density)) = self.targets.parallel(dir, u) else {
                                return (None, 0);
                            };
                            // E dA / p(A) per ray, from outside the scene's bounds.
                            let w = lamp.intensity.as_dvec3() / (density * f64::from(n));
                            (Ray::new((point - dir * back).as_vec3(), dir.as_vec3()), w)
                        }
                        _ => {
                            let x = lamp.position.as_dvec3();
                            let Some((dir, pdf)) = self.targets.direction(x, u) else {
                                return (None, 0);
                            };
                            let dir = dir.as_vec3().normalize();
                            // I(w) dw / p(w) per ray.
                            let w = lamp.intensity_toward(dir).as_dvec3() / (pdf * f64::from(n));
                            (Ray::new(lamp.position, dir), w)
                        }
                    };
                    if power.is_nan() || power.max_element() <= 0.0 {
                        return (None, 0);
                    }
                    let first = scene.intersect(&ray);
                    self.follow(scene, first, ray.direction, power, DVec3::ONE, &mut rng)
                })
                .collect();
            for (d, r) in results {
                deposits.extend(d);
                cast += r;
            }
        }
        let (sky, rays) = self.shoot_sky(scene, emitted, key);
        deposits.extend(sky);
        cast += rays;
        (deposits, cast)
    }

    /// Follows a ray that met `first` going in `dir` with `power` (of which the fraction
    /// `emitted` per channel is emission) through the delta surfaces; returns where it lands
    /// (after at least one specular bounce, on the front of a surface that takes part) and the
    /// rays cast, the first one's included.
    fn follow(
        &self,
        scene: &Scene,
        first: Option<Hit>,
        mut dir: Vec3,
        mut power: DVec3,
        emitted: DVec3,
        rng: &mut SplitMix64,
    ) -> (Option<Deposit>, u64) {
        let mut refracted = false;
        let mut rays = 1;
        let Some(mut hit) = first else {
            return (None, rays);
        };
        let mut bounces = 0;
        loop {
            let material = &scene.materials[hit.material as usize].material;
            let Some(lobe) = material.delta() else {
                // The first hit is diffuse: the form factors carry that light, not this pass.
                if bounces == 0 || !hit.front_face || !self.takes_part[hit.object as usize] {
                    return (None, rays);
                }
                let p = power.as_vec3();
                if !(p.is_finite() && p.max_element() > 0.0) {
                    return (None, rays);
                }
                return (
                    Some(Deposit {
                        triangle: hit.point.triangle,
                        b: Vec2::new(hit.barycentric[1], hit.barycentric[2]),
                        node: u32::MAX,
                        power: p,
                        focused: if refracted {
                            (power * emitted).as_vec3()
                        } else {
                            Vec3::ZERO
                        },
                    }),
                    rays,
                );
            };
            if bounces >= self.settings.max_depth {
                return (None, rays);
            }
            let frame = Frame::from_normal(hit.shading_normal);
            let wo = frame.to_local(-dir);
            let u = Vec2::new(unit_f32(rng.next_u64()), unit_f32(rng.next_u64()));
            let Some(sample) = lobe.sample_flux(wo, u) else {
                return (None, rays);
            };
            refracted |= sample.kind == twopass_brdf::SampleKind::SpecularTransmission;
            power *= sample.weight.as_dvec3();
            if power.max_element() <= 0.0 {
                return (None, rays);
            }
            dir = frame.to_world(sample.wi).normalize();
            bounces += 1;
            rays += 1;
            match scene.intersect_from(&hit.point, dir) {
                Some(h) => hit = h,
                None => return (None, rays),
            }
        }
    }
}

/// What leaf `n` has sent through the specular surfaces, (emitted, reflected) exitance in
/// W/m^2: its own record in `sent` (per node), else its deepest ancestor's (a leaf split off
/// since has its parent's), else nothing.
pub(crate) fn sent(mesh: &ElementMesh, sent: &[Option<[DVec3; 2]>], n: u32) -> [DVec3; 2] {
    match sent.get(n as usize).copied().flatten() {
        Some(s) => s,
        None => mesh
            .path_to(n)
            .iter()
            .rev()
            .find_map(|&a| sent.get(a as usize).copied().flatten())
            .unwrap_or([DVec3::ZERO; 2]),
    }
}

/// Per vertex: a third of the area of the leaves around it (scene units squared), the area a
/// vertex's irradiance stands for in the solver's power bookkeeping (an element receives its
/// area times the mean of its vertices' irradiance); and the leaves around it.
#[derive(Debug, Clone, Default)]
pub(crate) struct VertexAreas {
    /// Per vertex: a third of the area of the leaves around it.
    pub area: Vec<f64>,
    /// Per vertex: the leaves around it.
    pub leaves: Vec<Vec<u32>>,
}

impl VertexAreas {
    /// The areas and leaves of the current mesh.
    pub fn new(mesh: &ElementMesh) -> Self {
        let mut area = vec![0.0; mesh.vertices.len()];
        let mut leaves = vec![Vec::new(); mesh.vertices.len()];
        for leaf in mesh.leaves() {
            let node = &mesh.nodes[leaf as usize];
            for &v in &node.vertices {
                area[v as usize] += f64::from(node.area) / 3.0;
                leaves[v as usize].push(leaf);
            }
        }
        Self { area, leaves }
    }
}

/// A deposit's whole power (a `part` for [`splat`]).
pub(crate) fn power(d: &Deposit) -> Vec3 {
    d.power
}

/// A deposit's focused part (a `part` for [`splat`]).
pub(crate) fn focused(d: &Deposit) -> Vec3 {
    d.focused
}

/// The deposits' irradiance per vertex (W/m^2) from the power `part` picks of each
/// ([`Deposit::power`] or [`Deposit::focused`]), sorted by vertex, each vertex once: each
/// deposit's power is shared among the three vertices of the element it lands in by its
/// barycentric weights there, and divided by each vertex's area ([`VertexAreas`]), so the
/// power the solver's bookkeeping sees arriving is exactly the power deposited. `scratch` is
/// a per-vertex buffer of zeros (resized here), left zero. Each deposit remembers its element
/// for the next splat. The irradiance is also added into `into`, one value per vertex.
pub(crate) fn splat(
    mesh: &ElementMesh,
    areas: &VertexAreas,
    deposits: &mut [Deposit],
    scratch: &mut Vec<DVec3>,
    part: fn(&Deposit) -> Vec3,
    into: &mut [DVec3],
) -> Vec<(u32, DVec3)> {
    if scratch.len() != mesh.vertices.len() {
        *scratch = vec![DVec3::ZERO; mesh.vertices.len()];
    }
    let mut touched: Vec<u32> = Vec::new();
    for d in deposits {
        let power = part(d);
        if power == Vec3::ZERO {
            continue;
        }
        let found = if d.node == u32::MAX {
            mesh.locate(d.triangle, d.b.x, d.b.y)
        } else {
            Some(mesh.locate_from(d.node, d.b.x, d.b.y))
        };
        let Some((leaf, w)) = found else {
            continue;
        };
        d.node = leaf;
        let w = w.map(|x| f64::from(x).max(0.0));
        let sum = w[0] + w[1] + w[2];
        let w = if sum > 0.0 {
            w.map(|x| x / sum)
        } else {
            [1.0 / 3.0; 3]
        };
        let power = power.as_dvec3();
        for (k, &v) in mesh.nodes[leaf as usize].vertices.iter().enumerate() {
            let a = areas.area[v as usize];
            let e = power * (w[k] / a);
            // A vertex is listed when its sum leaves zero; signed powers (the hierarchical
            // solver sends decreases) may bring it back to zero and list it again (deduplicated
            // below).
            if a > 0.0 && e != DVec3::ZERO {
                if scratch[v as usize] == DVec3::ZERO {
                    touched.push(v);
                }
                scratch[v as usize] += e;
            }
        }
    }
    touched.sort_unstable();
    touched.dedup();
    touched
        .into_iter()
        .map(|v| {
            let e = std::mem::take(&mut scratch[v as usize]);
            into[v as usize] += e;
            (v, e)
        })
        .collect()
}
