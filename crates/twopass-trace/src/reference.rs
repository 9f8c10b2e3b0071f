//! The reference: a unidirectional path tracer with next-event estimation, multiple importance
//! sampling (power heuristic, Veach 1997) between emitter and BRDF sampling, and Russian
//! roulette. It uses the same materials (the whole BRDF, diffuse plus glossy, and the delta
//! lobes) and the same one-sided area emitters as the other methods; it is the ground truth of
//! the comparisons.
//!
//! Unbiased except for paths longer than [`ReferenceSettings::max_depth`] vertices, a safety
//! cap: Russian roulette on the throughput ends paths long before it for energy-conserving
//! materials, and the cap bounds the work for the published Phong, whose sample weights can
//! exceed 1.
//!
//! | setting | unit | default | meaning |
//! | --- | --- | --- | --- |
//! | `max_depth` | vertices | 64 | longest path (camera hit = 1) |
//! | `roulette_depth` | vertices | 3 | Russian roulette from this path length on |
//! | `caustics` | | `LightTracing` | who counts the caustic paths (below) |
//! | `light_paths` | light paths per camera sample | planned | how many the light tracing pass traces |
//! | `splits` | continuations per camera sample | planned | path splitting (below) |
//!
//! Emitters and lamps are chosen for next-event estimation in proportion to their mean emitted
//! power. A lamp (a delta light) is found by next-event estimation alone, without an MIS
//! weight. The sky takes one light sample of its own at every diffuse or glossy vertex (the
//! sun's cone or the dome, [`crate::sky::sky_mis`]) and a BRDF-sampled ray that escapes the
//! scene takes the sky's radiance; both are weighed by the power heuristic.
//!
//! **Caustics.** A path that sees a diffuse or glossy surface first and reaches the emitter
//! through a mirror or glass last (E D ... S+ L) is found by a camera path only when its
//! sampled direction happens to hit the emitter through the specular chain: for a small
//! light the noise of the caustic under a glass sphere dominates the image's for thousands of
//! samples. With [`Caustics::LightTracing`] (the default) the path tracer leaves exactly those
//! paths to a light tracing pass ([`crate::light_tracing`], scope
//! [`crate::light_tracing::CausticScope::All`]), which the render loop adds to the image: each
//! path is counted once, by the strategy that finds it easily. How many light paths that pass
//! traces per camera sample a pilot of both passes decides per render
//! ([`crate::light_plan`]): where the caustics are a small part of the image's noise, a few
//! light paths find them for a fraction of the time one per camera sample takes. A scene
//! without a delta surface has no such path and renders exactly as with
//! [`Caustics::PathTracing`].
//!
//! **Path splitting.** From the camera path's first diffuse or glossy vertex, after its light
//! sample, the path goes on as `N` continuations, each weighted `1 / N` and drawn from a fork
//! of the camera sample's sequence ([`Sampler::fork`]), so that a pixel's continuations are
//! one stratified sequence over all its samples. Russian roulette judges a continuation by the
//! throughput of the whole path, not its `1 / N` share (which would end nearly every one of
//! them and weigh the few left up: far more noise, the same mean). `N` comes from the render
//! ([`crate::SampleState::splits`]): [`ReferenceSettings::splits`] fixed, or planned by a
//! pilot ([`crate::split_plan`]).

use glam::Vec3;
use smart_default::SmartDefault;
use twopass_brdf::{BrdfSample, Material, Rgb, SampleKind};
use twopass_scene::{Hit, Ray, Scene, SurfacePoint};

use crate::counters::Tally;
use crate::emitters::{EmitterChoice, Light};
use crate::film::{Layer, Radiance};
use crate::integrator::{Integrator, SampleState, Shading, lamp_light};
use crate::light_tracing::{CausticScope, LightPaths, LightTracer, LightTracingSettings};
use crate::sampler::Sampler;
use crate::sky::{sky_light_pdf, sky_mis};
use crate::split_plan::PathSplits;

/// Path length settings of the reference path tracer.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct ReferenceSettings {
    /// Longest path, in surface vertices (the camera hit is vertex 1).
    #[default(64)]
    pub max_depth: u32,
    /// Path length (vertices) from which Russian roulette may end a path; survival probability
    /// is the largest channel of the throughput, capped at 1.
    #[default(3)]
    pub roulette_depth: u32,
    /// Which strategy counts the caustic paths E (D|G) ... S+ L.
    #[default(Caustics::LightTracing)]
    pub caustics: Caustics,
    /// With [`Caustics::LightTracing`], how many light paths the pass traces: by default as
    /// many per camera sample as a pilot measures to cost the least for the error
    /// ([`crate::light_plan`]).
    #[default(LightPaths::Planned)]
    pub light_paths: LightPaths,
    /// How many continuations a camera path takes from its first diffuse or glossy vertex:
    /// by default as many as a pilot measures to cost the least for the error
    /// ([`crate::split_plan`]).
    #[default(PathSplits::Planned)]
    pub splits: PathSplits,
}

/// Which strategy counts the paths that see a diffuse or glossy surface first and reach the
/// emitter through a delta bounce last.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Caustics {
    /// The path tracer alone (when its BRDF-sampled direction hits the emitter).
    PathTracing,
    /// A light tracing pass that the render loop adds (see the module documentation).
    LightTracing,
}

/// The reference path tracer for one scene (it precomputes the emitter choice).
#[derive(Debug, Clone)]
pub struct Reference {
    settings: ReferenceSettings,
    /// Which emitter next-event estimation samples.
    choice: EmitterChoice,
    /// Emitter index of each scene object, if it emits.
    emitter_of: Vec<Option<u32>>,
    /// The light tracing pass that counts the caustic paths, with
    /// [`Caustics::LightTracing`] in a scene that has any.
    light: Option<LightTracer>,
}

/// How a contribution is split among layers: by the first scattering event of the path.
#[derive(Debug, Clone, Copy)]
struct Split {
    a: Layer,
    b: Layer,
    /// Fraction per channel going to `a` (the rest to `b`).
    fraction: Rgb,
}

fn deposit(r: &mut Radiance, split: Option<Split>, default: Layer, c: Rgb) {
    match split {
        None => r.add(default, c),
        Some(s) => {
            r.add(s.a, c * s.fraction);
            r.add(s.b, c * (Rgb::ONE - s.fraction));
        }
    }
}

/// The diffuse fraction of f = f_d + f_g per channel (1 where f is zero).
fn diffuse_fraction(f_d: Rgb, f: Rgb) -> Rgb {
    Rgb::select(f.cmpgt(Rgb::ZERO), f_d / f, Rgb::ONE).clamp(Rgb::ZERO, Rgb::ONE)
}

/// Power heuristic with exponent 2 for the strategy of density `a` against `b`.
fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && (a2 + b2).is_finite() {
        a2 / (a2 + b2)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

impl Reference {
    /// The path tracer for `scene`.
    pub fn new(scene: &Scene, settings: ReferenceSettings) -> Self {
        let mut emitter_of = vec![None; scene.objects.len()];
        for (i, e) in scene.emitters.iter().enumerate() {
            emitter_of[e.object as usize] = Some(i as u32);
        }
        let light = match settings.caustics {
            Caustics::PathTracing => None,
            Caustics::LightTracing => LightTracer::new(
                scene,
                LightTracingSettings {
                    max_depth: settings.max_depth,
                    roulette_depth: settings.roulette_depth,
                    paths: settings.light_paths,
                    ..LightTracingSettings::new(CausticScope::All)
                },
            ),
        };
        Self {
            settings,
            choice: EmitterChoice::new(scene),
            emitter_of,
            light,
        }
    }

    /// The settings.
    pub fn settings(&self) -> ReferenceSettings {
        self.settings
    }

    /// Solid-angle density with which next-event estimation from `from` picks the point of
    /// `hit` on an emitter (1/sr), reached along unit direction `dir`.
    fn light_pdf(&self, scene: &Scene, from: &SurfacePoint, hit: &Hit, dir: Vec3) -> f32 {
        let Some(e) = self.emitter_of[hit.object as usize] else {
            return 0.0;
        };
        let emitter = &scene.emitters[e as usize];
        let dist2 = (hit.point.position - from.position).length_squared();
        let cos_y = -dir.dot(hit.point.normal);
        if cos_y <= 0.0 {
            return 0.0;
        }
        self.choice.probability(e as usize) / emitter.area * dist2 / cos_y
    }

    /// Next-event estimation at a non-delta shading point: one emitter sample weighted by MIS.
    /// Returns the reflected radiance split into (diffuse, glossy) parts.
    fn next_event(
        &self,
        scene: &Scene,
        s: &Shading,
        sampler: &mut Sampler,
        tally: &mut Tally,
    ) -> [Rgb; 2] {
        let zero = [Rgb::ZERO; 2];
        if !s.hit.front_face {
            return zero;
        }
        let m = s.material;
        let sky = sky_mis(
            scene,
            s,
            sampler,
            tally,
            &|wl| m.pdf(s.wo, wl),
            &|wl| [m.eval_diffuse(s.wo, wl), m.eval_non_diffuse(s.wo, wl)],
            power_heuristic,
        );
        if self.choice.is_empty() {
            return sky;
        }
        let [d, g] = self.next_event_emitter(scene, s, sampler, tally);
        [d + sky[0], g + sky[1]]
    }

    /// [`Self::next_event`]'s sample of one emitter or lamp.
    fn next_event_emitter(
        &self,
        scene: &Scene,
        s: &Shading,
        sampler: &mut Sampler,
        tally: &mut Tally,
    ) -> [Rgb; 2] {
        let zero = [Rgb::ZERO; 2];
        let e = match self.choice.pick(sampler.next_f32()) {
            Light::Area(e) => e,
            Light::Lamp(l) => {
                // A delta light: no BRDF sample reaches it, so no MIS weight.
                let p = self.choice.probability_of(Light::Lamp(l));
                let m = s.material;
                let [d, g] = lamp_light(scene, s, l, tally, &|wl| {
                    [m.eval_diffuse(s.wo, wl), m.eval_non_diffuse(s.wo, wl)]
                });
                return [d / p, g / p];
            }
        };
        let emitter = &scene.emitters[e];
        let pick = sampler.next_f32();
        let y = emitter.sample(scene, pick, sampler.next_2d());
        let x = s.hit.point;
        let d = y.position - x.position;
        let dist2 = d.length_squared();
        if dist2 <= 0.0 {
            return zero;
        }
        let wi = d / dist2.sqrt();
        let cos_y = -wi.dot(y.normal);
        if cos_y <= 0.0 || wi.dot(x.normal) <= 0.0 {
            return zero;
        }
        let wl = s.frame.to_local(wi);
        let m: &Material = &s.material;
        let f_d = m.eval_diffuse(s.wo, wl);
        let f_g = m.eval_non_diffuse(s.wo, wl);
        if wl.z <= 0.0 || (f_d + f_g).max_element() <= 0.0 {
            return zero;
        }
        tally.shadow_rays += 1;
        if scene.occluded_between(&x, &y) {
            return zero;
        }
        let pl = self.choice.probability(e) / emitter.area * dist2 / cos_y;
        let pb = m.pdf(s.wo, wl);
        let w = power_heuristic(pl, pb);
        let scale = emitter.radiance * (wl.z * w / pl);
        [f_d * scale, f_g * scale]
    }
}

impl Integrator for Reference {
    fn name(&self) -> &'static str {
        "reference"
    }

    fn light_tracer(&self) -> Option<&LightTracer> {
        self.light.as_ref()
    }

    fn path_splits(&self) -> Option<PathSplits> {
        Some(self.settings.splits)
    }

    fn radiance(&self, scene: &Scene, ray: &Ray, sample: SampleState<'_>) -> Radiance {
        let SampleState {
            sampler,
            tally,
            splits,
        } = sample;
        let mut r = Radiance::ZERO;
        tally.rays += 1;
        let hit = scene.intersect(ray);
        if hit.is_none() {
            r.add(Layer::Emission, crate::sky::escaped(scene, ray.direction));
            return r;
        }
        let path = Path {
            beta: Rgb::ONE,
            share: 1.0,
            split: None,
            dir: ray.direction,
            prev: None,
            depth: 1,
            seen_non_delta: false,
        };
        let mut walk = Walk {
            scene,
            sampler,
            tally,
            r: &mut r,
        };
        self.walk(&mut walk, hit, path, splits.max(1));
        r
    }
}

/// The state of a path between its vertices.
#[derive(Debug, Clone, Copy)]
struct Path {
    /// Throughput, this continuation's share included.
    beta: Rgb,
    /// The continuation's share of its camera sample (1 before any splitting): Russian
    /// roulette judges `beta / share`, the whole path's throughput.
    share: f32,
    /// How the path's contributions split among layers (set at its first scattering event).
    split: Option<Split>,
    /// The direction of the ray that reached the current vertex (unit).
    dir: Vec3,
    /// The previous vertex, the BRDF density of the current direction (1/sr), whether it was a
    /// delta bounce, and the vertex's shading normal (for MIS on emitters and the sky).
    prev: Option<(SurfacePoint, f32, bool, Vec3)>,
    /// Vertices so far (the camera hit is 1).
    depth: u32,
    /// Whether the camera's first vertex is a diffuse or glossy one: then a path reaching the
    /// emitter through a delta bounce is the light tracer's.
    seen_non_delta: bool,
}

/// What a camera sample's walk writes to and draws from.
struct Walk<'a, 'b> {
    scene: &'a Scene,
    sampler: &'b mut Sampler,
    tally: &'b mut Tally,
    r: &'b mut Radiance,
}

/// The fork site of path splitting's continuations ([`Sampler::fork`]), apart from the
/// gathers'; the split count is mixed in, so that runs of one pixel split differently never
/// share points.
const SPLIT_SITE: u64 = 0x7370_6c69_7400_0000;

impl Reference {
    /// Follows `p` from `hit` to its end, splitting it into `splits` continuations at its
    /// first diffuse or glossy vertex.
    fn walk(&self, w: &mut Walk<'_, '_>, mut hit: Option<Hit>, mut p: Path, splits: u32) {
        let scene = w.scene;
        while let Some(h) = hit {
            let s = Shading::new(scene, h, p.dir);
            if p.depth == 1 {
                p.seen_non_delta = s.material.delta().is_none();
            }

            if s.emitted.max_element() > 0.0 {
                let weight = match p.prev {
                    Some((_, _, true, _)) if p.seen_non_delta && self.light.is_some() => 0.0,
                    None | Some((_, _, true, _)) => 1.0,
                    Some((from, pdf_bsdf, false, _)) => {
                        power_heuristic(pdf_bsdf, self.light_pdf(scene, &from, &h, p.dir))
                    }
                };
                deposit(w.r, p.split, Layer::Emission, p.beta * s.emitted * weight);
            }
            if !s.scatters() || p.depth >= self.settings.max_depth {
                return;
            }
            if s.material.delta().is_none() {
                let [d, g] = self.next_event(scene, &s, w.sampler, w.tally);
                match p.split {
                    None => {
                        w.r.add(Layer::Diffuse, d);
                        w.r.add(Layer::DirectSpecular, g);
                    }
                    Some(_) => deposit(w.r, p.split, Layer::Diffuse, p.beta * (d + g)),
                }
                if splits > 1 {
                    let site = SPLIT_SITE ^ u64::from(splits);
                    let share = 1.0 / splits as f32;
                    for j in 0..splits {
                        let mut fork = w.sampler.fork(site, j, splits);
                        let mut sub = Walk {
                            scene,
                            sampler: &mut fork,
                            tally: w.tally,
                            r: w.r,
                        };
                        let mut q = Path {
                            beta: p.beta * share,
                            share: p.share * share,
                            ..p
                        };
                        if let Some(next) = self.bounce(&mut sub, &h, &s, &mut q) {
                            self.walk(&mut sub, next, q, 1);
                        }
                    }
                    return;
                }
            }
            match self.bounce(w, &h, &s, &mut p) {
                Some(next) => hit = next,
                None => return,
            }
        }
    }

    /// Samples the BRDF at `h` (shading `s`), takes `p` along the sampled direction (Russian
    /// roulette from [`ReferenceSettings::roulette_depth`] on) and traces it: the next hit,
    /// `None` inside when it leaves the scene (the sky's light counted), or `None` when the path
    /// ends here.
    fn bounce(
        &self,
        w: &mut Walk<'_, '_>,
        h: &Hit,
        s: &Shading,
        p: &mut Path,
    ) -> Option<Option<Hit>> {
        let m = &s.material;
        let bs = m.sample(s.wo, w.sampler.next_2d())?;
        let wi = s.frame.to_world(bs.wi).normalize();
        // An opaque surface reflects to the side it is seen from, by its geometric normal
        // too (shading normals must not leak light through the surface).
        if !s.is_dielectric() && wi.dot(h.point.normal) <= 0.0 {
            return None;
        }
        if p.split.is_none() {
            p.split = Some(first_split(m, s, &bs));
        }
        p.beta *= bs.weight;
        if p.depth >= self.settings.roulette_depth {
            let survive = (p.beta.max_element() / p.share).min(1.0);
            // A NaN throughput survives and is reported as a non-finite sample.
            if w.sampler.next_f32() >= survive {
                return None;
            }
            p.beta /= survive;
        }
        p.prev = Some((h.point, bs.pdf, bs.kind.is_delta(), h.shading_normal));
        p.dir = wi;
        w.tally.rays += 1;
        let hit = w.scene.intersect_from(&h.point, wi);
        p.depth += 1;
        if hit.is_none()
            && let Some(sky) = &w.scene.sky
        {
            // The sky, weighed against its light sample at the previous vertex; reached
            // through a delta bounce after a diffuse first vertex, the light tracer's (its
            // paths start at the sky too), as an emitter's light is.
            let weight = match p.prev {
                Some((_, _, true, _)) if p.seen_non_delta && self.light.is_some() => 0.0,
                None | Some((_, _, true, _)) => 1.0,
                Some((from, pdf_bsdf, false, normal)) => {
                    power_heuristic(pdf_bsdf, sky_light_pdf(sky, from.position, normal, wi))
                }
            };
            deposit(
                w.r,
                p.split,
                Layer::Emission,
                p.beta * sky.radiance(wi) * weight,
            );
        }
        Some(hit)
    }
}

/// The layer split of everything a path gathers after its first scattering event.
fn first_split(m: &Material, s: &Shading, bs: &BrdfSample) -> Split {
    match bs.kind {
        SampleKind::SpecularReflection => Split {
            a: Layer::Reflection,
            b: Layer::Reflection,
            fraction: Rgb::ONE,
        },
        SampleKind::SpecularTransmission => Split {
            a: Layer::Refraction,
            b: Layer::Refraction,
            fraction: Rgb::ONE,
        },
        SampleKind::Diffuse | SampleKind::Glossy => Split {
            a: Layer::Diffuse,
            b: Layer::DirectSpecular,
            fraction: diffuse_fraction(m.eval_diffuse(s.wo, bs.wi), m.eval(s.wo, bs.wi)),
        },
    }
}
