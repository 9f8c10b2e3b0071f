//! Evaluations per second of each reflection model (criterion). Each iteration evaluates one
//! BRDF on 1024 precomputed direction pairs, so the figures compare the models' arithmetic,
//! not the random-number generator. Report them as ratios to Lambert (docs/benchmarks.md).

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use twopass_brdf::check::Pcg32;
use twopass_brdf::sample::square_to_cosine_hemisphere;
use twopass_brdf::{
    BlinnPhongParams, Brdf, BrdfModel, ComplexIor, CookTorranceParams, FresnelModel, Material,
    PhongParams, Rgb,
};

fn models() -> Vec<(&'static str, BrdfModel)> {
    let phong = |normalized| {
        Material::phong(PhongParams {
            diffuse: Rgb::splat(0.3),
            specular: Rgb::splat(0.5),
            exponent: 40.0,
            ambient: Rgb::ZERO,
            normalized,
        })
        .unwrap()
        .model()
        .unwrap()
    };
    let blinn = |normalized| {
        Material::blinn_phong(BlinnPhongParams {
            diffuse: Rgb::splat(0.3),
            specular: Rgb::splat(0.5),
            exponent: 160.0,
            normalized,
        })
        .unwrap()
        .model()
        .unwrap()
    };
    let cook = |fresnel, ior| {
        Material::cook_torrance(CookTorranceParams {
            diffuse: Rgb::splat(0.3),
            specular: Rgb::splat(0.5),
            roughness: 0.2,
            ior,
            fresnel,
        })
        .unwrap()
        .model()
        .unwrap()
    };
    let gold = ComplexIor::conductor("gold").unwrap();
    vec![
        (
            "lambert",
            Material::lambert(Rgb::splat(0.5)).unwrap().model().unwrap(),
        ),
        ("phong", phong(false)),
        ("modified_phong", phong(true)),
        ("blinn_phong", blinn(false)),
        ("blinn_phong_normalized", blinn(true)),
        ("cook_torrance_exact", cook(FresnelModel::Exact, gold)),
        ("cook_torrance_schlick", cook(FresnelModel::Schlick, gold)),
    ]
}

fn eval(c: &mut Criterion) {
    let mut rng = Pcg32::new(1, 1);
    let pairs: Vec<(Vec3, Vec3)> = (0..1024)
        .map(|_| {
            (
                square_to_cosine_hemisphere(rng.next_vec2()),
                square_to_cosine_hemisphere(rng.next_vec2()),
            )
        })
        .collect();
    let mut group = c.benchmark_group("eval");
    group.throughput(Throughput::Elements(pairs.len() as u64));
    for (name, model) in models() {
        group.bench_function(name, |b| {
            b.iter(|| {
                let m = black_box(&model);
                let mut acc = Rgb::ZERO;
                for &(wo, wi) in black_box(&pairs) {
                    acc += m.eval(wo, wi);
                }
                acc
            })
        });
    }
    group.finish();
}

criterion_group!(benches, eval);
criterion_main!(benches);
