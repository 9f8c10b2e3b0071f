//! Ray queries per second on the Cornell box and on a generated 100k-triangle scene, for the
//! three kinds of query the passes cast (single thread; `twopass bench rays` measures all
//! threads). Throughput is reported in rays (elements) per second.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use twopass_scene::{Ray, Scene, load, workload};

const RAYS: usize = 1 << 14;

fn scenes() -> Vec<(&'static str, Scene)> {
    let cornell = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.toml");
    vec![
        ("cornell-box", load(cornell).expect("cornell box loads").0),
        (
            "generated-100k",
            workload::synthetic_scene(100_000, 0)
                .expect("generated scene loads")
                .0,
        ),
    ]
}

/// How many of `rays` hit the scene (the closest-hit query, its result kept from the optimiser).
fn hits(scene: &Scene, rays: &[Ray]) -> usize {
    rays.iter()
        .filter(|r| scene.intersect(black_box(r)).is_some())
        .count()
}

fn queries(c: &mut Criterion) {
    for (name, scene) in scenes() {
        let mut g = c.benchmark_group(name);
        g.throughput(Throughput::Elements(RAYS as u64));
        let camera: Vec<_> = workload::camera_rays(&scene)
            .into_iter()
            .step_by(16)
            .take(RAYS)
            .collect();
        g.throughput(Throughput::Elements(camera.len() as u64));
        g.bench_function("camera", |b| b.iter(|| hits(&scene, &camera)));
        g.throughput(Throughput::Elements(RAYS as u64));
        let incoherent = workload::incoherent_rays(&scene, RAYS, 1);
        g.bench_function("incoherent", |b| b.iter(|| hits(&scene, &incoherent)));
        let pairs = workload::occlusion_pairs(&scene, RAYS, 2);
        g.bench_function("occlusion", |b| {
            b.iter(|| {
                pairs
                    .iter()
                    .filter(|(a, p)| scene.occluded_between(black_box(a), p))
                    .count()
            })
        });
        g.finish();
    }
}

fn build(c: &mut Criterion) {
    let (_, scene) = scenes().pop().expect("two scenes");
    c.bench_function("build/generated-100k", |b| {
        b.iter(|| black_box(&scene.mesh).accel())
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = queries, build
}
criterion_main!(benches);
