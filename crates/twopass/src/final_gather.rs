//! What a bake's final gather covers (`--gather off|auto|N`): which outputs are gathered, with
//! how many rays per point, and the count of what each gather cast for the manifest.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use twopass_bake::PointGatherRecord;
use twopass_radiosity::Solution;
use twopass_radiosity::element::ElementMesh;
use twopass_radiosity::triangle_rule::DUNAVANT_6;
use twopass_scene::{RadianceEstimate, RadianceEstimator, Scene};
use twopass_trace::gather::GatherSettings;

use crate::args::checked;

/// The final gather a bake runs (`--gather`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gather {
    /// No gather: every output shows the solution.
    Off,
    /// The library's default gather for lightmap texels and the user's vertices, and a
    /// fixed count within [`ELEMENT_RAYS`] per point for the element mesh.
    Auto,
    /// At most this many gather rays per point, for every output.
    Rays(u32),
}

/// The fewest and the most gather rays per point of the element-mesh outputs under
/// `--gather auto`, which spends [`ELEMENT_RAY_BUDGET`] rays between them. Each element is
/// gathered at six points averaged over it, so a few rays per point average out where a
/// texel's would not: on the bench's rooms 16 rays put the element mesh's directly lit
/// regions within 0.5 % of 64 rays', but a region lit only by interreflection (a block's side
/// facing away from the light) is still about 1 % noisy at 16. The count is the same for every
/// point: stopping a point early where its few rays agree would bias it (the rays that missed
/// a small bright patch agree on darkness).
pub const ELEMENT_RAYS: (u32, u32) = (16, 64);

/// Gather rays the element-mesh outputs take under `--gather auto`, within [`ELEMENT_RAYS`]
/// per point: a coarse mesh gets 64 rays per point and the 100k-triangle room's 645,486
/// points get 16, fewer than the default lightmap gather of the Cornell box casts (1.9e7).
pub const ELEMENT_RAY_BUDGET: u64 = 1 << 23;

impl Gather {
    /// The gather's settings, `None` when off.
    pub(crate) fn settings(self, seed: u64) -> Option<GatherSettings> {
        let default = GatherSettings {
            seed,
            ..GatherSettings::default()
        };
        match self {
            Self::Off => None,
            Self::Auto => Some(default),
            Self::Rays(n) => Some(GatherSettings {
                min_rays: default.min_rays.min(n),
                max_rays: n,
                ..default
            }),
        }
    }

    /// Gather rays per point of the element-mesh outputs of `mesh` (gathered at the points of
    /// Dunavant's rule in each of its elements), `None` when off.
    pub(crate) fn element_rays(self, mesh: &ElementMesh) -> Option<u32> {
        match self {
            Self::Off => None,
            Self::Auto => {
                let points = (DUNAVANT_6.len() * mesh.leaves().count()) as u64;
                let (fewest, most) = ELEMENT_RAYS;
                let share = ELEMENT_RAY_BUDGET / points.max(1);
                Some(share.clamp(u64::from(fewest), u64::from(most)) as u32)
            }
            Self::Rays(n) => Some(n),
        }
    }
}

/// Most gather rays per point `--gather` accepts.
const MAX_GATHER_RAYS: u32 = 65_536;

pub(crate) fn parse_gather(s: &str) -> Result<Gather, String> {
    match s {
        "off" => Ok(Gather::Off),
        "auto" => Ok(Gather::Auto),
        _ => checked(
            s,
            |n: &u32| (1..=MAX_GATHER_RAYS).contains(n),
            &format!("must be off, auto or a ray count from 1 to {MAX_GATHER_RAYS}"),
        )
        .map(Gather::Rays),
    }
}

/// `solution` with its element-mesh outputs' values gathered by `estimator` (which casts at
/// most `max_rays` gather rays per point; [`twopass_bake::gathered_solution`]), and the
/// record of that gather.
pub(crate) fn gather_elements(
    solution: &Solution,
    scene: &Scene,
    estimator: &dyn RadianceEstimator,
    max_rays: u32,
) -> (Solution, PointGatherRecord) {
    let counted = Counted::new(estimator, max_rays);
    let gathered = twopass_bake::gathered_solution(solution, scene, &counted);
    (gathered, counted.record())
}

/// An estimator that counts the points it was asked for and the rays their estimates cast,
/// for the manifest's record of a gather ([`PointGatherRecord`]).
pub(crate) struct Counted<'e> {
    inner: &'e dyn RadianceEstimator,
    max_rays: u32,
    started: Instant,
    points: AtomicU64,
    rays: AtomicU64,
    shadow_rays: AtomicU64,
}

impl<'e> Counted<'e> {
    /// Counts what `inner` (at most `max_rays` gather rays per point) estimates from now on.
    pub(crate) fn new(inner: &'e dyn RadianceEstimator, max_rays: u32) -> Self {
        Self {
            inner,
            max_rays,
            started: Instant::now(),
            points: AtomicU64::new(0),
            rays: AtomicU64::new(0),
            shadow_rays: AtomicU64::new(0),
        }
    }

    /// What was counted, with the time since [`Counted::new`].
    pub(crate) fn record(&self) -> PointGatherRecord {
        let seconds = self.started.elapsed().as_secs_f64();
        let (rays, shadow_rays) = (
            self.rays.load(Ordering::Relaxed),
            self.shadow_rays.load(Ordering::Relaxed),
        );
        PointGatherRecord {
            max_rays: self.max_rays,
            points: self.points.load(Ordering::Relaxed),
            rays,
            shadow_rays,
            seconds,
            rays_per_second: (rays + shadow_rays) as f64 / seconds.max(1e-9),
        }
    }
}

impl RadianceEstimator for Counted<'_> {
    fn estimate(&self, triangle: u32, barycentric: [f32; 3], key: u64) -> RadianceEstimate {
        let e = self.inner.estimate(triangle, barycentric, key);
        self.points.fetch_add(1, Ordering::Relaxed);
        self.rays.fetch_add(e.rays, Ordering::Relaxed);
        self.shadow_rays.fetch_add(e.shadow_rays, Ordering::Relaxed);
        e
    }
}
