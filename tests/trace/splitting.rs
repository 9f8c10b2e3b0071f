//! Path splitting in the path tracer (`ReferenceSettings::splits`, twopass_trace::split_plan):
//! split paths keep the furnace at its closed form, cut the noise of a room's indirect light
//! at equal camera samples, and the plan splits where the continuations carry the noise and
//! not where they carry no light; a planned render is the fixed render of its pick.

use twopass_scene::Scene;
use twopass_trace::{PathSplits, ReferenceSettings, RenderOutput};

use super::common::{render_with, repo_scene, scene};
use super::furnace::{CUBE, assert_reads_one};

/// The reference with `splits`, `size` x `size` pixels, `spp` samples, seed `seed`.
fn render_split(scene: &Scene, splits: PathSplits, size: u32, spp: u32, seed: u64) -> RenderOutput {
    let settings = ReferenceSettings {
        splits,
        ..ReferenceSettings::default()
    };
    render_with(scene, settings, size, spp, seed)
}

/// Each continuation carries `1 / N` of its camera sample, and Russian roulette judges it by
/// the whole path's throughput: the furnace (albedo 0.5, L_e = 0.5 everywhere, L = 1) still
/// reads one, split four ways.
#[test]
fn split_paths_keep_the_furnace_at_one() {
    let s = scene(CUBE);
    let out = render_split(&s, PathSplits::Fixed(4), 32, 16, 5);
    assert_eq!(out.stats.splits, 4);
    assert_eq!(out.stats.non_finite, 0);
    assert_reads_one(&out.layers.composite(), 0.02);
}

/// The relative noise variance of two seeds' images, as the image metric weighs it: per pixel
/// and channel `(a - b)^2 / 2 / (r^2 + 0.01)`, summed, `r` the pixel in `reference`. (Absolute
/// differences would be the edge of the emitter the camera sees, the anti-aliasing's noise.)
fn noise(a: &RenderOutput, b: &RenderOutput, reference: &twopass_image::Image) -> f64 {
    let (a, b) = (a.layers.composite(), b.layers.composite());
    a.pixels()
        .iter()
        .zip(b.pixels())
        .zip(reference.pixels())
        .map(|((x, y), r)| {
            let d = (*x - *y).as_dvec3();
            let r = r.as_dvec3();
            (d * d * 0.5 / (r * r + 0.01)).element_sum()
        })
        .sum()
}

/// In the Cornell box the light arriving after the first bounce is nearly all of the noise
/// (the direct light's share, rendered alone, is about 1 % at 16 samples): four continuations
/// per camera sample, at equal camera samples, should leave at most a quarter of it plus the
/// prefix's share; measured 0.31 here and 0.2 on a 256-pixel-wide image at 16 samples (their
/// points are stratified over the pixel).
/// Half is the bound, with room for two seeds' noise: a Russian roulette that judged each
/// continuation by its 1/4 share alone (ending three in four) leaves 0.54 on that image.
#[test]
fn splitting_cuts_the_noise_of_the_indirect_light() {
    let s = repo_scene("cornell-box.toml");
    let run = |splits, seed| render_split(&s, PathSplits::Fixed(splits), 32, 8, seed);
    let reference = render_split(&s, PathSplits::Fixed(4), 32, 256, 9)
        .layers
        .composite();
    let (one, four) = (
        noise(&run(1, 1), &run(1, 2), &reference),
        noise(&run(4, 1), &run(4, 2), &reference),
    );
    eprintln!("relative noise variance: one continuation {one:.4e}, four {four:.4e}");
    assert!(four < 0.5 * one, "{four} against {one}");
}

/// The plan splits a closed room's paths (its noise is the indirect light, which the
/// continuations carry) and keeps one continuation in a plane lit by a point lamp alone,
/// where a continuation leaves the scene and brings nothing: splitting would only cost.
#[test]
fn the_plan_splits_where_the_continuations_carry_the_noise() {
    let planned = |s: &Scene| {
        let out = render_split(s, PathSplits::Planned, 32, 8, 3);
        let plan = out.stats.split_plan.expect("planned");
        assert_eq!(out.stats.splits, plan.splits);
        assert!(
            (1..=twopass_trace::split_plan::MAX_SPLITS).contains(&plan.splits),
            "{plan:?}"
        );
        assert!(plan.prefix_cost > 0.0, "{plan:?}");
        plan
    };
    let room = planned(&repo_scene("cornell-box.toml"));
    assert!(room.splits > 1, "{room:?}");
    assert!(room.continuation_cost > 0.0, "{room:?}");
    let lamp = scene(
        "version = 1\n[camera]\nposition = [0, 2, 2]\nlook_at = [0, 0, 0]\nfov_y = 60\n\
         [[material]]\nname = \"grey\"\ntype = \"lambert\"\ndiffuse = 0.5\n\
         [[object]]\nname = \"floor\"\nmaterial = \"grey\"\n\
         shape = { type = \"quad\", origin = [-2, 0, -2], edge_u = [0, 0, 4], edge_v = [4, 0, 0] }\n\
         [[light]]\nkind = \"point\"\nposition = [0, 1, 0]\nintensity = 1\n",
    );
    let lamp = planned(&lamp);
    assert_eq!(lamp.splits, 1, "{lamp:?}");
    assert_eq!(lamp.continuation_variance, 0.0, "{lamp:?}");
}

/// A planned render is exactly the render with the plan's count fixed: the pilot's samples
/// are its own, not the image's.
#[test]
fn a_planned_render_is_the_fixed_render_of_its_pick() {
    let s = repo_scene("cornell-box.toml");
    let planned = render_split(&s, PathSplits::Planned, 24, 8, 4);
    let n = planned.stats.split_plan.expect("planned").splits;
    let fixed = render_split(&s, PathSplits::Fixed(n), 24, 8, 4);
    assert!(fixed.stats.split_plan.is_none());
    assert_eq!(fixed.stats.splits, n);
    assert_eq!(planned.layers, fixed.layers);
    assert_eq!(planned.stats.rays, fixed.stats.rays);
}
