//! The integrator boundary (ARCHITECTURE.md, "Architecture invariants"): one required method that
//! turns a camera ray into layered radiance, plus the shared pieces every integrator uses: the
//! shading context at a hit (local frame, one-sided surfaces) and direct lighting from the area
//! emitters with stratified shadow rays and from the lamps with one shadow ray each. Visibility and ray-origin offsetting belong to the scene
//! (`Scene::intersect_from`, `Scene::occluded_between`); nothing here holds an epsilon. Integrators
//! never spawn threads.

use glam::Vec3;
use twopass_brdf::frame::Frame;
use twopass_brdf::{Material, Rgb};
use twopass_scene::{Hit, Ray, Scene};

use crate::counters::Tally;
use crate::emitters::Lights;
use crate::film::Radiance;
use crate::sampler::{Sampler, stratum};

/// What one camera sample carries through an integrator: its random stream and the count of
/// the rays it traces.
#[derive(Debug)]
pub struct SampleState<'a> {
    /// The sample's stream, keyed by (seed, pixel, sample).
    pub sampler: &'a mut Sampler,
    /// The rays traced for this sample so far.
    pub tally: &'a mut Tally,
    /// Continuations to trace from the camera path's first diffuse or glossy vertex (path
    /// splitting, [`crate::split_plan`]): what the render planned or was told for an integrator
    /// whose [`Integrator::path_splits`] is set, 1 for the others (which ignore it).
    pub splits: u32,
}

/// A light transport method: radiance arriving along a camera ray.
///
/// Implementations are pure functions of their inputs and the sampler's stream: the render
/// loop ([`crate::render()`]) owns tiling, threads, seeding and progress.
pub trait Integrator: Sync {
    /// A short name for reports and file names (`whitted`, `radiosity`, `hybrid`,
    /// `hybrid-classic`, `hybrid-direct`, `reference`).
    fn name(&self) -> &'static str;

    /// Radiance (W/(m^2 sr) per channel) arriving at the camera along `ray` (unit direction),
    /// split into [`crate::Layer`]s; the sample's tally counts the rays it traces.
    fn radiance(&self, scene: &Scene, ray: &Ray, sample: SampleState<'_>) -> Radiance;

    /// The light tracing pass whose per-pixel result the render loop adds to this
    /// integrator's image (the caustics it leaves to light tracing), if any.
    fn light_tracer(&self) -> Option<&crate::light_tracing::LightTracer> {
        None
    }

    /// How many continuations this integrator traces from a camera path's first diffuse or
    /// glossy vertex, if it splits paths: the render loop plans [`PathSplits::Planned`] and
    /// hands the count to every sample ([`SampleState::splits`]).
    ///
    /// [`PathSplits::Planned`]: crate::split_plan::PathSplits::Planned
    fn path_splits(&self) -> Option<crate::split_plan::PathSplits> {
        None
    }
}

/// What a shader needs at a hit: the material, the local shading frame and the outgoing
/// direction in it.
#[derive(Debug, Clone, Copy)]
pub struct Shading {
    /// The hit.
    pub hit: Hit,
    /// The hit surface's material at the hit: its diffuse part tinted by the base colour
    /// texture there ([`Scene::material_at`]; the material itself when untextured).
    pub material: Material,
    /// Local frame around the shading normal (on the geometric normal's side).
    pub frame: Frame,
    /// Direction toward the viewer (unit, local frame; z < 0 when seen from behind).
    pub wo: Vec3,
    /// Emitted radiance toward the viewer, W/(m^2 sr): the object's L_e on its front side,
    /// zero on its back (emitters are one-sided).
    pub emitted: Rgb,
}

impl Shading {
    /// The shading context of `hit`, reached by a ray of unit direction `direction`.
    pub fn new(scene: &Scene, hit: Hit, direction: Vec3) -> Self {
        let material = scene.material_at(hit.point.triangle, hit.barycentric);
        let frame = Frame::from_normal(hit.shading_normal);
        let wo = frame.to_local(-direction);
        let emitted = if hit.front_face {
            scene.objects[hit.object as usize].emission
        } else {
            Rgb::ZERO
        };
        Self {
            hit,
            material,
            frame,
            wo,
            emitted,
        }
    }

    /// Whether the surface scatters light toward this side: opaque surfaces are one-sided
    /// (their back reflects nothing, as in the radiosity solution, whose receivers are
    /// one-sided); a smooth dielectric is seen from both sides.
    pub fn scatters(&self) -> bool {
        self.hit.front_face || self.is_dielectric()
    }

    /// Whether the material is a smooth dielectric (two-sided interface).
    pub fn is_dielectric(&self) -> bool {
        self.material.is_dielectric()
    }
}

/// Light arriving at the shading point from unit world direction `dir`: its local direction and
/// the two BRDF values (1/sr) of `brdf` there, or `None` when nothing can arrive (below the
/// geometric or the shading surface) or both values are zero. The test before every shadow ray
/// the Whitted core casts (emitters, lamps, the sky), so no ray is spent on light that would be
/// multiplied by zero.
pub(crate) fn arriving(
    s: &Shading,
    dir: Vec3,
    brdf: &impl Fn(Vec3) -> [Rgb; 2],
) -> Option<(Vec3, [Rgb; 2])> {
    if dir.dot(s.hit.point.normal) <= 0.0 {
        return None;
    }
    let wl = s.frame.to_local(dir);
    if wl.z <= 0.0 {
        return None;
    }
    let f = brdf(wl);
    if f[0].max_element() <= 0.0 && f[1].max_element() <= 0.0 {
        return None;
    }
    Some((wl, f))
}

/// Direct light from every emitter at a shading point: `grid` x `grid` stratified shadow rays
/// over all the area emitters, each ray's emitter chosen in proportion to its importance at
/// the point ([`Lights::choice_at`]), and one shadow ray per lamp ([`lamps_light`]) (the sky's
/// light is `crate::sky::sky_light`'s), split into two parts by `brdf`, which returns two BRDF
/// values (1/sr, without the cosine) for a local incident direction. Returns the two reflected
/// radiances, W/(m^2 sr) per channel.
///
/// Estimator: the mean over the samples of f L_e cos(theta_x) cos(theta_y) / d^2 * A / p, with
/// the emitter (area A, radiance L_e) picked with probability p and its point uniform by area
/// (density 1/A): the grid's first coordinate picks the emitter and its remainder places the
/// point ([`Lights::sample`]), so the jittered grid stays stratified over each emitter's area.
/// Unbiased: an emitter gets probability zero only where none of its points can light the
/// point. Light must reach the front of the shading point's geometric surface and leave the
/// front of the emitter. With one emitter this is a stratified grid over its area, whatever
/// its importance; with many, the rays go where the light comes from instead of `grid`^2 to
/// each (a room of 17 strip lights: 16 shadow rays per point, not 272).
pub fn direct_light(
    scene: &Scene,
    lights: &Lights,
    s: &Shading,
    grid: u32,
    sampler: &mut Sampler,
    tally: &mut Tally,
    brdf: impl Fn(Vec3) -> [Rgb; 2],
) -> [Rgb; 2] {
    let mut out = [Rgb::ZERO; 2];
    if !s.hit.front_face {
        return out;
    }
    if !scene.emitters.is_empty() {
        let x = s.hit.point;
        // One emitter takes every ray: no importance to weigh.
        let choice = (scene.emitters.len() > 1)
            .then(|| lights.choice_at(x.position, x.normal, s.hit.shading_normal));
        let k = grid.max(1);
        let n = k * k;
        for i in 0..n {
            // Drawn whether or not an emitter can light the point, so the numbers after
            // these keep their dimensions of the sample's sequence.
            let u = stratum(i, k, sampler.next_2d());
            let (e, p, rest) = match &choice {
                None => (0, 1.0, u.x),
                Some(c) if c.is_empty() => continue,
                Some(c) => c.pick(u.x),
            };
            let emitter = &scene.emitters[e];
            let y = lights.sample(scene, e, glam::Vec2::new(rest, u.y));
            let Some((f, g)) = unoccluded(scene, s, &y, &brdf, tally) else {
                continue;
            };
            let w = emitter.radiance * (g * emitter.area / (p * n as f32));
            out[0] += f[0] * w;
            out[1] += f[1] * w;
        }
    }
    let lamps = lamps_light(scene, s, tally, &brdf);
    [out[0] + lamps[0], out[1] + lamps[1]]
}

/// The two BRDF values and the geometry term cos(theta_x) cos(theta_y) / d^2 (1/(scene unit)^2)
/// of light from emitter point `y` at the shading point of `s`, or `None` when it cannot
/// arrive: behind either surface, a BRDF of zero, or a blocker (a shadow ray, counted).
fn unoccluded(
    scene: &Scene,
    s: &Shading,
    y: &twopass_scene::SurfacePoint,
    brdf: &impl Fn(Vec3) -> [Rgb; 2],
    tally: &mut Tally,
) -> Option<([Rgb; 2], f32)> {
    let x = &s.hit.point;
    let d = y.position - x.position;
    let dist2 = d.length_squared();
    if dist2 <= 0.0 {
        return None;
    }
    let wi = d / dist2.sqrt();
    let cos_y = -wi.dot(y.normal);
    if cos_y <= 0.0 {
        return None;
    }
    let (wl, f) = arriving(s, wi, brdf)?;
    tally.shadow_rays += 1;
    if scene.occluded_between(x, y) {
        return None;
    }
    Some((f, wl.z * cos_y / dist2))
}

/// The irradiance (W/m^2 per channel) that emitter `e` (index into `Scene::emitters`) sends to
/// the front of the shading point, with `grid` x `grid` stratified shadow rays: the estimator
/// of [`direct_light`] for one emitter with the BRDF replaced by 1, so that the cosine at the
/// shading point is the shading normal's (for a final gather, which multiplies by rho / pi).
pub fn irradiance_from(
    scene: &Scene,
    lights: &Lights,
    s: &Shading,
    e: usize,
    grid: u32,
    sampler: &mut Sampler,
    tally: &mut Tally,
) -> Rgb {
    if !s.hit.front_face {
        return Rgb::ZERO;
    }
    emitter_light(scene, lights, s, e, grid, sampler, tally, &|_| {
        [Rgb::ONE, Rgb::ZERO]
    })[0]
}

/// [`direct_light`]'s estimator for emitter `e` alone.
#[allow(clippy::too_many_arguments)]
fn emitter_light(
    scene: &Scene,
    lights: &Lights,
    s: &Shading,
    e: usize,
    grid: u32,
    sampler: &mut Sampler,
    tally: &mut Tally,
    brdf: &impl Fn(Vec3) -> [Rgb; 2],
) -> [Rgb; 2] {
    let emitter = &scene.emitters[e];
    let k = grid.max(1);
    let n = k * k;
    let mut sum = [Rgb::ZERO; 2];
    for i in 0..n {
        let y = lights.sample(scene, e, stratum(i, k, sampler.next_2d()));
        if let Some((f, g)) = unoccluded(scene, s, &y, brdf, tally) {
            sum[0] += f[0] * g;
            sum[1] += f[1] * g;
        }
    }
    let scale = emitter.radiance * (emitter.area / n as f32);
    [sum[0] * scale, sum[1] * scale]
}

// Lamps (point, spot, directional: delta lights) by next-event estimation: one shadow ray per
// lamp, no random number. A ray never hits a lamp, so no other strategy finds their light and
// these estimates take no MIS weight.

/// The radiance reflected toward the viewer from lamp `l` (index into `Scene::lamps`), split
/// into two parts by `brdf`, which returns two BRDF values (1/sr, without the cosine) for a
/// local incident direction: f I(w) cos(theta) / r^2 (point, spot) or f E cos(theta)
/// (directional), zero when the lamp is behind the surface (by shading and geometric normal)
/// or a shadow ray finds a blocker. W/(m^2 sr) per channel.
pub fn lamp_light(
    scene: &Scene,
    s: &Shading,
    l: usize,
    tally: &mut Tally,
    brdf: &impl Fn(Vec3) -> [Rgb; 2],
) -> [Rgb; 2] {
    let zero = [Rgb::ZERO; 2];
    let x = s.hit.point;
    let Some(light) = scene.lamps[l].light_at(x.position) else {
        return zero;
    };
    let Some((wl, f)) = arriving(s, light.direction, brdf) else {
        return zero;
    };
    tally.shadow_rays += 1;
    if scene.lamp_occluded(&x, &light) {
        return zero;
    }
    let e = light.irradiance * wl.z;
    [f[0] * e, f[1] * e]
}

/// [`lamp_light`] summed over every lamp of the scene.
pub fn lamps_light(
    scene: &Scene,
    s: &Shading,
    tally: &mut Tally,
    brdf: &impl Fn(Vec3) -> [Rgb; 2],
) -> [Rgb; 2] {
    let mut out = [Rgb::ZERO; 2];
    for l in 0..scene.lamps.len() {
        let [a, b] = lamp_light(scene, s, l, tally, brdf);
        out[0] += a;
        out[1] += b;
    }
    out
}

/// The irradiance (W/m^2 per channel) lamp `l` gives the front of the shading point, by the
/// shading normal's cosine: [`lamp_light`] with the BRDF replaced by 1 (for a final gather,
/// which multiplies by rho / pi).
pub fn lamp_irradiance(scene: &Scene, s: &Shading, l: usize, tally: &mut Tally) -> Rgb {
    if !s.hit.front_face {
        return Rgb::ZERO;
    }
    lamp_light(scene, s, l, tally, &|_| [Rgb::ONE, Rgb::ZERO])[0]
}

/// [`lamp_irradiance`] summed over every lamp.
pub fn lamps_irradiance(scene: &Scene, s: &Shading, tally: &mut Tally) -> Rgb {
    (0..scene.lamps.len())
        .map(|l| lamp_irradiance(scene, s, l, tally))
        .fold(Rgb::ZERO, |a, b| a + b)
}

/// The closest hit along a ray leaving the shading point in world direction `direction`,
/// counted in `tally`.
pub fn trace_from(scene: &Scene, s: &Shading, direction: Vec3, tally: &mut Tally) -> Option<Hit> {
    tally.rays += 1;
    scene.intersect_from(&s.hit.point, direction)
}
