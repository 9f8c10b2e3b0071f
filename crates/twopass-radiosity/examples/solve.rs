//! Solves a scene's radiosity and prints the progress, the energy bookkeeping and, for small
//! meshes, the difference to the dense reference solve.
//!
//! `cargo run --release -p twopass-radiosity --example solve -- scenes/cornell-box.toml [unshot]`

mod common;

use std::ops::ControlFlow;

use twopass_radiosity::{Options, ProgressiveSolver, Stop, dense_solve};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (path, unshot) = common::scene_and_unshot()?;
    let (scene, _) = twopass_scene::load(&path)?;
    let options = Options {
        stop: Stop {
            unshot_fraction: unshot,
            ..Stop::default()
        },
        ..Options::default()
    };
    let mut solver = ProgressiveSolver::new(&scene, options)?;
    let start = solver.progress();
    println!(
        "{} patches, {} elements, {} vertices",
        start.patches, start.elements, start.vertices
    );
    let mut last = 0;
    let finish = solver.run(|s| {
        let p = s.progress();
        if p.shots >= last * 2 || p.shots == 1 {
            last = p.shots.max(1);
            println!(
                "shot {:6}  unshot {:.3e}  rays {:10}  {:.2?}",
                p.shots, p.unshot_fraction, p.rays, p.elapsed
            );
        }
        ControlFlow::Continue(())
    });
    let p = solver.progress();
    println!(
        "{finish:?}: {} shots, {} rays, {} elements, {} rounds, unshot {:.3e}, {:.2?}",
        p.shots, p.rays, p.elements, p.refinement_rounds, p.unshot_fraction, p.elapsed
    );
    let e = p.energy;
    println!(
        "energy: emitted {:.4e} absorbed {:.4e} escaped {:.4e} unshot {:.4e} remeshing {:.4e}; worst imbalance {:.2e}",
        e.emitted.element_sum(),
        e.absorbed.element_sum(),
        e.escaped.element_sum(),
        e.unshot.element_sum(),
        e.remeshing.element_sum(),
        p.worst_imbalance
    );
    println!("{:?}", solver.residuals(200));
    if let Some(dense) = dense_solve(&mut solver) {
        let prog = solver.vertex_radiosity();
        let (mut num, mut den) = (0.0, 0.0);
        for (a, b) in prog.iter().zip(&dense) {
            num += (*a - *b).length_squared();
            den += b.length_squared();
        }
        println!(
            "relative RMS difference to the dense solve: {:.3e}",
            (num / den).sqrt()
        );
    }
    Ok(())
}
