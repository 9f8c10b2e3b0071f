//! Solves one scene with both radiosity solvers, progressive refinement and hierarchical
//! radiosity with clustering, and prints their costs and how far apart their radiosities are
//! (relative RMS over the hierarchical solver's vertices, the progressive solution looked up
//! at the same points).
//!
//! `cargo run --release -p twopass-radiosity --example solvers -- scenes/cornell-box.toml [unshot]`
//!
//! The scene may be `generate:N` (the generated benchmark room of about N triangles). For
//! diagnosis, environment variables set: `TOL` (link tolerance), `MIN` (smallest element
//! edge), `ELEM` (progressive element size), `OCCLUSION=0` (no shadow rays), `PER_OBJECT`
//! (reflected power per object, direct and indirect), `PER_VERTEX` (the same from vertex
//! values), `HIERARCHICAL_ONLY` (skip progressive refinement, for large scenes), `VIS_MIN` and
//! `VIS_MAX` (shadow rays per visibility estimate, first and most).

mod common;

use std::time::Instant;

use glam::Vec3;
use twopass_radiosity::{HierarchicalOptions, Method, Options, Solution, Solver, Stop};
use twopass_scene::DiffuseRadiance;

fn solve(
    scene: &twopass_scene::Scene,
    method: Method,
    unshot: f64,
) -> Result<Solution, Box<dyn std::error::Error>> {
    let options = Options {
        method,
        hierarchical: HierarchicalOptions {
            link_tolerance: std::env::var("TOL").map_or(Ok(2e-5), |s| s.parse())?,
            min_element_size: std::env::var("MIN").ok().map(|s| s.parse()).transpose()?,
        },
        stop: Stop {
            unshot_fraction: unshot,
            ..Stop::default()
        },
        element_size: std::env::var("ELEM").ok().map(|s| s.parse()).transpose()?,
        occlusion: std::env::var("OCCLUSION").map_or(true, |s| s != "0"),
        visibility: twopass_radiosity::VisibilityRays {
            min: std::env::var("VIS_MIN").map_or(Ok(4), |s| s.parse())?,
            max: std::env::var("VIS_MAX").map_or(Ok(16), |s| s.parse())?,
        },
        ..Options::default()
    };
    let t = Instant::now();
    let mut solver = Solver::new(scene, options)?;
    let finish = solver.run(|_| std::ops::ControlFlow::Continue(()));
    let p = solver.progress();
    let r = solver.residuals(200);
    println!(
        "{:>12}: {finish:?} in {:.2} s (refining {:.2}); {} elements, {} vertices, {} links, \
         {} iterations, {} shots, {:.1} M rays, residual {:.1e}, imbalance {:.1e}, row sums \
         {:.3}..{:.3} (mean {:.4}), reciprocity {:.2e}",
        method.name(),
        t.elapsed().as_secs_f64(),
        p.refining.as_secs_f64(),
        p.elements,
        p.vertices,
        p.links,
        p.iterations,
        p.shots,
        p.rays as f64 / 1e6,
        p.unshot_fraction,
        p.worst_imbalance,
        r.row_sum_min,
        r.row_sum_max,
        r.row_sum_mean,
        r.reciprocity_mean
    );
    Ok(solver.solution())
}

/// Power per object (W per channel summed): direct and indirect (with ambient) reflected
/// light, each leaf's area times the mean of its vertices.
fn object_power(scene: &twopass_scene::Scene, s: &Solution) -> Vec<(f64, f64)> {
    let mesh = s.mesh();
    let mut out = vec![(0.0, 0.0); scene.objects.len()];
    for n in mesh.leaves() {
        let node = &mesh.nodes[n as usize];
        let o = scene.mesh.object_of(node.scene_triangle) as usize;
        let a = f64::from(node.area);
        for &v in &node.vertices {
            let v = v as usize;
            out[o].0 += a / 3.0 * f64::from(s.direct()[v].element_sum());
            out[o].1 += a / 3.0 * f64::from((s.indirect()[v] + s.ambient()[v]).element_sum());
        }
    }
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (path, unshot) = common::scene_and_unshot()?;
    let (scene, _) = match path.strip_prefix("generate:") {
        Some(n) => twopass_scene::workload::synthetic_scene(n.parse()?, 0)?,
        None => twopass_scene::load(&path)?,
    };
    let hier = solve(&scene, Method::Hierarchical, unshot)?;
    if std::env::var_os("HIERARCHICAL_ONLY").is_some() {
        return Ok(());
    }
    let prog = solve(&scene, Method::Progressive, unshot)?;
    let (mut num, mut den) = (0.0f64, 0.0f64);
    let (mut mh, mut mp) = (Vec3::ZERO, Vec3::ZERO);
    let mesh = hier.mesh();
    let radiosity = hier.vertex_radiosity();
    for (v, vert) in mesh.vertices.iter().enumerate() {
        let b = scene
            .mesh
            .barycentric(vert.triangle, vert.position.as_dvec3())
            .map(|x| x as f32);
        let p = prog.radiance(vert.triangle, b) * std::f32::consts::PI;
        let h = radiosity[v];
        num += f64::from((h - p).length_squared());
        den += f64::from(p.length_squared());
        mh += h;
        mp += p;
    }
    let n = mesh.vertices.len() as f32;
    // Direct and indirect parts apart, over the vertices that do not emit.
    let (mut dh, mut dp, mut ih, mut ip, mut m) = (0.0f32, 0.0f32, 0.0f32, 0.0f32, 0);
    let (ph, pp) = (object_power(&scene, &hier), object_power(&scene, &prog));
    let total = |p: &[(f64, f64)]| p.iter().fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    let (th, tp) = (total(&ph), total(&pp));
    println!(
        "reflected power, hierarchical / progressive: direct {:.4}, indirect {:.4}",
        th.0 / tp.0,
        th.1 / tp.1
    );
    if std::env::var_os("PER_OBJECT").is_some() {
        for (o, (h, p)) in ph.iter().zip(&pp).enumerate() {
            println!(
                "  {:>20}: power ratio direct {:.4}, indirect {:.4}",
                scene.objects[o].name,
                h.0 / p.0,
                h.1 / p.1
            );
        }
    }
    let mut per_object = vec![(0.0f32, 0.0f32, 0.0f32, 0.0f32); scene.objects.len()];
    for (v, vert) in mesh.vertices.iter().enumerate() {
        if scene.objects[vert.object as usize].emission != Vec3::ZERO {
            continue;
        }
        let b = scene
            .mesh
            .barycentric(vert.triangle, vert.position.as_dvec3())
            .map(|x| x as f32);
        dh += hier.direct()[v].element_sum();
        ih += (hier.indirect()[v] + hier.ambient()[v]).element_sum();
        let total = prog.radiance(vert.triangle, b) * std::f32::consts::PI;
        let ind = prog.indirect_radiance(vert.triangle, b) * std::f32::consts::PI;
        dp += (total - ind).element_sum();
        ip += ind.element_sum();
        m += 1;
        let o = vert.object as usize;
        per_object[o].0 += (hier.indirect()[v] + hier.ambient()[v]).element_sum();
        per_object[o].1 += ind.element_sum();
        per_object[o].2 += hier.direct()[v].element_sum();
        per_object[o].3 += (total - ind).element_sum();
    }
    let m = m as f32;
    if std::env::var_os("PER_VERTEX").is_some() {
        for (o, (a, b, c, d)) in per_object.iter().enumerate() {
            println!(
                "  {:>12}: indirect ratio {:.4}, direct ratio {:.4}",
                scene.objects[o].name,
                a / b,
                c / d
            );
        }
    }
    println!(
        "non-emitting vertices: direct {:.4} vs {:.4} (ratio {:.4}), indirect {:.4} vs {:.4} (ratio {:.4})",
        dh / m,
        dp / m,
        dh / dp,
        ih / m,
        ip / m,
        ih / ip
    );
    println!(
        "relative RMS hierarchical vs progressive: {:.4}; means {:?} vs {:?}",
        (num / den).sqrt(),
        mh / n,
        mp / n
    );
    Ok(())
}
