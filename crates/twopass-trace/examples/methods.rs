//! Renders a scene with every method and prints the render time, rays per second and image
//! mean of each: `cargo run --release -p twopass-trace --example methods -- [SCENE] [SIZE] [SPP]`
//! (defaults: `scenes/cornell-spheres.toml`, 64, 16). The radiosity solve (default options)
//! is timed separately. Timing lives here, not in tests.

use std::ops::ControlFlow;
use std::time::Instant;

use twopass_trace::hybrid::{DirectLight, gathered, hybrid, radiosity_only};
use twopass_trace::whitted::ambient_estimate;
use twopass_trace::{
    Integrator, Reference, ReferenceSettings, RenderProgress, RenderSettings, Whitted,
    WhittedSettings, render,
};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/cornell-spheres.toml"
        )
        .into()
    });
    let size: u32 = args.next().map_or(Ok(64), |s| s.parse())?;
    let spp: u32 = args.next().map_or(Ok(16), |s| s.parse())?;
    let (scene, _) = twopass_scene::load(&path)?;
    let camera = scene.camera.with_resolution(Some(size), Some(size));

    let t = Instant::now();
    let mut solver = twopass_radiosity::Solver::new(&scene, twopass_radiosity::Options::default())?;
    let _ = solver.run(|_| ControlFlow::Continue(()));
    let solution = solver.solution();
    println!("radiosity solve: {:.2} s", t.elapsed().as_secs_f64());

    let settings = RenderSettings {
        samples_per_pixel: spp,
        ..Default::default()
    };
    let w = WhittedSettings::default();
    let methods: Vec<Box<dyn Integrator + '_>> = vec![
        Box::new(Whitted::new(&scene, ambient_estimate(&scene), w)),
        Box::new(radiosity_only(&scene, &solution)),
        Box::new(gathered(&scene, &solution, w)),
        Box::new(hybrid(&scene, &solution, DirectLight::FromSolution, w)),
        Box::new(hybrid(&scene, &solution, DirectLight::PerPixel, w)),
        Box::new(Reference::new(&scene, ReferenceSettings::default())),
    ];
    println!(
        "{size} x {size}, {spp} spp, {} threads",
        rayon::current_num_threads()
    );
    println!("| method | time (s) | Mrays/s | non-finite | mean RGB |");
    println!("| --- | --- | --- | --- | --- |");
    for m in &methods {
        let out = render(
            &scene,
            &camera,
            m.as_ref(),
            &settings,
            &RenderProgress::new(),
        );
        let s = out.stats;
        let mean = out.layers.composite().mean();
        println!(
            "| {} | {:.3} | {:.2} | {} | {:.4} {:.4} {:.4} |",
            s.method,
            s.elapsed.as_secs_f64(),
            s.rays_per_second() / 1e6,
            s.non_finite,
            mean.x,
            mean.y,
            mean.z
        );
    }
    Ok(())
}
