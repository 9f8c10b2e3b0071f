//! Light tracing of caustics: paths that leave an emitter, go through at least one mirror or
//! glass surface (delta lobes), and are connected to the camera at a diffuse or glossy vertex.
//! In Heckbert's notation from the light: L S+ D E, and with [`CausticScope::All`] also every
//! longer path L S+ (D|G|S)* (D|G) E. Tracing these from the camera is hopeless for a small
//! light (a camera path must hit the emitter through the specular chain by chance); from the
//! light they are found directly, which is what the reference path tracer and the hybrid's
//! per-pixel caustics need (Chen et al. 1991; Veach 1997, section 10.2).
//!
//! **Splitting the work without double counting.** Each light path is counted by exactly one
//! strategy:
//! - [`CausticScope::All`] (the reference): the path tracer ([`crate::Reference`] with
//!   [`crate::reference::Caustics::LightTracing`]) drops every path whose first vertex seen
//!   from the camera is not a delta surface and whose last bounce before the emitter is a delta
//!   one; the light tracer counts exactly those, connecting each light path to the camera at
//!   every diffuse or glossy vertex after its first delta bounce. The union is every path once.
//! - [`CausticScope::Focused`] (the hybrid): only the paths whose delta chain holds a
//!   refraction, connected at their first diffuse vertex with its diffuse reflectance: the light
//!   the radiosity pass deposits on its elements blurred by their size (the focus under a glass
//!   sphere). The classic hybrids show the solution less that part there
//!   ([`twopass_scene::DiffuseRadiance::focused_caustic_radiance`]), the gathered hybrid
//!   leaves out the emission its gather rays reach through a refraction there
//!   ([`crate::gather`]), and the light tracer's value takes its place.
//! - [`CausticScope::FirstDiffuse`] (the gathered hybrid): as `Focused` for every delta chain,
//!   mirrors too; the gathered hybrid's gather rays at the surface the camera sees leave out
//!   the emission they reach through any delta path.
//!
//! **Estimator.** A light path starts at a point of an emitter chosen by power, uniform over
//! its area, in a direction drawn from the cones its specular objects subtend
//! ([`twopass_scene::SpecularTargets`]; a direction outside every cone cannot reach a specular
//! surface first), with throughput L_e cos(theta_e) A / (P(emitter) p(direction)); or at a
//! point or spot lamp chosen by power, with throughput I(w) / (P(lamp) p(direction)); or, from
//! a directional lamp, outside the scene on a line through a point of the beam's cross-section
//! drawn toward the specular objects, with throughput E / (P(lamp) p(area)); or from the sky,
//! as from a directional lamp in a direction drawn from the sun or the dome, with throughput
//! L(w) / (P(sky) p(w) p(area)). Delta
//! bounces carry power ([`twopass_brdf::delta::DeltaLobe::sample_flux`]). At a vertex x
//! connected to the camera the pixel j that sees x gains
//! beta f(x) |cos(theta_x)| / d^2 * W_j, with W_j = 1 / (A_pixel cos^3(theta_c)) the importance
//! of a pinhole camera's pixel for the box filter the render loop uses (A_pixel: the pixel's
//! area on the image plane at unit distance), the sum over N paths divided by N. Shading normals
//! get Veach's adjoint correction. The result is unbiased; it is a pixel's mean radiance, in
//! W/(m^2 sr), like the camera passes'.
//!
//! **Determinism.** Path i draws from the stream keyed by (seed, i); paths are traced in fixed
//! chunks and their splats added chunk by chunk in order, so the image does not depend on the
//! thread count.
//!
//! | setting | unit | default | meaning |
//! | --- | --- | --- | --- |
//! | `paths` | light paths per camera sample | 1 | N = this x spp x pixels, or planned per render |
//! | `max_depth` | bounces | 64 | longest light path |
//! | `roulette_depth` | bounces | 3 | Russian roulette from this bounce on |

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use twopass_brdf::Rgb;
use twopass_brdf::frame::Frame;
use twopass_scene::{Camera, Hit, LampKind, Ray, Scene, Sky, SpecularTargets};

use crate::counters::{RenderProgress, Tally};
use crate::emitters::{EmitterChoice, Light};
use crate::film::{Layer, LayerImages};
use crate::sampler::Sampler;

/// Which light paths the light tracer counts (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CausticScope {
    /// Every path through at least one delta bounce from the emitter, connected at every
    /// diffuse or glossy vertex: the reference's half of the path space.
    All,
    /// Paths whose delta chain holds a refraction, connected at their first diffuse vertex
    /// with its diffuse reflectance only: the classic hybrids' per-pixel caustics.
    Focused,
    /// Every path through at least one delta bounce, connected at its first diffuse vertex
    /// with its diffuse reflectance only: the gathered hybrid's per-pixel caustics (its gather
    /// rays would find the light a mirror or glass sends onto the point only by chance).
    FirstDiffuse,
}

/// How many light paths a render's light tracing pass traces.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightPaths {
    /// This many per camera sample: a render of `spp` samples over `pixels` pixels traces
    /// `ceil(per_sample * spp * pixels)` paths.
    PerSample(f32),
    /// As many per camera sample as a pilot of both passes measures to give the least error
    /// for the time ([`crate::light_plan`]), decided anew by each render.
    Planned,
}

/// Settings of the light tracer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightTracingSettings {
    /// How many light paths a render traces.
    pub paths: LightPaths,
    /// Which paths count.
    pub scope: CausticScope,
    /// Longest light path, in bounces.
    pub max_depth: u32,
    /// Bounce from which Russian roulette may end a path (on its throughput relative to its
    /// start, capped at 1).
    pub roulette_depth: u32,
}

impl LightTracingSettings {
    /// The defaults for `scope`: one light path per camera sample, 64 bounces, roulette from
    /// the third.
    pub fn new(scope: CausticScope) -> Self {
        Self {
            paths: LightPaths::PerSample(1.0),
            scope,
            max_depth: 64,
            roulette_depth: 3,
        }
    }
}

/// Light paths per parallel job; the splats of a job are added to the image in job order.
const CHUNK: u64 = 4096;
/// Jobs whose splats are held in memory at once before they are added.
const BATCH: u64 = 64;
/// Mixed into the render's seed, so light paths never share a stream with camera samples.
const LIGHT_SEED_MIX: u64 = 0x6c69_6768_7470_6174;

/// What a light tracing pass produced.
#[derive(Debug, Clone)]
pub struct LightImage {
    /// Per layer, the pixels' mean radiance from the light paths, W/(m^2 sr).
    pub layers: LayerImages,
    /// Light paths traced.
    pub paths: u64,
    /// Rays counted like the render's.
    pub tally: Tally,
    /// Splats dropped because a value was not finite.
    pub non_finite: u64,
}

/// A light tracer for one scene: the emitter choice and the specular targets.
#[derive(Debug, Clone)]
pub struct LightTracer {
    settings: LightTracingSettings,
    targets: SpecularTargets,
    choice: EmitterChoice,
    /// Probability that a path starts at the sky (its power, [`twopass_scene::Sky::power`],
    /// over the sky's, the emitters' and the lamps' together); the rest start at a light of
    /// `choice`.
    sky_share: f32,
}

/// One splat: pixel index (row-major), layer, value (radiance times the number of paths).
pub type Splat = (u32, Layer, Rgb);

/// The chunks of `paths` light paths: the unit in which paths are traced and their splats
/// added in order, so a range of chunks is a share of the pass that any process can trace.
pub fn light_chunks(paths: u64) -> u64 {
    paths.div_ceil(CHUNK)
}

/// Adds `splats` (in path order) to `layers`, counting the non-finite ones in `non_finite`
/// instead: the one sum of a light tracing pass, whether its chunks were traced here or in
/// other processes.
pub fn add_splats(layers: &mut LayerImages, splats: &[Splat], non_finite: &mut u64) {
    for &(pixel, layer, value) in splats {
        if value.is_finite() {
            layers.images[layer.index()].pixels_mut()[pixel as usize] += value;
        } else {
            *non_finite += 1;
        }
    }
}

/// Divides the summed splats of `paths` light paths by `paths`: each pixel's mean radiance.
/// A value that overflowed is zeroed and counted in `non_finite`.
pub fn finish_splats(layers: &mut LayerImages, paths: u64, non_finite: &mut u64) {
    let scale = if paths > 0 { 1.0 / paths as f32 } else { 0.0 };
    for img in &mut layers.images {
        for p in img.pixels_mut() {
            *p *= scale;
            if !p.is_finite() {
                *p = Rgb::ZERO;
                *non_finite += 1;
            }
        }
    }
}

impl LightTracer {
    /// The light tracer of `scene`, or `None` when it has nothing to do: no emitter, lamp or
    /// sky, or no specular object (then no path of its scope exists).
    pub fn new(scene: &Scene, settings: LightTracingSettings) -> Option<Self> {
        let targets = SpecularTargets::new(scene);
        let choice = EmitterChoice::new(scene);
        if targets.is_empty() || (choice.is_empty() && scene.sky.is_none()) {
            return None;
        }
        // Powers by the mean over the channels, as the emitter choice weighs them.
        let mean = |p: Rgb| f64::from(p.element_sum() / 3.0).max(0.0);
        let diagonal = scene.bounds.diagonal();
        let sky = scene.sky.as_ref().map_or(0.0, |s| mean(s.power(diagonal)));
        let lights: f64 = scene.emitters.iter().map(|e| mean(e.power)).sum::<f64>()
            + scene
                .lamps
                .iter()
                .map(|l| mean(l.power(diagonal)))
                .sum::<f64>();
        let sky_share = if scene.sky.is_none() {
            0.0
        } else if choice.is_empty() || (sky + lights).is_nan() || sky + lights <= 0.0 {
            1.0
        } else {
            (sky / (sky + lights)) as f32
        };
        Some(Self {
            settings,
            targets,
            choice,
            sky_share,
        })
    }

    /// The settings.
    pub fn settings(&self) -> LightTracingSettings {
        self.settings
    }

    /// Light paths a render of `samples` camera samples in all traces at `per_sample` light
    /// paths per camera sample (its [`LightPaths::PerSample`], or what a plan picked).
    pub fn paths_for_samples(samples: u64, per_sample: f32) -> u64 {
        let n = f64::from(per_sample) * samples as f64;
        if n.is_finite() {
            n.ceil().max(0.0) as u64
        } else {
            0
        }
    }

    /// Traces `paths` light paths with streams keyed by `seed` and returns each pixel's mean
    /// radiance from them. `progress` advances by `progress_units` over the pass. Runs on the
    /// current rayon pool; the result does not depend on its thread count.
    pub fn trace(
        &self,
        scene: &Scene,
        camera: &Camera,
        paths: u64,
        seed: u64,
        progress: &RenderProgress,
        progress_units: u64,
    ) -> LightImage {
        let mut layers = LayerImages::new(camera.width, camera.height);
        let mut tally = Tally::default();
        let mut non_finite = 0;
        let all = 0..light_chunks(paths);
        self.trace_chunks(
            scene,
            camera,
            paths,
            seed,
            all,
            progress,
            progress_units,
            |s, t| {
                tally.add(t);
                add_splats(&mut layers, &s, &mut non_finite);
            },
        );
        finish_splats(&mut layers, paths, &mut non_finite);
        LightImage {
            layers,
            paths,
            tally,
            non_finite,
        }
    }

    /// The splats of chunks `chunks` (see [`light_chunks`]) of a pass of `paths` light paths,
    /// in path order, and their rays: one process's share of [`LightTracer::trace`], which
    /// [`add_splats`] over every share in chunk order, then [`finish_splats`], turn into the
    /// pass's image bit for bit.
    #[allow(clippy::too_many_arguments)]
    pub fn trace_share(
        &self,
        scene: &Scene,
        camera: &Camera,
        paths: u64,
        seed: u64,
        chunks: std::ops::Range<u64>,
        progress: &RenderProgress,
        progress_units: u64,
    ) -> (Vec<Splat>, Tally) {
        let mut all = Vec::new();
        let mut tally = Tally::default();
        self.trace_chunks(
            scene,
            camera,
            paths,
            seed,
            chunks,
            progress,
            progress_units,
            |s, t| {
                tally.add(t);
                all.extend(s);
            },
        );
        (all, tally)
    }

    /// Traces the paths of `chunks` batch by batch, handing each chunk's splats (in path
    /// order) and rays to `sink` in chunk order.
    #[allow(clippy::too_many_arguments)]
    fn trace_chunks(
        &self,
        scene: &Scene,
        camera: &Camera,
        paths: u64,
        seed: u64,
        chunks: std::ops::Range<u64>,
        progress: &RenderProgress,
        progress_units: u64,
        mut sink: impl FnMut(Vec<Splat>, Tally),
    ) {
        let seed = seed ^ LIGHT_SEED_MIX;
        let view = PixelImportance::new(camera);
        let count = chunks.end.saturating_sub(chunks.start);
        let mut done_units = 0;
        let mut first = chunks.start;
        while first < chunks.end {
            let last = (first + BATCH).min(chunks.end);
            let results: Vec<(Vec<Splat>, Tally)> = (first..last)
                .into_par_iter()
                .map(|c| {
                    let mut splats = Vec::new();
                    let mut tally = Tally::default();
                    for i in c * CHUNK..((c + 1) * CHUNK).min(paths) {
                        let mut sampler = Sampler::new(seed, i, 0);
                        self.path(scene, &view, &mut sampler, &mut tally, &mut splats);
                    }
                    (splats, tally)
                })
                .collect();
            for (splats, t) in results {
                sink(splats, t);
            }
            let units = progress_units * (last - chunks.start) / count.max(1);
            progress.add_done(units - done_units);
            done_units = units;
            first = last;
        }
    }

    /// The first segment of a light path from a light chosen by power: a point of an area
    /// emitter, uniform over its area, or a point or spot lamp's position, and a direction
    /// toward the specular targets. Returns what the ray hit (if anything), its direction, and
    /// the path's throughput there, W: the flux one path carries (divided by the number of
    /// paths, the estimator's): L_e cos(theta_e) A / (P(emitter) p(direction)) from an area,
    /// I(w) / (P(lamp) p(direction)) from a lamp (a lamp sends I(w) dw as an area sends
    /// L cos dA), E / (P(lamp) p(A)) from a directional lamp (a point across its beam drawn
    /// toward the targets, [`SpecularTargets::parallel`]). `None` for a direction the light
    /// does not send light into.
    pub(crate) fn emit(
        &self,
        scene: &Scene,
        sampler: &mut Sampler,
        tally: &mut Tally,
    ) -> Option<(Option<Hit>, Vec3, Rgb)> {
        let u = sampler.next_f32();
        if u < self.sky_share {
            let sky = scene.sky.as_ref()?;
            // The number an area emitter's point takes, so that the direction and the point
            // take the same dimensions of the stream as a lamp's.
            sampler.next_f32();
            let (ray, start) = emit_from_sky(
                scene,
                sky,
                &self.targets,
                u / self.sky_share,
                sampler.next_2d(),
                sampler.next_2d(),
            )?;
            tally.rays += 1;
            return Some((scene.intersect(&ray), ray.direction, start / self.sky_share));
        }
        let u = ((u - self.sky_share) / (1.0 - self.sky_share)).min(1.0 - f32::EPSILON / 2.0);
        let light = self.choice.pick(u);
        let chosen = self.choice.probability_of(light) * (1.0 - self.sky_share);
        let (hit, dir, start) = match light {
            Light::Area(e) => {
                let emitter = &scene.emitters[e];
                let y = emitter.sample(scene, sampler.next_f32(), sampler.next_2d());
                let (dir, pdf) = self
                    .targets
                    .direction(y.position.as_dvec3(), sampler.next_2d())?;
                let dir = dir.as_vec3().normalize();
                let cos_e = dir.dot(y.normal);
                if cos_e <= 0.0 || pdf <= 0.0 {
                    return None;
                }
                let start = emitter.radiance * (cos_e * emitter.area / (chosen * pdf as f32));
                tally.rays += 1;
                (scene.intersect_from(&y, dir), dir, start)
            }
            Light::Lamp(l) => {
                let lamp = &scene.lamps[l];
                if let LampKind::Directional { direction } = lamp.kind {
                    sampler.next_f32();
                    let dir = direction.as_dvec3().normalize();
                    let (point, density) = self.targets.parallel(dir, sampler.next_2d())?;
                    if density <= 0.0 {
                        return None;
                    }
                    // E dA / p(A): the beam's power through the sampled point. The ray starts
                    // outside the scene's bounds, so whatever the beam meets first it meets.
                    let start = lamp.intensity / (chosen * density as f32);
                    let back = f64::from(scene.bounds.diagonal()) * 2.0;
                    let origin = (point - dir * back).as_vec3();
                    tally.rays += 1;
                    let dir = dir.as_vec3();
                    return (start.max_element() > 0.0)
                        .then(|| (scene.intersect(&Ray::new(origin, dir)), dir, start));
                }
                // The number an area emitter's point takes, drawn so that the direction
                // takes the same dimensions of the stream whichever light was picked.
                sampler.next_f32();
                let (dir, pdf) = self
                    .targets
                    .direction(lamp.position.as_dvec3(), sampler.next_2d())?;
                let dir = dir.as_vec3().normalize();
                if pdf <= 0.0 {
                    return None;
                }
                let start = lamp.intensity_toward(dir) / (chosen * pdf as f32);
                tally.rays += 1;
                (scene.intersect(&Ray::new(lamp.position, dir)), dir, start)
            }
        };
        (start.max_element() > 0.0).then_some((hit, dir, start))
    }

    /// One light path: its splats (radiance times the number of paths) go to `splats`.
    fn path(
        &self,
        scene: &Scene,
        view: &PixelImportance,
        sampler: &mut Sampler,
        tally: &mut Tally,
        splats: &mut Vec<Splat>,
    ) {
        let s = &self.settings;
        let Some((mut hit, mut dir, start)) = self.emit(scene, sampler, tally) else {
            return;
        };
        let mut beta = start;
        let mut bounces = 0u32;
        let mut refracted = false;
        while let Some(h) = hit {
            let material = scene.material_at(h.point.triangle, h.barycentric);
            let frame = Frame::from_normal(h.shading_normal);
            let wo = frame.to_local(-dir);
            if let Some(lobe) = material.delta() {
                if bounces >= s.max_depth {
                    return;
                }
                let Some(b) = lobe.sample_flux(wo, sampler.next_2d()) else {
                    return;
                };
                refracted |= b.kind == twopass_brdf::SampleKind::SpecularTransmission;
                beta *= b.weight;
                dir = frame.to_world(b.wi).normalize();
            } else {
                // The first vertex must be a delta one: every other path is the camera's.
                if bounces == 0 || !h.front_face {
                    return;
                }
                match s.scope {
                    CausticScope::Focused => {
                        if refracted {
                            self.connect(scene, view, &h, &frame, wo, beta, true, tally, splats);
                        }
                        return;
                    }
                    CausticScope::FirstDiffuse => {
                        self.connect(scene, view, &h, &frame, wo, beta, true, tally, splats);
                        return;
                    }
                    CausticScope::All => {
                        self.connect(scene, view, &h, &frame, wo, beta, false, tally, splats);
                    }
                }
                if bounces >= s.max_depth {
                    return;
                }
                // Continue with the adjoint BRDF: f(next, previous) with the shading normal
                // correction |wo.ns| |wi.ng| / |wo.ng| (Veach 1997, section 5.3).
                let Some(b) = material.sample(wo, sampler.next_2d()) else {
                    return;
                };
                let next = frame.to_world(b.wi).normalize();
                let ng = h.point.normal;
                let (cos_in_g, cos_out_g) = ((-dir).dot(ng), next.dot(ng));
                if cos_out_g <= 0.0 || cos_in_g <= 0.0 || b.pdf <= 0.0 {
                    return;
                }
                let f = material.eval(b.wi, wo);
                beta *= f * (wo.z.abs() * cos_out_g / (cos_in_g * b.pdf));
                dir = next;
            }
            bounces += 1;
            if bounces >= s.roulette_depth && !survives_roulette(&mut beta, start, sampler) {
                return;
            }
            tally.rays += 1;
            hit = scene.intersect_from(&h.point, dir);
        }
    }

    /// Connects vertex `h` (local frame `frame`, `wo` toward where the light came from) holding
    /// throughput `beta` to the camera; with `diffuse_only`, with its diffuse reflectance only.
    #[allow(clippy::too_many_arguments)]
    fn connect(
        &self,
        scene: &Scene,
        view: &PixelImportance,
        h: &Hit,
        frame: &Frame,
        wo: Vec3,
        beta: Rgb,
        diffuse_only: bool,
        tally: &mut Tally,
        splats: &mut Vec<Splat>,
    ) {
        let material = scene.material_at(h.point.triangle, h.barycentric);
        let x = &h.point;
        let to_cam = view.camera.position - x.position;
        let d2 = to_cam.length_squared();
        if d2.is_nan() || d2 <= 0.0 {
            return;
        }
        let wc = to_cam / d2.sqrt();
        let cos_cam_g = wc.dot(x.normal);
        if cos_cam_g <= 0.0 {
            return;
        }
        let Some((pixel, importance)) = view.pixel(-wc) else {
            return;
        };
        let wc_local = frame.to_local(wc);
        let f_d = material.eval_diffuse(wc_local, wo);
        let f_g = if diffuse_only {
            Rgb::ZERO
        } else {
            material.eval_non_diffuse(wc_local, wo)
        };
        if (f_d + f_g).max_element() <= 0.0 {
            return;
        }
        // |wi.ns| |wc.ng| / |wi.ng|: the cosine at x with the adjoint shading correction.
        let cos_in_g = frame.to_world(wo).dot(x.normal);
        if cos_in_g <= 0.0 {
            return;
        }
        let g = wo.z.abs() * cos_cam_g / (cos_in_g * d2) * importance;
        tally.shadow_rays += 1;
        if scene.occluded(x, view.camera.position) {
            return;
        }
        if f_d.max_element() > 0.0 {
            splats.push((pixel, Layer::Diffuse, beta * f_d * g));
        }
        if f_g.max_element() > 0.0 {
            splats.push((pixel, Layer::DirectSpecular, beta * f_g * g));
        }
    }
}

/// Russian roulette on a light path's throughput `beta` relative to its start `start`: the path
/// survives with probability min(1, max(beta) / max(start)), its throughput then divided by
/// that probability so the estimate stays unbiased. A NaN throughput ends the path.
pub(crate) fn survives_roulette(beta: &mut Rgb, start: Rgb, sampler: &mut Sampler) -> bool {
    let survive = (beta.max_element() / start.max_element()).min(1.0);
    if survive.is_nan() || sampler.next_f32() >= survive {
        return false;
    }
    *beta /= survive;
    true
}

/// Where a direction from the eye lands on the image, and the importance of that pixel.
struct PixelImportance {
    camera: Camera,
    /// Area of one pixel on the image plane at unit distance from the eye.
    pixel_area: f32,
}

impl PixelImportance {
    fn new(camera: &Camera) -> Self {
        let side = 2.0 * (camera.fov_y * 0.5).tan() / camera.height as f32;
        Self {
            camera: *camera,
            pixel_area: side * side,
        }
    }

    /// The pixel (row-major index) unit direction `dir` from the eye falls in, and its
    /// importance 1 / (A_pixel cos^3 theta), 1/sr.
    fn pixel(&self, dir: Vec3) -> Option<(u32, f32)> {
        let c = &self.camera;
        let p: Vec2 = c.project(dir)?;
        if !(p.x >= 0.0 && p.y >= 0.0 && p.x < c.width as f32 && p.y < c.height as f32) {
            return None;
        }
        let (px, py) = (p.x as u32, p.y as u32);
        if px >= c.width || py >= c.height {
            return None;
        }
        let cos = dir.dot(c.forward);
        if cos <= 0.0 {
            return None;
        }
        Some((py * c.width + px, 1.0 / (self.pixel_area * cos * cos * cos)))
    }
}

/// The first segment of a light path that starts at the sky: the sun with probability
/// proportional to its share of the radiance integrals ([`Sky::integrals`]; the dome
/// otherwise), a direction toward it (`u_dir`: over the sun's disc, or
/// [`Sky::sample_dome_emission`]) and a point across the beam toward the specular objects
/// (`u_point`, [`SpecularTargets::parallel`]); the ray starts outside the scene's bounds, so
/// whatever the beam meets first it meets. `pick` in [0, 1) chooses. Returns the ray (unit
/// direction) and its throughput L(w) / (P(part) p(w) p(A)), W; `None` when it carries nothing.
fn emit_from_sky(
    scene: &Scene,
    sky: &Sky,
    targets: &SpecularTargets,
    pick: f32,
    u_dir: Vec2,
    u_point: Vec2,
) -> Option<(Ray, Rgb)> {
    let (dome, sun) = sky.integrals();
    let (dome, sun) = (dome.element_sum(), sun.element_sum());
    let sun_share = sun / (sun + dome);
    if !sun_share.is_finite() {
        return None;
    }
    let (w, radiance, pdf) = if pick < sun_share {
        let (w, pdf) = sky.sample_sun(u_dir)?;
        (w, sky.sun_radiance(w), pdf * sun_share)
    } else {
        let (w, pdf) = sky.sample_dome_emission(u_dir);
        (w, sky.dome_radiance(w), pdf * (1.0 - sun_share))
    };
    let travel = -w.as_dvec3().normalize();
    let (point, density) = targets.parallel(travel, u_point)?;
    if !(density > 0.0 && pdf > 0.0) {
        return None;
    }
    let start = radiance / (pdf * density as f32);
    let back = f64::from(scene.bounds.diagonal()) * 2.0;
    let origin = (point - travel * back).as_vec3();
    (start.max_element() > 0.0 && start.is_finite())
        .then(|| (Ray::new(origin, travel.as_vec3()), start))
}
