//! The bake manifest (JSON): what was solved, how, how long it took and how good it is.

use std::path::PathBuf;
use std::time::Duration;

use serde::{Deserialize, Serialize};
use twopass_radiosity::{Finish, Options, Residuals, SolveProgress};
use twopass_scene::Scene;

use crate::error::BakeError;
use crate::fingerprint::{geometry_fingerprint, lighting_fingerprint};

/// Version of the [`Manifest`] JSON layout.
pub const MANIFEST_VERSION: u32 = 2;

/// The solver settings a bake was made with (`null`: the solver's default).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SettingsRecord {
    /// Requested longest patch edge, scene units (default: diagonal / 8).
    pub patch_size: Option<f32>,
    /// Requested longest element edge, scene units (default: diagonal / 24).
    pub element_size: Option<f32>,
    /// The scene's bounding-box diagonal, scene units (what the defaults derive from).
    pub scene_diagonal: f32,
    /// Adaptive subdivision, or `null` when off.
    pub adaptive: Option<AdaptiveRecord>,
    /// Shadow rays per visibility estimate: first estimate.
    pub visibility_rays_min: u32,
    /// Shadow rays per visibility estimate: most.
    pub visibility_rays_max: u32,
    /// Whether visibility was measured with shadow rays.
    pub occlusion: bool,
    /// Whether shaft culling skipped the rays of pairs nothing can come between (progressive
    /// refinement). Absent in manifests written before it existed, which did not cull.
    #[serde(default)]
    pub shaft_culling: bool,
    /// Stop at this unshot fraction of the emitted power.
    pub unshot_fraction: f64,
    /// Hierarchical solver: refine links whose estimated error exceeds this fraction of the
    /// emitted power.
    #[serde(default)]
    pub link_tolerance: f64,
    /// Hierarchical solver: smallest element edge, scene units (`null`: diagonal / 200).
    #[serde(default)]
    pub min_element_size: Option<f32>,
    /// Stop after this many shots, if set.
    pub max_shots: Option<u64>,
    /// Stop after this wall-clock time, seconds, if set.
    pub time_budget_s: Option<f64>,
    /// Seed of the visibility sampling and of the specular transfer.
    pub seed: u64,
    /// Worker threads (the result does not depend on it).
    pub threads: usize,
    /// Specular transfer (light through mirrors and glass, progressive refinement): rays a
    /// shot of the whole emitted power traces, or `null` when the options turn it off. It
    /// runs only on scenes that need it (`twopass info` says whether).
    #[serde(default)]
    pub specular_rays: Option<u32>,
}

/// Adaptive subdivision settings (see `twopass_radiosity::AdaptiveOptions`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveRecord {
    /// Split when vertex luminances differ by more than this fraction of the mean.
    pub threshold: f32,
    /// Smallest element edge / 2, scene units (`null`: element size / 8).
    pub min_element_size: Option<f32>,
    /// Refinement rounds allowed.
    pub rounds: u32,
    /// Unshot fraction at which each round looks at the solution.
    pub at_unshot_fraction: f64,
}

/// Wall-clock time per phase, seconds.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TimingsRecord {
    /// Loading the scene and building its accelerator.
    pub load_s: f64,
    /// Building the patch and element mesh.
    pub meshing_s: f64,
    /// Shooting (solve time less meshing and refining).
    pub shooting_s: f64,
    /// Adaptive subdivision, with the new vertices' gathering.
    pub refining_s: f64,
    /// Computing the residual report.
    pub residuals_s: f64,
    /// Encoding and writing the output files (all but the manifest).
    pub writing_s: f64,
    /// Everything, up to writing the manifest.
    pub total_s: f64,
}

/// Mesh sizes at the end of the solve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CountsRecord {
    /// Scene triangles.
    pub scene_triangles: usize,
    /// Patches (shooters).
    pub patches: usize,
    /// Elements (displayed triangles).
    pub elements: usize,
    /// Element vertices (where radiosity is stored).
    pub vertices: usize,
    /// Adaptive rounds (progressive) or link re-refinements (hierarchical) done.
    pub refinement_rounds: u32,
    /// Links between hierarchy nodes (hierarchical).
    #[serde(default)]
    pub links: usize,
    /// Clusters above the surfaces (hierarchical).
    #[serde(default)]
    pub clusters: usize,
    /// Gather iterations (hierarchical).
    #[serde(default)]
    pub iterations: u64,
}

/// Power bookkeeping, W per RGB channel (scene units, so mm^2 scenes give W * 1e-6 per m^2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnergyRecord {
    /// Emitted.
    pub emitted: [f64; 3],
    /// Absorbed by surfaces.
    pub absorbed: [f64; 3],
    /// Shot but received by no element.
    pub escaped: [f64; 3],
    /// Received but not shot yet.
    pub unshot: [f64; 3],
    /// Change of the unshot estimate by adaptive subdivision.
    pub remeshing: [f64; 3],
    /// Sent by the surfaces (the base of the escaped share).
    #[serde(default)]
    pub sent: [f64; 3],
    /// Largest relative imbalance after any step.
    pub worst_imbalance: f64,
}

/// The residual report: how many vertices and patch pairs were sampled, then the solver's
/// [`Residuals`] field by field (energy imbalance, row sums, reciprocity).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualsRecord {
    /// Vertices and patch pairs sampled.
    pub samples: usize,
    /// The figures themselves, as fields of this record in the JSON.
    #[serde(flatten)]
    pub residuals: Residuals,
}

/// The `.glb` colour mapping used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColorRecord {
    /// The mapping, as a formula.
    pub mapping: String,
    /// Multiplier on radiance, sr m^2 / W.
    pub exposure: f32,
    /// `"auto"` (99th-percentile luminance to 1) or `"fixed"` (given by the user).
    pub exposure_mode: String,
    /// Vertices with a channel clipped at 1.
    pub clamped_vertices: usize,
}

/// The convergence measure at the end of the solve.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ConvergenceRecord {
    /// What is measured, in words.
    pub measure: String,
    /// Its value at the end.
    pub value: f64,
    /// The tolerance the solve stopped on.
    pub tolerance: f64,
    /// Whether the value reached the tolerance.
    pub converged: bool,
}

/// One written file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileRecord {
    /// `"glb"`, `"ply"` or `"bake"`.
    pub format: String,
    /// Where it was written.
    pub path: PathBuf,
    /// Size, bytes.
    pub bytes: u64,
    /// CRC-32 (IEEE) of the file's bytes, so a reader can tell a file of this set from one a
    /// later, interrupted bake left beside it (absent in manifests from before it was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crc32: Option<u32>,
}

/// The bake manifest (JSON): what was solved, how, how long it took and how good it is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// [`MANIFEST_VERSION`].
    pub manifest_version: u32,
    /// `twopass <version>`.
    pub generator: String,
    /// The scene file.
    pub scene: PathBuf,
    /// [`geometry_fingerprint`] of the scene, 16 hex digits.
    pub geometry_fingerprint: String,
    /// [`lighting_fingerprint`] of the scene, 16 hex digits.
    pub lighting_fingerprint: String,
    /// The solver that ran: `progressive` or `hierarchical`.
    #[serde(default)]
    pub solver: String,
    /// Solver settings.
    pub settings: SettingsRecord,
    /// The convergence measure both solvers stop on.
    #[serde(default)]
    pub convergence: ConvergenceRecord,
    /// Why the solve stopped: `converged`, `max_shots`, `time_budget`, `cancelled`,
    /// `exhausted`.
    pub finish: String,
    /// Time per phase.
    pub timings: TimingsRecord,
    /// Shots (patches shot, with repeats).
    pub shots: u64,
    /// Rays cast: shadow rays, and the specular transfer's.
    pub rays: u64,
    /// Mesh sizes.
    pub counts: CountsRecord,
    /// Unshot power over emitted power at the end (sums over channels).
    pub unshot_fraction: f64,
    /// Power bookkeeping.
    pub energy: EnergyRecord,
    /// The residual report.
    pub residuals: ResidualsRecord,
    /// The `.glb` colour mapping, when a `.glb` was written.
    pub color: Option<ColorRecord>,
    /// The lightmap, when one was baked.
    #[serde(default)]
    pub lightmap: Option<LightmapRecord>,
    /// The final gather of the element-mesh outputs (`.glb`, `.ply`, `.bake`), when they were
    /// gathered.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub element_gather: Option<PointGatherRecord>,
    /// The final gather at the user's vertices (`.vertex.glb`), when it was written gathered.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vertex_gather: Option<PointGatherRecord>,
    /// The files written (the manifest not included).
    pub files: Vec<FileRecord>,
}

/// A lightmap bake ([`bake_lightmap`](crate::lightmap::bake_lightmap)).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LightmapRecord {
    /// Texel edge on the surface, scene units.
    pub texel_size: f32,
    /// Border around each chart, texels.
    pub padding: u32,
    /// Atlas width, texels.
    pub width: u32,
    /// Atlas height, texels.
    pub height: u32,
    /// Charts (coplanar connected triangles) in the atlas; 1 for the scene's own coordinates.
    pub charts: usize,
    /// Objects whose charts got finer texels than `texel_size` for their curvature (one texel
    /// spanning at most [`MAX_TEXEL_ANGLE`](crate::lightmap::MAX_TEXEL_ANGLE) radians).
    #[serde(default)]
    pub curved_objects: usize,
    /// Where the texture coordinates come from (the scene's, or generated and why).
    #[serde(default)]
    pub atlas: String,
    /// Texels a triangle touches (conservative rasterization), each lit at its own point.
    pub covered_texels: usize,
    /// What the texels hold: `radiance` (outgoing, W/(m^2 sr), albedo and emission included)
    /// or `irradiance` (E / pi, W/(m^2 sr), to be multiplied by the albedo);
    /// [`LightmapQuantity`](crate::LightmapQuantity). Older manifests, without it, hold radiance.
    #[serde(default = "radiance")]
    pub quantity: String,
    /// How the PNG encodes the texels.
    pub png: String,
    /// The texture the `.glb` files reference for engines: `rgbm` (`<stem>.lightmap.rgbm.png`,
    /// HDR) or `srgb` (the PNG above); [`LightmapEncoding`](crate::LightmapEncoding). Older
    /// manifests, without it, reference the sRGB PNG.
    #[serde(default = "srgb")]
    pub encoding: String,
    /// The RGBM PNG's range multiplier: `value = multiplier * A * (R, G, B)`; `None` without
    /// one.
    #[serde(default)]
    pub rgbm_multiplier: Option<f32>,
    /// Time to lay out, fill and encode the lightmap, seconds.
    pub seconds: f64,
    /// The final gather that filled the texels, or `None` when they show the solution.
    #[serde(default)]
    pub gather: Option<GatherRecord>,
}

fn srgb() -> String {
    "srgb".into()
}

fn radiance() -> String {
    "radiance".to_owned()
}

/// The settings and cost of a final gather, as the manifest records them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GatherRecord {
    /// Shadow rays per point over all emitters.
    pub shadow_rays_per_point: u32,
    /// Gather rays of a point's first batch.
    pub min_rays: u32,
    /// Most gather rays of one point.
    pub max_rays: u32,
    /// Relative standard error of the indirect luminance at which a point stops.
    pub target_error: f32,
    /// Most mirror and glass bounces of a gather ray.
    pub max_depth: u32,
    /// Seed of every point's random sequence.
    pub seed: u64,
    /// How the indirect part was denoised.
    pub filter: String,
    /// Closest-hit rays traced.
    pub rays: u64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// Rays (both kinds) per second of the gather.
    pub rays_per_second: f64,
    /// Points (texels, the user's vertices and the element mesh's points, which share the
    /// gather) that showed the solution instead because the time budget ran out before their
    /// gather.
    #[serde(default)]
    pub late_points: u64,
    /// Caustic photons the gather estimated the light through mirrors and glass from (0: the
    /// scene has none, or the gather rays found that light).
    #[serde(default)]
    pub caustic_photons: u64,
}

/// The final gather of the element mesh or the user's vertices: each point gathered as a
/// lightmap texel is ([`GatherRecord`] holds the shared settings when a lightmap was baked too),
/// with at most `max_rays` gather rays.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointGatherRecord {
    /// Most gather rays of one point.
    pub max_rays: u32,
    /// Points gathered (six per element of the element mesh, one per user vertex).
    pub points: u64,
    /// Closest-hit rays traced.
    pub rays: u64,
    /// Shadow rays traced.
    pub shadow_rays: u64,
    /// Seconds the gather took in this process.
    pub seconds: f64,
    /// Rays (both kinds) per second of the gather.
    pub rays_per_second: f64,
}

fn seconds(d: Duration) -> f64 {
    d.as_secs_f64()
}

impl Manifest {
    /// A manifest of a finished solve of `scene` with `options`: `progress` is the solver's
    /// final progress, `residuals` its residual report over `samples` samples, computed in
    /// `residuals_time`. Timings of loading and writing, the colour record and the files are
    /// left for the caller to fill in.
    pub fn new(
        scene: &Scene,
        options: &Options,
        finish: Finish,
        progress: &SolveProgress,
        residuals: &Residuals,
        samples: usize,
        residuals_time: Duration,
    ) -> Self {
        let e = &progress.energy;
        let shooting = progress
            .elapsed
            .saturating_sub(progress.meshing)
            .saturating_sub(progress.refining);
        Self {
            manifest_version: MANIFEST_VERSION,
            generator: format!("twopass {}", env!("CARGO_PKG_VERSION")),
            scene: scene.path.clone(),
            geometry_fingerprint: format!("{:016x}", geometry_fingerprint(scene)),
            lighting_fingerprint: format!("{:016x}", lighting_fingerprint(scene)),
            solver: progress.method.name().into(),
            convergence: ConvergenceRecord {
                measure: "residual (unshot) power / emitted power, sums over channels".into(),
                value: progress.unshot_fraction,
                tolerance: options.stop.unshot_fraction,
                converged: progress.unshot_fraction <= options.stop.unshot_fraction,
            },
            settings: SettingsRecord {
                patch_size: options.patch_size,
                element_size: options.element_size,
                scene_diagonal: scene.bounds.diagonal(),
                adaptive: options.adaptive.map(|a| AdaptiveRecord {
                    threshold: a.threshold,
                    min_element_size: a.min_element_size,
                    rounds: a.rounds,
                    at_unshot_fraction: a.at_unshot_fraction,
                }),
                visibility_rays_min: options.visibility.min,
                visibility_rays_max: options.visibility.max,
                occlusion: options.occlusion,
                shaft_culling: options.shaft_culling,
                unshot_fraction: options.stop.unshot_fraction,
                link_tolerance: options.hierarchical.link_tolerance,
                min_element_size: options.hierarchical.min_element_size,
                max_shots: options.stop.max_shots,
                time_budget_s: options.stop.time_budget.map(seconds),
                seed: options.seed,
                threads: rayon::current_num_threads(),
                specular_rays: options.specular.map(|s| s.rays),
            },
            finish: match finish {
                Finish::Converged => "converged",
                Finish::MaxShots => "max_shots",
                Finish::TimeBudget => "time_budget",
                Finish::Cancelled => "cancelled",
                Finish::Exhausted => "exhausted",
            }
            .into(),
            timings: TimingsRecord {
                meshing_s: seconds(progress.meshing),
                shooting_s: seconds(shooting),
                refining_s: seconds(progress.refining),
                residuals_s: seconds(residuals_time),
                ..TimingsRecord::default()
            },
            shots: progress.shots,
            rays: progress.rays,
            counts: CountsRecord {
                scene_triangles: scene.mesh.triangle_count(),
                patches: progress.patches,
                elements: progress.elements,
                vertices: progress.vertices,
                refinement_rounds: progress.refinement_rounds,
                links: progress.links,
                clusters: progress.clusters,
                iterations: progress.iterations,
            },
            unshot_fraction: progress.unshot_fraction,
            energy: EnergyRecord {
                emitted: e.emitted.to_array(),
                absorbed: e.absorbed.to_array(),
                escaped: e.escaped.to_array(),
                unshot: e.unshot.to_array(),
                remeshing: e.remeshing.to_array(),
                sent: e.sent.to_array(),
                worst_imbalance: progress.worst_imbalance,
            },
            residuals: ResidualsRecord {
                samples,
                residuals: *residuals,
            },
            color: None,
            lightmap: None,
            element_gather: None,
            vertex_gather: None,
            files: Vec::new(),
        }
    }

    /// The manifest as pretty-printed JSON (non-finite numbers become `null`).
    pub fn to_json(&self) -> Result<Vec<u8>, BakeError> {
        let mut bytes = serde_json::to_vec_pretty(self).map_err(|e| BakeError::Encode {
            path: PathBuf::from("manifest"),
            message: e.to_string(),
        })?;
        bytes.push(b'\n');
        Ok(bytes)
    }
}
