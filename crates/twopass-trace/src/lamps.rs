//! Light from the lamps (point, spot, directional: delta lights) at a shading point, by
//! next-event estimation: one shadow ray per lamp, no random number. A ray never hits a lamp,
//! so no other strategy finds their light and these estimates take no MIS weight.

use glam::Vec3;
use twopass_brdf::Rgb;
use twopass_scene::Scene;

use crate::counters::Tally;
use crate::integrator::Shading;

/// The radiance reflected toward the viewer from lamp `l` (index into `Scene::lamps`), split
/// into two parts by `brdf`, which returns two BRDF values (1/sr, without the cosine) for a
/// local incident direction: f I(w) cos(theta) / r^2 (point, spot) or f E cos(theta)
/// (directional), zero when the lamp is behind the surface (by shading and geometric normal)
/// or a shadow ray finds a blocker. W/(m^2 sr) per channel.
pub fn lamp_light(
    scene: &Scene,
    s: &Shading<'_>,
    l: usize,
    tally: &mut Tally,
    brdf: &impl Fn(Vec3) -> [Rgb; 2],
) -> [Rgb; 2] {
    let zero = [Rgb::ZERO; 2];
    let x = s.hit.point;
    let Some(light) = scene.lamps[l].light_at(x.position) else {
        return zero;
    };
    if light.direction.dot(x.normal) <= 0.0 {
        return zero;
    }
    let wl = s.frame.to_local(light.direction);
    if wl.z <= 0.0 {
        return zero;
    }
    let f = brdf(wl);
    if f[0].max_element() <= 0.0 && f[1].max_element() <= 0.0 {
        return zero;
    }
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
    s: &Shading<'_>,
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
pub fn lamp_irradiance(scene: &Scene, s: &Shading<'_>, l: usize, tally: &mut Tally) -> Rgb {
    if !s.hit.front_face {
        return Rgb::ZERO;
    }
    lamp_light(scene, s, l, tally, &|_| [Rgb::ONE, Rgb::ZERO])[0]
}

/// [`lamp_irradiance`] summed over every lamp.
pub fn lamps_irradiance(scene: &Scene, s: &Shading<'_>, tally: &mut Tally) -> Rgb {
    (0..scene.lamps.len())
        .map(|l| lamp_irradiance(scene, s, l, tally))
        .fold(Rgb::ZERO, |a, b| a + b)
}
