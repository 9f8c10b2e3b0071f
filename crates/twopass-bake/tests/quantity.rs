//! The lightmap's two quantities: on a scene whose surfaces share one Lambertian albedo rho,
//! the radiance lightmap is rho times the irradiance lightmap (E / pi), plus the emission on
//! the emitter's texels, texel for texel; a glTF scene bakes irradiance unless told otherwise.

use twopass_bake::ColorMapping;
use twopass_bake::lightmap::{LightmapQuantity, LightmapSettings, TexelSource, bake_lightmap};
use twopass_brdf::Rgb;

use crate::common::{repo, solve};

/// The white of the Cornell box, given here to its red and green walls too.
const WHITE: [f32; 3] = [0.725, 0.71, 0.68];

#[test]
fn radiance_is_albedo_times_irradiance_plus_emission() {
    let text = std::fs::read_to_string(repo().join("scenes/cornell-box.toml"))
        .unwrap()
        .replace("[0.63, 0.065, 0.05]", "[0.725, 0.71, 0.68]")
        .replace("[0.14, 0.45, 0.091]", "[0.725, 0.71, 0.68]");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("white-box.toml");
    let (scene, _) = twopass_scene::load_toml(&text, &path).unwrap();
    assert!(
        scene
            .materials
            .iter()
            .all(|m| m.material.diffuse_albedo().to_array() == WHITE)
    );
    let emission = scene.emitters[0].radiance;
    let solution = solve(&scene, 60.0);
    let bake = |quantity| {
        let settings = LightmapSettings {
            texel_size: Some(8.0),
            padding: 2,
            quantity: Some(quantity),
            ..Default::default()
        };
        bake_lightmap(
            TexelSource::Solution(&solution),
            &scene,
            &settings,
            ColorMapping { exposure: 1.0 },
        )
        .unwrap()
    };
    let radiance = bake(LightmapQuantity::Radiance);
    let irradiance = bake(LightmapQuantity::Irradiance);
    assert_eq!(radiance.quantity, LightmapQuantity::Radiance);
    assert_eq!(irradiance.quantity, LightmapQuantity::Irradiance);
    // A TOML scene bakes radiance by default.
    assert_eq!(
        LightmapQuantity::for_scene(&scene),
        LightmapQuantity::Radiance
    );
    let rho = Rgb::from_array(WHITE);
    let (mut lit, mut emitting) = (0, 0);
    for (l, e) in radiance
        .radiance
        .pixels()
        .iter()
        .zip(irradiance.radiance.pixels())
    {
        let reflected = rho * *e;
        let tolerance = 1e-4 * l.max_element().max(1.0);
        if (*l - reflected).abs().max_element() <= tolerance {
            lit += usize::from(l.max_element() > 0.0);
        } else {
            // The emitter's own texels: the radiance adds its emission, the irradiance not.
            assert!(
                (*l - reflected - emission).abs().max_element() <= tolerance,
                "radiance {l}, albedo x irradiance {reflected}, emission {emission}"
            );
            emitting += 1;
        }
    }
    assert!(
        lit > 1000 && emitting > 10,
        "{lit} lit, {emitting} emitting texels"
    );
}
