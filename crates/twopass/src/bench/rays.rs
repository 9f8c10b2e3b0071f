//! `twopass bench rays`: ray queries per second (camera, incoherent, occlusion) on one and on
//! all threads, one ray at a time and through the many-ray calls, and the BVH build time. It
//! measures the accelerator's queries ([`Accel::closest`], [`Accel::any_hit`] and their
//! many-ray forms) as another engine's are measured: the hit's shading data that
//! `Scene::intersect` adds (normals, material) is not part of a ray query.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;
use rayon::prelude::*;
use serde::Serialize;
use twopass_scene::workload::{self, QueryKind};
use twopass_scene::{Accel, Ray, Scene};

use super::memory::{fmt_mib, mib, peak_memory, reset_peak_memory};
use crate::args::checked;
use crate::context::Context;
use crate::error::CliError;

/// Arguments of `twopass bench rays`.
#[derive(Debug, Args)]
pub struct RaysArgs {
    /// Scene file (.toml or .obj); omit it with `--generate`.
    #[arg(required_unless_present = "generate")]
    pub scene: Option<PathBuf>,
    /// Instead of a file, generate a scene of about this many triangles (the Cornell room
    /// filled with icospheres).
    #[arg(long, conflicts_with = "scene", value_parser = clap::value_parser!(u64).range(1..=50_000_000))]
    pub generate: Option<u64>,
    /// Incoherent and occlusion rays per batch.
    #[arg(long, default_value_t = 1 << 18, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    pub rays: u64,
    /// Minimum measuring time per query and thread count, seconds.
    #[arg(long, default_value_t = 1.0, value_parser = parse_seconds)]
    pub seconds: f64,
    /// Also write the scene's triangles, the three ray batches exactly as cast, and this
    /// engine's answers to DIR as raw little-endian arrays (described in DIR/rays.json), so
    /// another ray engine can cast the same queries (`crates/twopass/bench/embree_rays.py`).
    #[arg(long, value_name = "DIR")]
    pub export: Option<PathBuf>,
}

/// One measured ray query: rates on one and on all threads, one ray at a time
/// ([`Accel::closest`], [`Accel::any_hit`]) and through the many-ray calls
/// ([`Accel::closest_many`], [`Accel::any_hit_many`], in batches of [`CHUNK`] rays: interleaved
/// where the tree is larger than [`twopass_scene::INTERLEAVE_MIN_BYTES`] and the batch is not
/// coherent; coherent closest-hit batches, as camera rays are, walked eight rays to a packet).
#[derive(Debug, Serialize)]
struct RayRow {
    query: &'static str,
    rays: usize,
    /// Millions of rays per second on one thread, one ray at a time.
    mrays_1: f64,
    /// Millions of rays per second on all threads, one ray at a time.
    mrays_n: f64,
    /// mrays_n / mrays_1.
    speedup: f64,
    /// Millions of rays per second on one thread, through the many-ray calls.
    many_mrays_1: f64,
    /// Millions of rays per second on all threads, through the many-ray calls.
    many_mrays_n: f64,
    /// Fraction of rays that hit (closest hit) or are blocked (occlusion).
    hit_fraction: f64,
    /// Largest resident memory while measuring this query (scene, BVH and ray batch), MiB.
    peak_memory_mib: Option<f64>,
}

/// The `bench rays` report.
#[derive(Debug, Serialize)]
struct RayReport {
    scene: String,
    triangles: usize,
    threads: usize,
    /// Median of 5 builds, milliseconds.
    bvh_build_ms: f64,
    bvh_nodes: usize,
    /// Triangle packets (up to four triangles each).
    bvh_packets: usize,
    /// The tree's nodes and packets, MiB.
    bvh_mib: f64,
    rows: Vec<RayRow>,
}

/// Rays per chunk: one rayon job when casting on all threads, one many-ray call.
const CHUNK: usize = 1024;

/// One batch of rays as the accelerator receives them: closest-hit rays, or occlusion
/// segments (already offset off their surfaces, [`Scene::segment_between`]).
enum Batch {
    Closest(Vec<Ray>),
    Occlusion(Vec<Ray>),
}

impl Batch {
    fn rays(&self) -> &[Ray] {
        match self {
            Self::Closest(r) | Self::Occlusion(r) => r,
        }
    }

    /// Casts one ray: whether it hits (closest) or is blocked (occlusion). The accelerator's
    /// queries, as another engine's (Embree's `rtcIntersect1`, `rtcOccluded1`): the shading
    /// data `Scene::intersect` adds to a hit is not part of it.
    #[inline]
    fn cast_one(&self, accel: &Accel, r: &Ray) -> bool {
        match self {
            Self::Closest(_) => accel.closest(r.origin, r.direction, r.t_max).is_some(),
            Self::Occlusion(_) => accel.any_hit(r.origin, r.direction, r.t_max),
        }
    }

    /// This engine's answer per ray: the hit triangle and `t` (closest hit; -1 and infinity
    /// for a miss), or 1 and 0 for blocked and 0 and infinity for clear (occlusion).
    fn answers(&self, accel: &Accel) -> Vec<(i32, f32)> {
        self.rays()
            .par_iter()
            .map(|r| match self {
                Self::Closest(_) => accel
                    .closest(r.origin, r.direction, r.t_max)
                    .map_or((-1, f32::INFINITY), |h| (h.triangle as i32, h.t)),
                Self::Occlusion(_) if accel.any_hit(r.origin, r.direction, r.t_max) => (1, 0.0),
                Self::Occlusion(_) => (0, f32::INFINITY),
            })
            .collect()
    }

    fn len(&self) -> usize {
        self.rays().len()
    }

    /// Casts `rays` through the many-ray calls ([`Accel::closest_many`],
    /// [`Accel::any_hit_many`]); returns how many hit.
    fn cast_many(&self, accel: &Accel, rays: &[Ray]) -> usize {
        match self {
            Self::Closest(_) => {
                let mut hits = vec![None; rays.len()];
                accel.closest_many(rays, &mut hits);
                hits.iter().filter(|h| h.is_some()).count()
            }
            Self::Occlusion(_) => {
                let mut blocked = vec![false; rays.len()];
                accel.any_hit_many(rays, &mut blocked);
                blocked.iter().filter(|&&b| b).count()
            }
        }
    }

    /// Casts the whole batch once, in chunks of [`CHUNK`] rays (one rayon job each when
    /// `parallel`), one ray at a time or through the many-ray calls; returns how many rays
    /// hit.
    fn cast(&self, accel: &Accel, parallel: bool, many: bool) -> usize {
        let chunk = |c: &[Ray]| {
            if many {
                self.cast_many(accel, c)
            } else {
                c.iter().filter(|r| self.cast_one(accel, r)).count()
            }
        };
        let rays = self.rays();
        if parallel {
            rays.par_chunks(CHUNK).map(chunk).sum()
        } else {
            rays.chunks(CHUNK).map(chunk).sum()
        }
    }

    /// Rays per second (casting repeatedly for at least `min`) and the hit fraction.
    fn measure(&self, accel: &Accel, parallel: bool, many: bool, min: Duration) -> (f64, f64) {
        let hits = self.cast(accel, parallel, many); // warm-up, also the hit count
        let start = Instant::now();
        let mut passes = 0usize;
        while passes == 0 || start.elapsed() < min {
            std::hint::black_box(self.cast(accel, parallel, many));
            passes += 1;
        }
        let rate = (passes * self.len()) as f64 / start.elapsed().as_secs_f64();
        (rate, hits as f64 / self.len().max(1) as f64)
    }
}

/// Little-endian bytes of a list of f32 or i32/u32 values.
fn le_bytes<T: Copy, const N: usize>(
    values: impl Iterator<Item = T>,
    f: fn(T) -> [u8; N],
) -> Vec<u8> {
    values.flat_map(f).collect()
}

/// Writes `bench rays --export`: the triangles, each batch's rays and this engine's answers.
fn export(
    dir: &std::path::Path,
    scene: &Scene,
    batches: &[(QueryKind, &str, Batch)],
) -> Result<(), CliError> {
    use crate::output::write_atomic;
    let mesh = &scene.mesh;
    let positions = mesh.positions().flat_map(|p| p.to_array());
    write_atomic(
        &dir.join("positions.f32"),
        &le_bytes(positions, f32::to_le_bytes),
    )?;
    let triangles = mesh.triangles().flatten();
    write_atomic(
        &dir.join("triangles.u32"),
        &le_bytes(triangles, u32::to_le_bytes),
    )?;
    let mut kinds = Vec::new();
    for (kind, _, batch) in batches {
        let name = match kind {
            QueryKind::Camera => "camera",
            QueryKind::Incoherent => "incoherent",
            QueryKind::Occlusion => "occlusion",
        };
        let rays = batch.rays().iter().flat_map(|r| {
            let (o, d) = (r.origin, r.direction);
            [o.x, o.y, o.z, d.x, d.y, d.z, r.t_max]
        });
        write_atomic(
            &dir.join(format!("{name}.rays")),
            &le_bytes(rays, f32::to_le_bytes),
        )?;
        let answers = batch.answers(scene.accel());
        let ids = answers.iter().map(|a| a.0);
        write_atomic(
            &dir.join(format!("{name}.ids")),
            &le_bytes(ids, i32::to_le_bytes),
        )?;
        let ts = answers.iter().map(|a| a.1);
        write_atomic(
            &dir.join(format!("{name}.t")),
            &le_bytes(ts, f32::to_le_bytes),
        )?;
        kinds.push(serde_json::json!({
            "name": name,
            "query": if matches!(batch, Batch::Closest(_)) { "closest" } else { "any" },
            "rays": batch.len(),
        }));
    }
    let manifest = serde_json::json!({
        "format": "twopass bench rays export 1",
        "triangles": mesh.triangle_count(),
        "vertices": mesh.vertex_count(),
        "files": {
            "positions.f32": "vertex positions, x y z, f32 little-endian",
            "triangles.u32": "vertex indices, 3 per triangle, u32 little-endian",
            "NAME.rays": "per ray: origin x y z, direction x y z, t_max (t in (0, t_max], in units of |direction|), f32 little-endian",
            "NAME.ids": "per ray, i32 little-endian: the hit triangle or -1 (closest); 1 blocked, 0 clear (any)",
            "NAME.t": "per ray, f32 little-endian: t of the closest hit, infinity for a miss; 0 blocked, infinity clear (any)",
        },
        "batches": kinds,
    });
    let text = serde_json::to_string_pretty(&manifest).map_err(|e| CliError::Encode {
        path: dir.join("rays.json"),
        message: e.to_string(),
    })?;
    write_atomic(&dir.join("rays.json"), text.as_bytes())
}

/// A measuring time: more than 0 and at most a day, seconds.
fn parse_seconds(s: &str) -> Result<f64, String> {
    let in_range = |x: &f64| *x > 0.0 && *x <= 86_400.0;
    checked(s, in_range, "must be more than 0 and at most 86400 seconds")
}

/// Measures the BVH build and the ray queries.
pub fn run(args: &RaysArgs, ctx: &Context) -> Result<(), CliError> {
    let (scene, name) = match (&args.scene, args.generate) {
        (_, Some(n)) => (
            workload::synthetic_scene(n as usize, ctx.seed)?.0,
            format!("generated ({n} triangles requested)"),
        ),
        (Some(path), None) => (ctx.load_scene(path)?.0, path.display().to_string()),
        (None, None) => unreachable!("clap requires a scene or --generate"),
    };
    let mut scene = scene;
    scene.camera = ctx.camera(&scene.camera)?;
    let n = args.rays as usize;
    let batches = [
        (
            QueryKind::Camera,
            "camera (coherent)",
            Batch::Closest(workload::camera_rays(&scene)),
        ),
        (
            QueryKind::Incoherent,
            "incoherent",
            Batch::Closest(workload::incoherent_rays(&scene, n, ctx.seed)),
        ),
        (
            QueryKind::Occlusion,
            "occlusion",
            Batch::Occlusion(
                workload::occlusion_pairs(&scene, n, ctx.seed ^ 0x5eed)
                    .iter()
                    .map(|(a, b)| Scene::segment_between(a, b))
                    .collect(),
            ),
        ),
    ];
    if let Some(dir) = &args.export {
        export(dir, &scene, &batches)?;
    }
    let progress = ctx.progress(13, "bench rays");
    let mut builds: Vec<f64> = (0..5)
        .map(|_| {
            let a = scene.mesh.accel();
            a.build_time().as_secs_f64() * 1e3
        })
        .collect();
    builds.sort_by(f64::total_cmp);
    progress.inc(1);
    let min = Duration::from_secs_f64(args.seconds);
    let mut rows = Vec::new();
    for (_, label, batch) in &batches {
        reset_peak_memory();
        let mut rates = [[0.0; 2]; 2];
        let mut hit = 0.0;
        for (many, rates) in [false, true].into_iter().zip(&mut rates) {
            for (parallel, rate) in [false, true].into_iter().zip(rates.iter_mut()) {
                (*rate, hit) = batch.measure(scene.accel(), parallel, many, min);
                progress.inc(1);
            }
        }
        let [[r1, rn], [i1, i_n]] = rates;
        rows.push(RayRow {
            query: label,
            rays: batch.len(),
            mrays_1: r1 / 1e6,
            mrays_n: rn / 1e6,
            speedup: rn / r1,
            many_mrays_1: i1 / 1e6,
            many_mrays_n: i_n / 1e6,
            hit_fraction: hit,
            peak_memory_mib: mib(peak_memory()),
        });
    }
    progress.finish_and_clear();
    let report = RayReport {
        scene: name,
        triangles: scene.mesh.triangle_count(),
        threads: rayon::current_num_threads(),
        bvh_build_ms: builds[2],
        bvh_nodes: scene.accel().node_count(),
        bvh_packets: scene.accel().quad_count(),
        bvh_mib: scene.accel().bytes() as f64 / f64::from(1 << 20),
        rows,
    };
    crate::output::report(&report, ctx, || {
        outln!(
            "scene {}: {} triangles, BVH {} nodes and {} packets ({:.1} MiB) built in {:.2} ms \
             (median of 5), {} threads",
            report.scene,
            report.triangles,
            report.bvh_nodes,
            report.bvh_packets,
            report.bvh_mib,
            report.bvh_build_ms,
            report.threads
        );
        outln!(
            "{:<18} {:>9} {:>14} {:>14} {:>9} {:>14} {:>14} {:>7} {:>9}",
            "query",
            "rays",
            "1 thr Mrays/s",
            format!("{} thr Mrays/s", report.threads),
            "speed-up",
            "many-ray 1",
            format!("many-ray {}", report.threads),
            "hit %",
            "peak MiB"
        );
        for r in &report.rows {
            outln!(
                "{:<18} {:>9} {:>14.2} {:>14.2} {:>8.2}x {:>14.2} {:>14.2} {:>6.1}% {:>9}",
                r.query,
                r.rays,
                r.mrays_1,
                r.mrays_n,
                r.speedup,
                r.many_mrays_1,
                r.many_mrays_n,
                100.0 * r.hit_fraction,
                fmt_mib(r.peak_memory_mib)
            );
        }
        Ok(())
    })
}
