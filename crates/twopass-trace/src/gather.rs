//! The final gather over a radiosity solution (the classic second pass of two-pass methods:
//! Chen et al. 1991; what Bakery and Unity's and Godot's lightmappers do per texel): at one
//! surface point, the direct light from every emitter by stratified shadow rays, plus the
//! indirect light by one bounce of gather rays that read the solution where they land. The
//! solution supplies every further bounce smoothly and cheaply; its blockiness and its errors
//! in the direct light never reach the point, and its errors in the indirect light reach it
//! scaled by the reflectance and averaged over the hemisphere.
//!
//! **No double counting.** The point's radiance is L_e + rho / pi (E_direct + E_gather):
//! - E_direct: light leaving the front of an emitter and reaching the point unoccluded
//!   ([`crate::integrator::direct_light`]; mirrors and glass occlude shadow rays), and from
//!   every lamp by one shadow ray each ([`crate::integrator::lamps_irradiance`]), and from
//!   the sky by stratified directions over the sun's cone and the dome with a shadow ray each
//!   ([`Scene::sky_irradiance`], keyed by the point);
//! - E_gather: the gather rays. Where one lands on a diffuse surface first it takes the
//!   solution's radiance there less the emission (the shadow rays counted that); where it
//!   lands on a mirror or glass, it follows the delta path (one branch chosen by its weight)
//!   and takes the whole solution's radiance where the path ends on a diffuse surface, less
//!   the emission when the scene has caustic photons ([`GatherSettings::photons`]): then the
//!   light an emitter sends onto the point through mirrors and glass (L S+ D, which no shadow
//!   ray finds) is the photons' density estimate, smooth where a few gather rays would carry
//!   all of a small emitter's light (without photons the gather rays take that emission too,
//!   noisily but in full).
//!
//! A gather ray that escapes the scene from the point carries nothing (the sky is in
//! E_direct); one that escapes after a mirror or glass carries the sky's radiance (L S+ D
//! from the sky: no shadow ray passes a delta surface) unless the photons or a light tracer
//! count it (their light paths start at the sky as at the emitters).
//!
//! The point's own value in the solution is not used at all.
//!
//! **Per pixel.** The gathered hybrid ([`crate::hybrid::gathered`]) runs the same gather rays
//! at every diffuse point the camera sees, directly or through mirrors and glass, a few per
//! camera sample (its direct light comes from the Whitted core's shadow rays, the same
//! estimator as E_direct's). Where the camera sees the point directly and a light tracer adds
//! the caustics per pixel ([`crate::light_tracing::CausticScope::FirstDiffuse`]: L S+ D E),
//! the gather rays leave out the emission they reach through a delta path, which is exactly
//! that path class; the rest of the solution they reach through mirrors and glass they keep.
//! At the points it sees through mirrors and glass, caustic photons
//! ([`crate::photons::CausticPhotons`], [`GatherSettings::photons`]) give that light
//! instead, and the gather rays leave it out the same way.
//!
//! **Near hits.** A landing nearer than [`GatherSettings::near_distance`] (by default the
//! radiosity pass's element edge) takes one more bounce instead of the solution's value there:
//! near the point one element fills much of the hemisphere, and its error (a concave corner
//! or a contact the element mesh does not resolve) would reach the point whole. That bounce's
//! own near landings bounce again, up to [`NEAR_BOUNCES`] in all (in a contact both surfaces
//! near the point are where the solution leaks).
//!
//! **Inside objects.** The estimate reports which share of its gather rays first hit the back
//! of a closed object ([`RadianceEstimate::back_faces`]): a lightmap texel whose centre lies
//! where another object intersects its surface sees only that, and the bake leaves it out.
//!
//! **Sampling.** Gather rays are cosine-distributed about the shading normal (importance
//! sampling of the cosine in E = integral of L cos), dimensions 0 and 1 of one Owen-scrambled
//! Sobol point per ray ([`Sampler`], keyed by (seed, point key, ray)); a delta path takes its
//! branch choices from the following dimensions. Rays below the geometric surface carry
//! nothing. The count adapts per point: batches of [`GatherSettings::min_rays`], doubled until
//! the standard error of the indirect luminance is below [`GatherSettings::target_error`] of
//! the point's total or [`GatherSettings::max_rays`] is reached. Everything depends on the
//! point's key and the settings only, so an estimate is the same whichever thread or process
//! computes it, and a bake split into parts merges bit for bit.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use glam::{Vec2, Vec3};
use smart_default::SmartDefault;
use twopass_brdf::Rgb;
use twopass_brdf::colour::luminance;
use twopass_scene::workload::cosine_direction;
use twopass_scene::{DiffuseRadiance, Hit, RadianceEstimate, RadianceEstimator, Scene};

use crate::counters::Tally;
use crate::emitters::{EmitterChoice, Light, Lights};
use crate::integrator::{Shading, irradiance_from, lamp_irradiance, lamps_irradiance};
use crate::photons::{CausticPhotons, PhotonSettings};
use crate::sampler::Sampler;

pub mod fixed;

/// Stream separating a point's shadow-ray numbers from its gather rays' (the gather rays use
/// sample indices 0, 1, ... of the point's Sobol sequence; the shadow rays a sequence of their
/// own).
const DIRECT_STREAM: u64 = 0x5eed_d1ec_7000_0001;

/// Mixed into the seed of a point's sky samples in the final gather.
const SKY_STREAM: u64 = 0x5eed_5c1e_0000_0002;

/// What a gather ray hit first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FirstHit {
    /// Nothing (or it left below the geometric surface).
    Nothing,
    /// The front of a surface, or glass (two-sided).
    Front,
    /// The back of an opaque closed surface: the ray left from inside a closed object.
    Back,
}

/// Per object of `scene`: whether its surface is closed, every edge (its two end positions,
/// bit for bit) shared by exactly two of its triangles.
fn closed_objects(scene: &Scene) -> Vec<bool> {
    use std::collections::HashMap;
    let m = &scene.mesh;
    let key = |v: u32| m.position(v).to_array().map(f32::to_bits);
    scene
        .objects
        .iter()
        .map(|o| {
            let mut edges: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
            for t in o.triangles.clone() {
                let [a, b, c] = m.triangle(t);
                for (p, q) in [(a, b), (b, c), (c, a)] {
                    let (p, q) = (key(p), key(q));
                    *edges.entry((p.min(q), p.max(q))).or_default() += 1;
                }
            }
            !edges.is_empty() && edges.values().all(|&n| n == 2)
        })
        .collect()
}

/// How a final gather samples each point.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct GatherSettings {
    /// Shadow rays per point over all emitters, each emitter getting a stratified k x k grid
    /// with k^2 about its share of the emitted power times this (at least 1 x 1).
    #[default(64)]
    pub shadow_rays: u32,
    /// Gather rays of the first batch (at least 1); each further batch doubles the count.
    #[default(64)]
    pub min_rays: u32,
    /// Most gather rays for one point (at least `min_rays`).
    #[default(256)]
    pub max_rays: u32,
    /// A point stops adding gather rays once the standard error of its indirect luminance is
    /// at most this fraction of its total luminance (0: always `max_rays`).
    #[default(0.02)]
    pub target_error: f32,
    /// Most mirror and glass bounces a gather ray follows.
    #[default(8)]
    pub max_depth: u32,
    /// Hits closer than this (scene units) take one more bounce instead of the solution's
    /// value: a shadow ray from the hit and one more cosine-distributed ray that reads the
    /// solution (or, landing this near again, bounces again: [`NEAR_BOUNCES`] in all). Near
    /// the point, an element of the solution fills much of the hemisphere and its error would
    /// reach the point whole (a concave corner, a contact); farther away the
    /// same error is averaged over many elements. `None`: the scene's bounding-box diagonal
    /// over [`NEAR_PER_DIAGONAL`] (the radiosity pass's default element edge); 0: never.
    #[default(None)]
    pub near_distance: Option<f32>,
    /// Seed of every point's random sequence (and of the caustic photons').
    #[default(0)]
    pub seed: u64,
    /// Caustic photons for the light that reaches a point through mirrors and glass (L S+ D),
    /// which gather rays find only by chance when the emitter is small; `None`: gather rays
    /// alone. Built only for scenes with an emitter and a mirror or glass.
    #[default(Some(PhotonSettings::default()))]
    pub photons: Option<PhotonSettings>,
}

/// Most bounces a near hit takes before reading the solution ([`GatherSettings::near_distance`]):
/// each further one multiplies the solution's error there by a reflectance and the share of
/// near landings, so a few leave a contact's error far below the gather's noise.
pub const NEAR_BOUNCES: u32 = 4;

/// The default [`GatherSettings::near_distance`] is the scene's diagonal over this: the
/// default element edge of the radiosity pass, the scale of the solution's blockiness.
pub const NEAR_PER_DIAGONAL: f32 = 24.0;

/// The final gather over one solution of one scene.
pub struct Gatherer<'a> {
    scene: &'a Scene,
    solution: &'a dyn DiffuseRadiance,
    lights: Lights,
    /// Shadow-ray grid side per emitter.
    grids: Vec<u32>,
    /// Emitter choice by power, for the one shadow ray of a near hit's extra bounce.
    choice: EmitterChoice,
    /// Samples per axis of the sky's sun and dome grids per point (about the square root of
    /// [`GatherSettings::shadow_rays`]).
    sky_grid: u32,
    /// Hits closer than this take one more bounce (scene units).
    near: f32,
    /// Past this instant, points take the solution's value instead of a gather (a time budget).
    deadline: Option<Instant>,
    /// Points that took the solution's value because the deadline had passed.
    late: AtomicU64,
    /// Per object: whether its surface is closed (every edge, by position, shared by exactly
    /// two of its triangles), so that only a point inside it can see its back.
    closed: Vec<bool>,
    /// The caustic photons, for the per-pixel gather's points seen through mirrors and glass.
    caustics: Option<CausticPhotons>,
    settings: GatherSettings,
}

impl std::fmt::Debug for Gatherer<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gatherer")
            .field("grids", &self.grids)
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

impl<'a> Gatherer<'a> {
    /// A gather over `solution` (which supplies the radiance where gather rays land) on
    /// `scene`.
    pub fn new(
        scene: &'a Scene,
        solution: &'a dyn DiffuseRadiance,
        settings: GatherSettings,
    ) -> Self {
        let powers: Vec<f64> = scene
            .emitters
            .iter()
            .map(|e| f64::from(luminance(e.power)).max(0.0))
            .collect();
        let total: f64 = powers.iter().sum();
        let n = powers.len().max(1) as f64;
        let grids = powers
            .iter()
            .map(|&p| {
                let share = if total > 0.0 { p / total } else { 1.0 / n };
                let k = (share * f64::from(settings.shadow_rays)).sqrt().round();
                (k as u32).max(1)
            })
            .collect();
        Self {
            scene,
            solution,
            lights: Lights::new(scene),
            grids,
            choice: EmitterChoice::new(scene),
            sky_grid: (f64::from(settings.shadow_rays).sqrt().round() as u32).max(1),
            near: settings
                .near_distance
                .unwrap_or(scene.bounds.diagonal() / NEAR_PER_DIAGONAL)
                .max(0.0),
            closed: closed_objects(scene),
            caustics: settings.photons.and_then(|p| {
                CausticPhotons::build(
                    scene,
                    PhotonSettings {
                        seed: settings.seed,
                        ..p
                    },
                )
            }),
            deadline: None,
            late: AtomicU64::new(0),
            settings: GatherSettings {
                min_rays: settings.min_rays.max(1),
                max_rays: settings.max_rays.max(settings.min_rays.max(1)),
                ..settings
            },
        }
    }

    /// The same gather, ending at `deadline`: a point estimated after it takes the solution's
    /// value there (split into its parts as the solution splits it) instead of a gather, so a
    /// bake keeps its time budget and its output stays complete ([`Gatherer::late_points`]
    /// counts them). The result then depends on the machine's speed.
    pub fn with_deadline(mut self, deadline: Instant) -> Self {
        self.deadline = Some(deadline);
        self
    }

    /// Caustic photons the gather estimates the light through mirrors and glass from (0:
    /// none).
    pub fn caustic_photons(&self) -> usize {
        self.caustics.as_ref().map_or(0, CausticPhotons::len)
    }

    /// Whether the gather has caustic photons.
    pub fn has_caustic_photons(&self) -> bool {
        self.caustics.is_some()
    }

    /// The diffusely reflected caustic at the shading point `s` from the photons for a
    /// diffuse reflectance `rho`, rho / pi E, W/(m^2 sr): zero without photons, on a back face
    /// or on a surface without a diffuse part. The gather rays at `s` must then leave out the
    /// emission they reach through delta paths (`caustics_elsewhere`), which is this light.
    pub(crate) fn caustic_radiance(&self, s: &Shading, rho: Rgb) -> Rgb {
        match &self.caustics {
            Some(photons) if s.hit.front_face && s.material.reflects_diffusely() => {
                rho * photons.irradiance(s.hit.point.position, s.hit.point.normal)
                    * std::f32::consts::FRAC_1_PI
            }
            _ => Rgb::ZERO,
        }
    }

    /// Points that took the solution's value because the deadline had passed.
    pub fn late_points(&self) -> u64 {
        self.late.load(Ordering::Relaxed)
    }

    /// The settings in force (counts raised to their floors).
    pub fn settings(&self) -> GatherSettings {
        self.settings
    }

    /// The diffusely reflected indirect light at the shading point `s` (rho times the mean
    /// radiance its gather rays bring, W/(m^2 sr); zero on a back face or a surface without a
    /// diffuse part) from `rays` gather rays of one camera sample: the per-pixel gather of the
    /// hybrid ([`crate::hybrid::gathered`]). The rays are [`RadianceEstimator::estimate`]'s
    /// (near hits take one more bounce, delta paths are followed), their numbers forked from
    /// the camera sample's `sampler` at `site` ([`Sampler::fork`]) so that a pixel's rays over
    /// all its samples are stratified together. With `caustics_elsewhere`, the emission reached
    /// through mirrors and glass is left to the light tracer.
    pub(crate) fn indirect_per_sample(
        &self,
        s: &Shading,
        rays: u32,
        caustics_elsewhere: bool,
        (sampler, site): (&Sampler, u64),
        tally: &mut Tally,
    ) -> Rgb {
        if !s.hit.front_face || !s.material.reflects_diffusely() || rays == 0 {
            return Rgb::ZERO;
        }
        let mut sum = Rgb::ZERO;
        for j in 0..rays {
            let mut fork = sampler.fork(site, j, rays);
            let u = fork.next_2d();
            let (l, _) = self.gather_ray(s, u, caustics_elsewhere, &mut fork, tally);
            if l.is_finite() {
                sum += l;
            }
        }
        s.material.diffuse_albedo() * sum / rays as f32
    }

    /// The shading context of a point on the front of triangle `t`, seen along its shading
    /// normal.
    fn shading_at(&self, t: u32, b: [f32; 3]) -> Shading {
        let hit = self.scene.surface_hit(t, b);
        Shading::new(self.scene, hit, -hit.shading_normal)
    }

    /// Radiance arriving along one gather ray leaving `s` in the cosine-distributed
    /// direction of `u` (the direct part excluded), W/(m^2 sr), and what the ray hit first.
    /// With `caustics_elsewhere`, the emission reached through a delta path is left out: a
    /// light tracer counts that light at this point
    /// ([`crate::light_tracing::CausticScope::FirstDiffuse`]).
    fn gather_ray(
        &self,
        s: &Shading,
        u: Vec2,
        caustics_elsewhere: bool,
        sampler: &mut Sampler,
        tally: &mut Tally,
    ) -> (Rgb, FirstHit) {
        let scene = self.scene;
        let dir = cosine_direction(s.hit.shading_normal, u);
        if dir.dot(s.hit.point.normal) <= 0.0 {
            return (Rgb::ZERO, FirstHit::Nothing);
        }
        tally.rays += 1;
        let origin = s.hit.point.spawn_origin(dir);
        let Some(h) = scene.accel().closest(origin, dir, f32::INFINITY) else {
            return (Rgb::ZERO, FirstHit::Nothing);
        };
        // Most rays land on a surface without a delta lobe: read the solution there without
        // building the full hit (shading normal, error bounds, frame).
        let object = scene.mesh.object_of(h.triangle) as usize;
        let material = &scene.materials[scene.objects[object].material as usize].material;
        if material.delta().is_none() {
            let front = dir.dot(scene.mesh.geometric_normal(h.triangle)) < 0.0;
            if !front {
                let first = if self.closed[object] {
                    FirstHit::Back
                } else {
                    FirstHit::Front
                };
                return (Rgb::ZERO, first);
            }
            if h.t < self.near && material.reflects_diffusely() {
                return (
                    self.near_bounce(h.triangle, h.barycentric, dir, sampler, tally),
                    FirstHit::Front,
                );
            }
            let solved = self.solution.radiance(h.triangle, h.barycentric);
            let l = (solved - scene.objects[object].emission).max(Rgb::ZERO);
            return (l, FirstHit::Front);
        }
        // A mirror or glass: the same query again, with the full hit to continue from.
        let Some(hit) = scene.intersect_from(&s.hit.point, dir) else {
            return (Rgb::ZERO, FirstHit::Nothing);
        };
        let here = Shading::new(scene, hit, dir);
        let first = if here.hit.front_face
            || here.is_dielectric()
            || !self.closed[here.hit.object as usize]
        {
            FirstHit::Front
        } else {
            FirstHit::Back
        };
        // The first landing: the shadow rays counted its emission.
        let mut l = Rgb::ZERO;
        if here.hit.front_face {
            let solved = self
                .solution
                .radiance(here.hit.point.triangle, here.hit.barycentric);
            l = (solved - here.emitted).max(Rgb::ZERO);
        }
        if let Some(lobe) = here.material.delta()
            && self.settings.max_depth > 0
            && here.scatters()
            && let Some(bs) = lobe.sample(here.wo, sampler.next_2d())
        {
            let next = here.frame.to_world(bs.wi).normalize();
            tally.rays += 1;
            if let Some(h) = scene.intersect_from(&here.hit.point, next) {
                l += bs.weight * self.follow(h, next, caustics_elsewhere, sampler, tally);
            } else if !caustics_elsewhere {
                // The sky through mirrors and glass (L S+ D): no shadow ray passes them, and
                // with `caustics_elsewhere` the photons or the light tracer count it.
                l += bs.weight * crate::sky::escaped(scene, next);
            }
        }
        (l, first)
    }

    /// The diffuse light a near hit (triangle `t` at `b`, reached along `dir`) reflects
    /// toward the point, without its emission (the point's shadow rays counted that) and
    /// estimated by one more bounce: one shadow ray to an emitter chosen by power, and one
    /// cosine-distributed ray whose landing gives the solution's radiance less its emission.
    /// A landing of that ray near the hit in turn takes one more bounce, up to
    /// [`NEAR_BOUNCES`] in all: in a contact or a concave corner the surfaces facing each
    /// other near the point are where the solution errs most (a contact's leak).
    fn near_bounce(
        &self,
        t: u32,
        b: [f32; 3],
        dir: Vec3,
        sampler: &mut Sampler,
        tally: &mut Tally,
    ) -> Rgb {
        let scene = self.scene;
        let (mut t, mut b, mut dir) = (t, b, dir);
        // The product of the reflectances of the bounces so far, and the radiance gathered.
        let (mut weight, mut sum) = (Rgb::ONE, Rgb::ZERO);
        for level in 1..=NEAR_BOUNCES {
            let hit = scene.surface_hit(t, b);
            let (point, normal) = (hit.point, hit.shading_normal);
            let here = Shading::new(scene, hit, dir);
            weight *= here.material.diffuse_albedo();
            if !self.choice.is_empty() {
                let light = self.choice.pick(sampler.next_f32());
                let p = self.choice.probability_of(light);
                if p > 0.0 {
                    let irradiance = match light {
                        Light::Area(e) => {
                            irradiance_from(scene, &self.lights, &here, e, 1, sampler, tally)
                        }
                        Light::Lamp(l) => lamp_irradiance(scene, &here, l, tally),
                    } / p;
                    sum += weight * irradiance * std::f32::consts::FRAC_1_PI;
                }
            }
            if scene.sky.is_some() {
                let e = crate::sky::sky_irradiance(scene, &here, 1, sampler, tally);
                sum += weight * e * std::f32::consts::FRAC_1_PI;
            }
            let bounce = cosine_direction(normal, sampler.next_2d());
            if bounce.dot(point.normal) <= 0.0 {
                break;
            }
            tally.rays += 1;
            let origin = point.spawn_origin(bounce);
            let Some(h) = scene.accel().closest(origin, bounce, f32::INFINITY) else {
                break;
            };
            if bounce.dot(scene.mesh.geometric_normal(h.triangle)) >= 0.0 {
                break;
            }
            let landed = scene.mesh.object_of(h.triangle) as usize;
            let material = &scene.materials[scene.objects[landed].material as usize].material;
            if h.t < self.near
                && level < NEAR_BOUNCES
                && material.delta().is_none()
                && material.reflects_diffusely()
            {
                (t, b, dir) = (h.triangle, h.barycentric, bounce);
                continue;
            }
            // Under cosine sampling the reflected radiance is rho times the landing's.
            let solved = self.solution.radiance(h.triangle, h.barycentric);
            sum += weight * (solved - scene.objects[landed].emission).max(Rgb::ZERO);
            break;
        }
        sum
    }

    /// Radiance arriving along a delta path from its hit `hit` (reached along `dir`, one delta
    /// bounce in), W/(m^2 sr): the solution where it ends, emission included unless
    /// `caustics_elsewhere` (a light tracer counts it).
    fn follow(
        &self,
        hit: Hit,
        dir: Vec3,
        caustics_elsewhere: bool,
        sampler: &mut Sampler,
        tally: &mut Tally,
    ) -> Rgb {
        let scene = self.scene;
        let (mut hit, mut dir, mut depth, mut throughput) = (hit, dir, 1, Rgb::ONE);
        let mut sum = Rgb::ZERO;
        loop {
            let here = Shading::new(scene, hit, dir);
            if here.hit.front_face {
                let mut l = self
                    .solution
                    .radiance(here.hit.point.triangle, here.hit.barycentric);
                if caustics_elsewhere {
                    l = (l - here.emitted).max(Rgb::ZERO);
                }
                sum += throughput * l;
            }
            let Some(lobe) = here.material.delta() else {
                return sum;
            };
            if depth >= self.settings.max_depth || !here.scatters() {
                return sum;
            }
            let Some(bs) = lobe.sample(here.wo, sampler.next_2d()) else {
                return sum;
            };
            let next = here.frame.to_world(bs.wi).normalize();
            tally.rays += 1;
            throughput *= bs.weight;
            let Some(h) = scene.intersect_from(&here.hit.point, next) else {
                // The sky at the delta path's end is emission too.
                if caustics_elsewhere {
                    return sum;
                }
                return sum + throughput * crate::sky::escaped(scene, next);
            };
            if throughput.max_element() <= 0.0 {
                return sum;
            }
            hit = h;
            dir = next;
            depth += 1;
        }
    }
}

impl RadianceEstimator for Gatherer<'_> {
    fn estimate(&self, triangle: u32, barycentric: [f32; 3], key: u64) -> RadianceEstimate {
        let (min_rays, max_rays) = (self.settings.min_rays, self.settings.max_rays);
        self.estimate_with(triangle, barycentric, key, min_rays, max_rays)
    }
}

impl Gatherer<'_> {
    /// [`RadianceEstimator::estimate`] with the gather rays' first batch and cap given.
    pub(super) fn estimate_with(
        &self,
        triangle: u32,
        barycentric: [f32; 3],
        key: u64,
        min_rays: u32,
        max_rays: u32,
    ) -> RadianceEstimate {
        if self.deadline.is_some_and(|d| Instant::now() >= d) {
            self.late.fetch_add(1, Ordering::Relaxed);
            let object = self.scene.mesh.object_of(triangle);
            let emitted = self.scene.objects[object as usize].emission;
            let total = self.solution.radiance(triangle, barycentric);
            let indirect = self.solution.indirect_radiance(triangle, barycentric);
            // The solution's light holds the texture's mean over its elements: taken out
            // again, as the estimate's caller puts the texture's value back.
            let tint = self.scene.albedo_tint(triangle, barycentric);
            let untint = |v: Rgb| {
                Rgb::from_array(std::array::from_fn(|c| {
                    if tint[c] > 0.0 { v[c] / tint[c] } else { 0.0 }
                }))
            };
            return RadianceEstimate {
                emitted,
                direct: untint((total - indirect - emitted).max(Rgb::ZERO)),
                indirect: untint(indirect),
                ..RadianceEstimate::default()
            };
        }
        let s = self.shading_at(triangle, barycentric);
        let mut tally = Tally::default();
        // The material's own reflectance (a texture's factor): the caller tints the estimate
        // with the texture's value at the point (`RadianceEstimate::tinted`), and an
        // irradiance lightmap divides this back out.
        let material = self.scene.material_of(triangle);
        let rho = material.diffuse_albedo();
        let emitted = s.emitted;
        if !material.reflects_diffusely() {
            return RadianceEstimate {
                emitted,
                ..RadianceEstimate::default()
            };
        }
        // Direct irradiance E (W/m^2): the BRDF slot carries 1, so the estimator's sum is E.
        let mut direct_sampler = Sampler::new(self.settings.seed ^ DIRECT_STREAM, key, 0);
        let mut irradiance = Rgb::ZERO;
        for (e, &k) in self.grids.iter().enumerate() {
            irradiance += irradiance_from(
                self.scene,
                &self.lights,
                &s,
                e,
                k,
                &mut direct_sampler,
                &mut tally,
            );
        }
        irradiance += lamps_irradiance(self.scene, &s, &mut tally);
        if self.scene.sky.is_some() {
            let key = twopass_brdf::random::hash(self.settings.seed ^ SKY_STREAM ^ key);
            let mut rays = 0;
            irradiance += self.scene.sky_irradiance(
                &s.hit.point,
                s.hit.shading_normal,
                key,
                self.sky_grid,
                &mut rays,
            );
            tally.shadow_rays += rays;
        }
        let direct = rho * irradiance * std::f32::consts::FRAC_1_PI;

        // Indirect: cosine-weighted gather rays, E = pi mean(L), so rho / pi E = rho mean(L);
        // with caustic photons, the gather rays leave out the emission they reach through
        // mirrors and glass and the photons give that light.
        let photons = self.has_caustic_photons();
        let caustic = self.caustic_radiance(&s, rho);
        let (mut sum, mut sum_y, mut sum_y2) = (Rgb::ZERO, 0.0f64, 0.0f64);
        let mut n = 0u32;
        let (mut hits, mut backs) = (0u32, 0u32);
        let mut batch = min_rays;
        loop {
            for i in n..n + batch {
                let mut sampler = Sampler::new(self.settings.seed, key, u64::from(i));
                let u = sampler.next_2d();
                let (l, first) = self.gather_ray(&s, u, photons, &mut sampler, &mut tally);
                hits += u32::from(first != FirstHit::Nothing);
                backs += u32::from(first == FirstHit::Back);
                if !l.is_finite() {
                    continue;
                }
                sum += l;
                let y = f64::from(luminance(rho * l));
                sum_y += y;
                sum_y2 += y * y;
            }
            n += batch;
            let mean = sum_y / f64::from(n);
            let variance = (sum_y2 / f64::from(n) - mean * mean).max(0.0) / f64::from(n.max(2) - 1);
            let error = variance.sqrt();
            let total = mean + f64::from(luminance(direct + emitted + caustic));
            if n >= max_rays || error <= f64::from(self.settings.target_error) * total {
                let indirect = rho * sum / n as f32 + caustic;
                return RadianceEstimate {
                    emitted,
                    direct,
                    indirect,
                    indirect_error: error as f32,
                    back_faces: if hits > 0 {
                        backs as f32 / hits as f32
                    } else {
                        0.0
                    },
                    rays: tally.rays,
                    shadow_rays: tally.shadow_rays,
                };
            }
            batch = n.min(max_rays - n);
        }
    }
}
