//! Scene loading time against the object count (issue 12: it grew quadratically, 14.9 s for
//! 20k objects, because every object's line was found by rescanning the file). Each size loads
//! a generated scene of that many quads, as TOML objects and as OBJ groups; throughput is in
//! objects per second, which stays flat when loading is linear.

use std::hint::black_box;
use std::path::Path;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};

const HEADER: &str = "version = 1\n[camera]\nposition = [15, 15, -50]\nlook_at = [15, 15, 0]\n\
                      fov_y = 40\n[[material]]\nname = \"w\"\ntype = \"lambert\"\ndiffuse = 0.5\n";

/// `n` unit-spaced quads as `[[object]]` tables, the first one emitting.
fn toml_scene(n: usize) -> String {
    let mut s = HEADER.to_owned();
    for i in 0..n {
        let (x, y) = ((i % 100) as f32 * 0.3, (i / 100) as f32 * 0.3);
        s += &format!(
            "[[object]]\nname = \"q{i}\"\nmaterial = \"w\"\n{}shape = {{ type = \"quad\", \
             origin = [{x}, {y}, 0], edge_u = [0.2, 0, 0], edge_v = [0, 0.2, 0] }}\n",
            if i == 0 { "emission = 1\n" } else { "" }
        );
    }
    s
}

/// `n` triangles, one OBJ group each.
fn obj_groups(n: usize) -> String {
    let mut s = String::new();
    for i in 0..n {
        let (x, y) = ((i % 100) as f32 * 0.3, (i / 100) as f32 * 0.3);
        let v = 3 * i + 1;
        s += &format!(
            "g g{i}\nv {x} {y} 0\nv {} {y} 0\nv {x} {} 0\nf {v} {} {}\n",
            x + 0.2,
            y + 0.2,
            v + 1,
            v + 2
        );
    }
    s
}

fn loading(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("twopass-bench-load-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch folder");
    let mut g = c.benchmark_group("load");
    g.sample_size(10);
    for n in [2_500usize, 10_000, 20_000] {
        g.throughput(Throughput::Elements(n as u64));
        let text = toml_scene(n);
        g.bench_function(format!("toml-objects-{n}"), |b| {
            b.iter(|| twopass_scene::load_toml(black_box(&text), Path::new("bench.toml")).unwrap())
        });
        let obj = dir.join(format!("groups-{n}.obj"));
        std::fs::write(&obj, obj_groups(n)).expect("scratch OBJ");
        let scene = dir.join(format!("groups-{n}.toml"));
        std::fs::write(
            &scene,
            format!(
                "{HEADER}[[object]]\nname = \"g\"\nmaterial = \"w\"\nemission = 1\n\
                 shape = {{ type = \"obj\", file = \"groups-{n}.obj\" }}\n"
            ),
        )
        .expect("scratch scene");
        g.bench_function(format!("obj-groups-{n}"), |b| {
            b.iter(|| twopass_scene::load(black_box(&scene)).unwrap())
        });
    }
    g.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, loading);
criterion_main!(benches);
