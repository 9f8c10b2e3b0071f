//! The Whitted-style ray tracer (Whitted 1980) and the shading core it shares with the
//! radiosity-based methods of [`crate::hybrid`].
//!
//! At each hit: emission (one-sided), the diffuse light from a [`DiffuseSource`], the glossy lobe
//! of the material (Phong, Blinn-Phong, Cook-Torrance) against every emitter with stratified
//! shadow rays, and the delta lobes followed recursively: perfect mirror, smooth conductor
//! (reflecting in its own colour: exact complex Fresnel per channel) and smooth dielectric
//! (Snell refraction with exact Fresnel weights and total internal reflection), until
//! [`WhittedSettings::max_depth`] or until the path's throughput falls under
//! [`WhittedSettings::min_throughput`]. Rays that leave the scene see the sky (black without
//! one); the sky lights the shading points by shadow rays ([`crate::sky::sky_light`]).
//!
//! | setting | unit | default | meaning |
//! | --- | --- | --- | --- |
//! | `max_depth` | bounces | 8 | delta bounces followed after the camera hit |
//! | `min_throughput` | dimensionless | 1e-3 | a branch whose largest channel weight falls below is cut |
//! | `shadow_grid` | samples per axis | 4 | shadow rays per shading point over all area emitters, each ray's emitter by its importance there: grid^2 (and as many for the sky's sun and for its dome; one per lamp) |
//! | `caustic_paths` | light paths per camera sample | 1 | the hybrids' per-pixel caustics ([`crate::hybrid`]); 0: off |
//! | `gather_rays` | rays per camera sample and shading point | 8 | the gathered hybrid's indirect light ([`crate::hybrid::gathered`]) |

use smart_default::SmartDefault;
use twopass_brdf::Rgb;
use twopass_scene::{Ray, Scene};

use crate::counters::Tally;
use crate::diffuse::{DiffuseSource, SampleSite};
use crate::emitters::Lights;
use crate::film::{Layer, Radiance};
use crate::integrator::{Integrator, SampleState, Shading, direct_light, trace_from};
use crate::light_tracing::LightTracer;
use crate::sampler::Sampler;

/// Recursion and shadow-ray settings of the Whitted-family tracers.
#[derive(SmartDefault, Debug, Clone, Copy, PartialEq)]
pub struct WhittedSettings {
    /// Largest number of delta bounces (reflection or refraction) after the camera hit.
    #[default(8)]
    pub max_depth: u32,
    /// Smallest throughput (largest channel of the product of delta weights, dimensionless)
    /// for which a reflection or refraction ray is still traced.
    #[default(1e-3)]
    pub min_throughput: f32,
    /// Shadow rays per shading point along each axis of the stratification grid, over all the
    /// area emitters (`shadow_grid`^2 rays, each ray's emitter chosen by its importance at the
    /// point: [`crate::integrator::direct_light`]; at least 1).
    #[default(4)]
    pub shadow_grid: u32,
    /// Light paths per camera sample of the hybrids' per-pixel caustics (light through mirrors
    /// and glass onto the surface the camera sees, [`crate::light_tracing::CausticScope`]); 0
    /// turns them off (the gathered hybrid's gather rays then find that light by chance). See
    /// [`crate::hybrid`] for when each hybrid runs them.
    #[default(1.0)]
    pub caustic_paths: f32,
    /// Gather rays per camera sample at each diffuse shading point of the gathered hybrid
    /// ([`crate::hybrid::gathered`]): a pixel of `spp` samples averages `spp` times as many
    /// (stratified together, [`Sampler::fork`]). 0: no indirect light. The CLI's `render` spends
    /// 256 rays per pixel as 4 rays at each of 64 samples (`RenderDefaults` there).
    #[default(8)]
    pub gather_rays: u32,
}

/// A Whitted-family ray tracer: camera rays, local models against emitters, delta lobes
/// followed recursively, and diffuse light from a [`DiffuseSource`]. The classic Whitted
/// tracer is [`Whitted::new`]; the radiosity-based methods are built in [`crate::hybrid`].
#[derive(Clone)]
pub struct Whitted<'a> {
    pub(crate) lights: Lights,
    pub(crate) source: DiffuseSource<'a>,
    /// Whether the view-dependent terms (glossy lobes, reflection, refraction) are traced;
    /// `false` only for radiosity alone.
    pub(crate) view_dependent: bool,
    pub(crate) settings: WhittedSettings,
    pub(crate) name: &'static str,
    /// The per-pixel caustics (the hybrids only): the render loop adds this light tracer's
    /// image, and the camera's first diffuse hit leaves that light out ([`crate::hybrid`]).
    pub(crate) caustics: Option<LightTracer>,
}

impl std::fmt::Debug for Whitted<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Whitted")
            .field("name", &self.name)
            .field("view_dependent", &self.view_dependent)
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

impl<'a> Whitted<'a> {
    /// The classic Whitted tracer: direct light by shadow rays and the constant ambient term
    /// k_a I_amb in place of interreflection, with `ambient` = I_amb, a radiance in
    /// W/(m^2 sr) per channel (see [`ambient_estimate`] for a value derived from the scene),
    /// for rendering `scene`.
    pub fn new(scene: &Scene, ambient: Rgb, settings: WhittedSettings) -> Self {
        Self {
            lights: Lights::new(scene),
            source: DiffuseSource::Ambient { ambient },
            view_dependent: true,
            settings,
            name: "whitted",
            caustics: None,
        }
    }

    /// The settings.
    pub fn settings(&self) -> WhittedSettings {
        self.settings
    }

    /// The layered radiance leaving the surface of `hit` toward the origin of a ray of unit
    /// direction `direction`, `depth` delta bounces after the camera hit, reached with
    /// throughput `throughput` along the branches `site` (1 at the camera hit; a child's is
    /// twice its parent's, plus 1 through a refraction).
    fn shade(
        &self,
        scene: &Scene,
        s: &Shading,
        (depth, site): (u32, u64),
        throughput: Rgb,
        sampler: &mut Sampler,
        tally: &mut Tally,
    ) -> Radiance {
        let mut r = Radiance::ZERO;
        let m = s.material;
        let glossy = self.view_dependent && m.lobe().is_some_and(|l| !l.is_delta());

        // Diffuse light (and emission) from the source; direct diffuse light by shadow rays
        // when the source asks for it, sharing the shadow rays with the glossy lobe.
        let per_pixel_caustics = depth == 0 && self.caustics.is_some();
        let at = SampleSite {
            sampler: &*sampler,
            site,
        };
        let direct_diffuse = self
            .source
            .diffuse(s, per_pixel_caustics, at, tally, &mut r);
        let need_diffuse = direct_diffuse && m.reflects_diffusely();
        if s.hit.front_face && (need_diffuse || glossy) {
            let brdf = |wi| {
                [
                    if need_diffuse {
                        m.eval_diffuse(s.wo, wi)
                    } else {
                        Rgb::ZERO
                    },
                    if glossy {
                        m.eval_non_diffuse(s.wo, wi)
                    } else {
                        Rgb::ZERO
                    },
                ]
            };
            let grid = self.settings.shadow_grid;
            let [d, g] = direct_light(scene, &self.lights, s, grid, sampler, tally, brdf);
            let [sd, sg] = crate::sky::sky_light(scene, s, grid, sampler, tally, &brdf);
            let (d, g) = (d + sd, g + sg);
            r.add(Layer::Diffuse, d);
            r.add(Layer::DirectSpecular, g);
        }

        // Delta lobes, followed recursively.
        if self.view_dependent
            && depth < self.settings.max_depth
            && let Some(lobe) = m.delta()
        {
            let rays = [
                (lobe.reflection(s.wo), Layer::Reflection, 0),
                (lobe.refraction(s.wo), Layer::Refraction, 1),
            ];
            for (ray, layer, branch) in rays {
                let Some(ray) = ray else { continue };
                let t = throughput * ray.weight;
                if t.max_element() < self.settings.min_throughput {
                    continue;
                }
                let dir = s.frame.to_world(ray.wi).normalize();
                if let Some(h) = trace_from(scene, s, dir, tally) {
                    let child = Shading::new(scene, h, dir);
                    let child_site = site.wrapping_mul(2).wrapping_add(branch);
                    let l = self.shade(scene, &child, (depth + 1, child_site), t, sampler, tally);
                    r.add(layer, ray.weight * l.total());
                } else {
                    r.add(layer, ray.weight * crate::sky::escaped(scene, dir));
                }
            }
        }
        r
    }
}

impl Integrator for Whitted<'_> {
    fn name(&self) -> &'static str {
        self.name
    }

    fn light_tracer(&self) -> Option<&LightTracer> {
        self.caustics.as_ref()
    }

    fn radiance(&self, scene: &Scene, ray: &Ray, sample: SampleState<'_>) -> Radiance {
        let SampleState { sampler, tally, .. } = sample;
        tally.rays += 1;
        match scene.intersect(ray) {
            None => Radiance::single(Layer::Emission, crate::sky::escaped(scene, ray.direction)),
            Some(hit) => {
                let s = Shading::new(scene, hit, ray.direction);
                self.shade(scene, &s, (0, 1), Rgb::ONE, sampler, tally)
            }
        }
    }
}

/// A constant ambient radiance I_amb (W/(m^2 sr) per channel) for the classic Whitted tracer,
/// from the scene alone: the indirect irradiance of a uniformly lit enclosure,
/// E_ind = (sum of emitted power, lamps included / total area) * rho / (1 - rho), with rho the area-weighted
/// mean diffuse reflectance, as radiance E_ind / pi (the estimate behind the ambient term of
/// progressive radiosity, Cohen et al. 1988, with the first bounce left to the shadow rays).
pub fn ambient_estimate(scene: &Scene) -> Rgb {
    let total_area = scene.total_area();
    if total_area <= 0.0 {
        return Rgb::ZERO;
    }
    let mut rho_area = glam::DVec3::ZERO;
    for o in &scene.objects {
        let area = |t: u32| f64::from(scene.mesh.area(t));
        rho_area += if scene.has_textures() {
            // Each triangle's texture mean.
            o.triangles
                .clone()
                .map(|t| scene.triangle_albedo(t).as_dvec3() * area(t))
                .sum::<glam::DVec3>()
        } else {
            let rho = scene.materials[o.material as usize]
                .material
                .diffuse_albedo()
                .as_dvec3();
            rho * o.triangles.clone().map(area).sum::<f64>()
        };
    }
    let rho = rho_area / total_area;
    let power = scene
        .emitters
        .iter()
        .fold(scene.lamp_power().as_dvec3(), |a, e| a + e.power.as_dvec3());
    let e_ind = power / total_area * rho / (glam::DVec3::ONE - rho);
    (e_ind / std::f64::consts::PI).as_vec3()
}
