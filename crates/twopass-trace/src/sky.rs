//! The sky in the tracer ([`twopass_scene::Sky`]): a ray that escapes the scene sees its
//! radiance; at a shading point its light comes by next-event estimation with shadow rays to
//! infinity: the sun over its cone and the dome by the cosine (through the portals when there
//! are any). The Whitted family and the final gather take a stratified grid of each
//! ([`sky_light`], [`sky_irradiance`]) and never count a BRDF-sampled ray that escapes at a
//! diffuse or glossy point; the path tracer takes one sample of the mixture ([`sky_mis`]) and
//! weighs it and the escaping BRDF-sampled rays by the power heuristic ([`sky_light_pdf`]).
//! Light paths start at the sky too ([`crate::light_tracing`]): what it sends through mirrors
//! and glass is the light tracer's and the photons', as an emitter's is.

use glam::Vec3;
use twopass_brdf::Rgb;
use twopass_scene::{Scene, Sky};

use crate::counters::Tally;
use crate::integrator::Shading;
use crate::sampler::{Sampler, stratum};

/// Radiance (W/(m^2 sr) per channel) a ray of unit direction `dir` sees when it escapes
/// `scene`: the sky's, or black without one.
pub fn escaped(scene: &Scene, dir: Vec3) -> Rgb {
    scene.sky.as_ref().map_or(Rgb::ZERO, |s| s.radiance(dir))
}

/// One direction's contribution: f L cos / pdf split by `brdf`, after the shadow ray.
fn contribution(
    scene: &Scene,
    s: &Shading,
    dir: Vec3,
    l: Rgb,
    tally: &mut Tally,
    brdf: &impl Fn(Vec3) -> [Rgb; 2],
) -> Option<([Rgb; 2], f32)> {
    if l == Rgb::ZERO {
        return None;
    }
    let (wl, f) = crate::integrator::arriving(s, dir, brdf)?;
    tally.shadow_rays += 1;
    if !scene.sky_visible(&s.hit.point, dir) {
        return None;
    }
    Some(([f[0] * l * wl.z, f[1] * l * wl.z], wl.z))
}

/// The radiance the sky reflects toward the viewer at a shading point, split into two parts by
/// `brdf` (two BRDF values, 1/sr without the cosine, for a local incident direction):
/// `grid` x `grid` stratified directions over the sun's cone and as many for the dome, each
/// with a shadow ray, the mean of f L cos / pdf. W/(m^2 sr) per channel; zero without a sky
/// or on the back of the surface.
pub fn sky_light(
    scene: &Scene,
    s: &Shading,
    grid: u32,
    sampler: &mut Sampler,
    tally: &mut Tally,
    brdf: &impl Fn(Vec3) -> [Rgb; 2],
) -> [Rgb; 2] {
    let mut out = [Rgb::ZERO; 2];
    let Some(sky) = &scene.sky else {
        return out;
    };
    if !s.hit.front_face {
        return out;
    }
    let k = grid.max(1);
    let n = k * k;
    let mut add = |dir: Vec3, pdf: f32, l: Rgb, tally: &mut Tally| {
        if let Some(([a, b], _)) = contribution(scene, s, dir, l, tally, brdf) {
            out[0] += a / (pdf * n as f32);
            out[1] += b / (pdf * n as f32);
        }
    };
    if sky.sun.is_some() {
        for i in 0..n {
            if let Some((dir, pdf)) = sky.sample_sun(stratum(i, k, sampler.next_2d())) {
                add(dir, pdf, sky.sun_radiance(dir), tally);
            }
        }
    }
    for i in 0..n {
        let u = stratum(i, k, sampler.next_2d());
        let pick = sampler.next_f32();
        let x = s.hit.point.position;
        if let Some((dir, pdf)) = sky.sample_dome(x, s.hit.shading_normal, u, pick) {
            add(dir, pdf, sky.dome_radiance(dir), tally);
        }
    }
    out
}

/// The irradiance (W/m^2 per channel) the sky gives the front of the shading point by the
/// shading normal's cosine: [`sky_light`] with the BRDF replaced by 1 (for a final gather,
/// which multiplies by rho / pi).
pub fn sky_irradiance(
    scene: &Scene,
    s: &Shading,
    grid: u32,
    sampler: &mut Sampler,
    tally: &mut Tally,
) -> Rgb {
    sky_light(scene, s, grid, sampler, tally, &|_| [Rgb::ONE, Rgb::ZERO])[0]
}

/// Density (1/sr) with which [`sky_mis`] at a point `x` of shading normal `normal` samples
/// unit direction `dir`: the mixture of the sun's cone (probability [`Sky::sun_share`]) and
/// the dome's sampling.
pub fn sky_light_pdf(sky: &Sky, x: Vec3, normal: Vec3, dir: Vec3) -> f32 {
    let q = sky.sun_share();
    q * sky.sun_pdf(dir) + (1.0 - q) * sky.dome_pdf(x, normal, dir)
}

/// One light sample of the sky for the path tracer, weighted by the power heuristic against
/// BRDF sampling of density `brdf_pdf` (1/sr, for a local direction): the sun with
/// probability [`Sky::sun_share`], else the dome, and the whole sky's radiance in the sampled
/// direction over the mixture's density ([`sky_light_pdf`]). Split by `brdf` as
/// [`sky_light`]; W/(m^2 sr) per channel.
pub fn sky_mis(
    scene: &Scene,
    s: &Shading,
    sampler: &mut Sampler,
    tally: &mut Tally,
    brdf_pdf: &impl Fn(Vec3) -> f32,
    brdf: &impl Fn(Vec3) -> [Rgb; 2],
    heuristic: impl Fn(f32, f32) -> f32,
) -> [Rgb; 2] {
    let zero = [Rgb::ZERO; 2];
    let Some(sky) = &scene.sky else {
        return zero;
    };
    if !s.hit.front_face {
        return zero;
    }
    let x = s.hit.point.position;
    let normal = s.hit.shading_normal;
    let pick = sampler.next_f32();
    let u = sampler.next_2d();
    let sampled = if pick < sky.sun_share() {
        sky.sample_sun(u)
    } else {
        sky.sample_dome(x, normal, u, sampler.next_f32())
    };
    let Some((dir, _)) = sampled else {
        return zero;
    };
    let pl = sky_light_pdf(sky, x, normal, dir);
    if !(pl > 0.0 && pl.is_finite()) {
        return zero;
    }
    let Some(([a, b], _)) = contribution(scene, s, dir, sky.radiance(dir), tally, brdf) else {
        return zero;
    };
    let w = heuristic(pl, brdf_pdf(s.frame.to_local(dir))) / pl;
    [a * w, b * w]
}
