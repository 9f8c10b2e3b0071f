//! `twopass bake SCENE --from X.bake --part I/N`: the I-th of N shards of a bake's final
//! gather over a saved solution, written as a part file; and the merge of a whole set into the
//! files the single-process bake writes.
//!
//! A `.bake` file holds the element mesh and its radiosity with the scene's fingerprints, not
//! the scene (materials, emitters, the triangles the gather's rays hit) nor the atlas (which is
//! laid out from the scene's triangles): so `--from` takes the `.bake` beside the same scene
//! argument, and `read_bake` refuses a scene whose fingerprints differ from the recorded ones.
//!
//! Every gathered point's random sequence is keyed by its index (a texel's in the atlas, a
//! vertex's in its output plus `VERTEX_KEYS` or `ELEMENT_KEYS`), so a shard is the points whose
//! key is I - 1 modulo N, interleaved so that every shard gets cheap and costly regions alike.
//! A part runs the bake's own code with an estimator that gathers its shard's points, records
//! their estimates and answers the others with nothing; the merge runs it again with an
//! estimator that replays the recorded estimates, so everything computed from them (the
//! lightmap's filter over each chart, the dilation, the encodings, the manifest's ray counts)
//! runs once, over the whole set, exactly as in the single process.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use clap::{Parser, ValueEnum};
use serde::Serialize;
use serde_json::{Value, json};
use twopass_bake::{ColorMapping, TexelSource};
use twopass_radiosity::Solution;
use twopass_scene::{RadianceEstimate, RadianceEstimator, Scene};
use twopass_trace::gather::Gatherer;

use super::file::{Cost, PartHeader, PartIndex, encode, part_path, stem};
use super::set::PartSet;
use crate::bake::{BakeArgs, BakeSet, Format, lock_folder, write_set};
use crate::context::Context;
use crate::error::CliError;
use crate::final_gather::{Gather, gather_elements};

/// `f32` words per recorded estimate: the key (2), the point (triangle and barycentrics, 4),
/// emitted, direct and indirect (9), the indirect error and back-face fraction (2), rays and
/// shadow rays (4).
const WORDS: usize = 21;

/// A gathered point as the bake asks for it: its key, triangle and barycentrics (as bit
/// patterns), so that a replayed estimate is only ever given for the very point it was
/// computed at.
type Point = (u64, u32, [u32; 3]);

fn point(key: u64, triangle: u32, barycentric: [f32; 3]) -> Point {
    (key, triangle, barycentric.map(f32::to_bits))
}

/// Gathers the points of one shard with `inner` and records their estimates; every other
/// point gets an empty estimate (no light, no rays), which the part never writes.
struct Shard<'a> {
    inner: &'a dyn RadianceEstimator,
    part: PartIndex,
    taken: &'a Mutex<Vec<(Point, RadianceEstimate)>>,
}

impl RadianceEstimator for Shard<'_> {
    fn estimate(&self, triangle: u32, barycentric: [f32; 3], key: u64) -> RadianceEstimate {
        if key % u64::from(self.part.of) != u64::from(self.part.index - 1) {
            return RadianceEstimate::default();
        }
        let e = self.inner.estimate(triangle, barycentric, key);
        self.taken
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .push((point(key, triangle, barycentric), e));
        e
    }
}

/// Answers every point with the estimate a part recorded for it; a point no part recorded is
/// kept (and answered with nothing), so the merge can refuse before writing.
struct Replay {
    estimates: HashMap<Point, RadianceEstimate>,
    unknown: Mutex<Option<u64>>,
}

impl RadianceEstimator for Replay {
    fn estimate(&self, triangle: u32, barycentric: [f32; 3], key: u64) -> RadianceEstimate {
        match self.estimates.get(&point(key, triangle, barycentric)) {
            Some(e) => *e,
            None => {
                *self
                    .unknown
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(key);
                RadianceEstimate::default()
            }
        }
    }
}

/// Runs every consumer of the final gather that the bake's flags select, with `estimator`
/// (`elements` for the element mesh's points), asking for exactly the points (and keys)
/// `write_set` asks for.
fn ask_every_point(
    args: &BakeArgs,
    scene: &Scene,
    solution: &Solution,
    estimator: &dyn RadianceEstimator,
    elements: &dyn RadianceEstimator,
) -> Result<(), CliError> {
    let mapping = ColorMapping { exposure: 1.0 };
    if args.gathers_elements() {
        twopass_bake::gathered_solution(solution, scene, elements);
    }
    if args.format.contains(&Format::VertexGlb) {
        twopass_bake::encode_vertex_glb(solution, scene, mapping, Some(estimator))?;
    }
    if args.lightmap {
        let settings = twopass_bake::LightmapSettings {
            texel_size: args.texel_size,
            ..twopass_bake::LightmapSettings::default()
        };
        twopass_bake::bake_lightmap(TexelSource::Gather(estimator), scene, &settings, mapping)?;
    }
    Ok(())
}

/// The bake flags that shape the gathered outputs, as a command line `merge` parses again.
fn bake_flags(args: &BakeArgs) -> Vec<String> {
    let name = |f: &Format| name_of(*f);
    let mut flags = vec![
        "--format".to_owned(),
        args.format.iter().map(name).collect::<Vec<_>>().join(","),
        "--gather".to_owned(),
        match args.gather {
            Gather::Off => "off".to_owned(),
            Gather::Auto => "auto".to_owned(),
            Gather::Rays(n) => n.to_string(),
        },
    ];
    if args.lightmap {
        flags.push("--lightmap".into());
    }
    if let Some(t) = args.texel_size {
        flags.extend(["--texel-size".into(), format!("{t:e}")]);
    }
    if let Some(e) = args.exposure {
        flags.extend(["--exposure".into(), format!("{e:e}")]);
    }
    if let Some(q) = args.lightmap_quantity {
        flags.extend(["--lightmap-quantity".into(), name_of(q)]);
    }
    if args.lightmap {
        flags.extend([
            "--lightmap-encoding".into(),
            name_of(args.lightmap_encoding),
        ]);
    }
    flags
}

/// The command-line name of a value of a `clap::ValueEnum`.
fn name_of(v: impl ValueEnum) -> String {
    v.to_possible_value()
        .map_or_else(String::new, |v| v.get_name().to_owned())
}

#[derive(Serialize)]
struct PartSummary<'a> {
    part: String,
    file: &'a Path,
    points: usize,
    rays: u64,
    shadow_rays: u64,
    seconds: f64,
}

/// Gathers shard `part` over the solution in `from` and writes its part file.
pub fn write_part(
    args: &BakeArgs,
    from: &Path,
    part: PartIndex,
    ctx: &Context,
) -> Result<(), CliError> {
    let started = Instant::now();
    if args.solve.time_budget.is_some() {
        return Err(CliError::Usage(
            "--part with --time-budget: a deadline makes the points gathered after it cheaper, \
             which depends on the clock, so parts would not merge bit for bit"
                .into(),
        ));
    }
    if !args.gathers() {
        return Err(CliError::Usage(
            "--part splits the final gather, and this bake gathers nothing: drop --gather off"
                .into(),
        ));
    }
    let (scene, warnings) = ctx.load_scene(&args.scene)?;
    if !ctx.quiet {
        for w in &warnings {
            errln!("warning: {w}");
        }
    }
    crate::pipeline::check_in_set(from)?;
    let bake_bytes = twopass_scene::read_bounded(from, twopass_bake::MAX_BAKE_BYTES)
        .map_err(|e| CliError::io(from, e))?;
    let solution = decode(&bake_bytes, &scene, from)?;
    let settings = args
        .gather
        .settings(ctx.seed)
        .expect("a bake that gathers has gather settings");
    let gatherer = Gatherer::new(&scene, &solution, settings);
    let rays = args
        .gather
        .element_rays(solution.mesh())
        .unwrap_or(settings.max_rays);
    let fixed = gatherer.fixed(rays);
    let taken = Mutex::new(Vec::new());
    let shard = |inner| Shard {
        inner,
        part,
        taken: &taken,
    };
    ask_every_point(args, &scene, &solution, &shard(&gatherer), &shard(&fixed))?;
    let mut taken = taken
        .into_inner()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    taken.sort_by_key(|(p, _)| *p);
    taken.dedup_by_key(|(p, _)| *p);
    let mut payload = Vec::with_capacity(WORDS * taken.len());
    for ((key, triangle, bary), e) in &taken {
        let words = [
            *key as u32,
            (key >> 32) as u32,
            *triangle,
            bary[0],
            bary[1],
            bary[2],
            e.emitted.x.to_bits(),
            e.emitted.y.to_bits(),
            e.emitted.z.to_bits(),
            e.direct.x.to_bits(),
            e.direct.y.to_bits(),
            e.direct.z.to_bits(),
            e.indirect.x.to_bits(),
            e.indirect.y.to_bits(),
            e.indirect.z.to_bits(),
            e.indirect_error.to_bits(),
            e.back_faces.to_bits(),
            e.rays as u32,
            (e.rays >> 32) as u32,
            e.shadow_rays as u32,
            (e.shadow_rays >> 32) as u32,
        ];
        payload.extend(words.map(f32::from_bits));
    }
    let cost = Cost {
        rays: taken.iter().map(|(_, e)| e.rays).sum(),
        shadow_rays: taken.iter().map(|(_, e)| e.shadow_rays).sum(),
        seconds: started.elapsed().as_secs_f64(),
    };
    let absolute = |p: &Path| std::path::absolute(p).map_err(|e| CliError::io(p, e));
    let header = PartHeader {
        kind: "bake".into(),
        part,
        scene: args.scene.clone(),
        scene_fingerprint: format!("{:016x}", twopass_bake::scene_fingerprint(&scene)),
        settings: match json!({
            "seed": ctx.seed,
            "flags": bake_flags(args),
            "bake": format!("{} crc32 {:08x}", stem(from), crc32fast::hash(&bake_bytes)),
        }) {
            Value::Object(map) => map,
            _ => unreachable!("a JSON object literal"),
        },
        extra: json!({ "scene": absolute(&args.scene)?, "from": absolute(from)? }),
        cost,
    };
    let path = part_path(
        ctx.output.as_deref(),
        &format!("{}-bake", stem(&args.scene)),
        part,
    );
    crate::output::write_atomic(&path, &encode(&header, &payload)?)?;
    let summary = PartSummary {
        part: part.to_string(),
        file: &path,
        points: taken.len(),
        rays: cost.rays,
        shadow_rays: cost.shadow_rays,
        seconds: cost.seconds,
    };
    crate::output::report(&summary, ctx, || {
        outln!(
            "part {} of {}: {} points gathered in {:.2} s ({} rays, {} shadow rays)",
            part.index,
            part.of,
            summary.points,
            summary.seconds,
            summary.rays,
            summary.shadow_rays
        );
        outln!("wrote {}", path.display());
        Ok(())
    })
}

/// `twopass bake` as a parser alone, to read the flags a part recorded.
#[derive(Parser)]
struct BakeLine {
    #[command(flatten)]
    args: BakeArgs,
}

/// Merges a checked set of gather shards into the single-process bake's files, in the
/// `--output` folder (default `bake`); the manifest is the solve's (`<stem>.manifest.json`
/// beside the `.bake`) completed with the gather, and its `total_s` is the whole job's: the
/// solve's, every part's and the merge's seconds.
pub fn merge(set: &PartSet, ctx: &Context, started: Instant) -> Result<(), CliError> {
    let first = &set.parts[0];
    let bad = |what: &str| {
        CliError::Input(format!(
            "{}: a bake part without a valid {what}",
            first.path.display()
        ))
    };
    let path_of = |k: &str| {
        first
            .header
            .extra
            .get(k)
            .and_then(Value::as_str)
            .map(PathBuf::from)
            .ok_or_else(|| bad(k))
    };
    let (scene_path, from) = (path_of("scene")?, path_of("from")?);
    let flags: Vec<String> = set
        .header
        .settings
        .get("flags")
        .cloned()
        .and_then(|f| serde_json::from_value(f).ok())
        .ok_or_else(|| bad("flags"))?;
    let line = BakeLine::try_parse_from(
        std::iter::once("bake".to_owned())
            .chain(std::iter::once(scene_path.display().to_string()))
            .chain(flags),
    )
    .map_err(|e| bad(&format!("bake command line ({e})")))?;
    let args = line.args;
    let (scene, _) = ctx.load_scene(&scene_path)?;
    let fingerprint = format!("{:016x}", twopass_bake::scene_fingerprint(&scene));
    if fingerprint != set.header.scene_fingerprint {
        return Err(CliError::Input(format!(
            "{}: the scene changed since the parts were gathered (fingerprint {fingerprint}, \
             the parts' {}); nothing merged",
            scene_path.display(),
            set.header.scene_fingerprint
        )));
    }
    let bake_bytes = twopass_scene::read_bounded(&from, twopass_bake::MAX_BAKE_BYTES)
        .map_err(|e| CliError::io(&from, e))?;
    let recorded = set.header.settings.get("bake").and_then(Value::as_str);
    let now = format!("{} crc32 {:08x}", stem(&from), crc32fast::hash(&bake_bytes));
    if recorded != Some(now.as_str()) {
        return Err(CliError::Input(format!(
            "{}: not the solution the parts were gathered over ({now}; the parts': {}); \
             nothing merged",
            from.display(),
            recorded.unwrap_or("none")
        )));
    }
    let solution = decode(&bake_bytes, &scene, &from)?;
    let replay = Replay {
        estimates: estimates_of(set)?,
        unknown: Mutex::new(None),
    };
    ask_every_point(&args, &scene, &solution, &replay, &replay)?;
    if let Some(key) = *replay
        .unknown
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
    {
        return Err(CliError::Input(format!(
            "{}: no part holds the point of key {key} (part {} of {}) where this bake asks for \
             it; nothing merged",
            first.path.display(),
            key % u64::from(set.header.part.of) + 1,
            set.header.part.of
        )));
    }
    let manifest_path = from.with_file_name(format!("{}.manifest.json", stem(&from)));
    let text =
        crate::output::read_small(&manifest_path).map_err(|e| CliError::io(&manifest_path, e))?;
    let mut manifest: twopass_bake::Manifest = serde_json::from_slice(&text).map_err(|e| {
        CliError::Input(format!(
            "{}: not a bake manifest ({e}); the merge completes the solve's manifest",
            manifest_path.display()
        ))
    })?;
    manifest.files.clear();
    manifest.color = None;
    manifest.lightmap = None;
    manifest.vertex_gather = None;
    let job_seconds = manifest.timings.total_s + set.cost.seconds;
    let settings = args
        .gather
        .settings(ctx.seed)
        .expect("the parts gathered, so the flags ask for a gather");
    let gatherer = Gatherer::new(&scene, &solution, settings);
    let estimator: &dyn RadianceEstimator = &replay;
    let elements = args.gathers_elements().then(|| {
        let rays = args.gather.element_rays(solution.mesh()).unwrap_or(1);
        gather_elements(&solution, &scene, estimator, rays)
    });
    let dir = ctx.output_or(Path::new("bake"));
    crate::output::create_dir(dir)?;
    let _folder = lock_folder(dir, ctx)?;
    if ctx.chatty() {
        outln!(
            "merged {} gather parts of {}: {} rays, {} shadow rays, {:.2} s in all parts",
            set.header.part.of,
            scene_path.display(),
            set.cost.rays,
            set.cost.shadow_rays,
            set.cost.seconds
        );
    }
    let bake_set = BakeSet {
        dir,
        scene: &scene,
        solution: &solution,
        shown: elements.as_ref().map_or(&solution, |(s, _)| s),
        gatherer: Some(&gatherer),
        estimator: Some(estimator),
        started: started
            .checked_sub(Duration::from_secs_f64(job_seconds.max(0.0)))
            .unwrap_or(started),
    };
    manifest.element_gather = elements.as_ref().map(|(_, record)| record.clone());
    write_set(&args, ctx, &bake_set, manifest)
}

/// Every part's recorded estimates by key, each key checked to be in its part's shard.
fn estimates_of(set: &PartSet) -> Result<HashMap<Point, RadianceEstimate>, CliError> {
    let mut all = HashMap::new();
    for part in &set.parts {
        let corrupt = |why: String| {
            CliError::Input(format!(
                "{}: part {}: {why}; nothing merged",
                part.path.display(),
                part.header.part
            ))
        };
        if part.payload.len() % WORDS != 0 {
            return Err(corrupt(format!(
                "{} values, not whole records of {WORDS}",
                part.payload.len()
            )));
        }
        let shard = u64::from(part.header.part.index - 1);
        for r in part.payload.chunks_exact(WORDS) {
            let w: Vec<u32> = r.iter().map(|v| v.to_bits()).collect();
            let key = u64::from(w[0]) | u64::from(w[1]) << 32;
            if key % u64::from(part.header.part.of) != shard {
                return Err(corrupt(format!(
                    "the point of key {key} is not in its shard"
                )));
            }
            let f = |i: usize| f32::from_bits(w[i]);
            let e = RadianceEstimate {
                emitted: glam::Vec3::new(f(6), f(7), f(8)),
                direct: glam::Vec3::new(f(9), f(10), f(11)),
                indirect: glam::Vec3::new(f(12), f(13), f(14)),
                indirect_error: f(15),
                back_faces: f(16),
                rays: u64::from(w[17]) | u64::from(w[18]) << 32,
                shadow_rays: u64::from(w[19]) | u64::from(w[20]) << 32,
            };
            all.insert((key, w[2], [w[3], w[4], w[5]]), e);
        }
    }
    Ok(all)
}

/// The solution in the bytes of the `.bake` file `path`, checked against `scene` (its
/// fingerprints) like `read_bake` does.
fn decode(bytes: &[u8], scene: &Scene, path: &Path) -> Result<Solution, CliError> {
    twopass_bake::decode_bake(bytes, scene).map_err(|problem| {
        CliError::Bake(twopass_bake::BakeError::Invalid {
            path: path.to_owned(),
            problem,
        })
    })
}
