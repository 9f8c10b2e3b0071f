//! The progressive solver's state ([`ProgressiveSolver`]) and the sizes and limits its jobs
//! share.

use std::sync::atomic::AtomicU8;

use glam::DVec3;
use twopass_scene::{Scene, SurfacePoint};

use super::patch_elements::PatchElements;
use crate::element::ElementMesh;
use crate::options::Options;
use crate::report::Bookkeeping;
use crate::specular_receivers::SpecularReceivers;

/// Most patches or elements a solve meshes before adaptive subdivision (about 2 GB of mesh,
/// form-factor rows and radiosities); smaller patch or element sizes are refused up front.
pub const MAX_ELEMENTS: usize = 4_000_000;

/// Most form factors one sweep of progressive refinement (every patch shooting once to every
/// vertex) may take, counted from the fewest patches and vertices the sizes can make: a solve
/// converges in several sweeps, each a pair loop over patches x vertices, so a finer mesh is
/// refused up front (with the estimate) rather than left running for hours. The largest mesh
/// `twopass bench radiosity` measures (200,000 elements of the Cornell box, element size about
/// 7.5 mm) makes about 1.2e7.
pub const MAX_SWEEP_FORM_FACTORS: f64 = 1e8;

/// Approximate bytes per element: the node, its share of vertices with their per-vertex sums
/// and receiving points, the edge map and the patch lists.
pub(super) const BYTES_PER_ELEMENT: f64 = 400.0;

/// Most form factors [`ProgressiveSolver::patch_rows`] computes in one parallel pass (16 MiB of
/// rows in flight beside the cache).
pub(super) const ROW_BATCH: usize = 1 << 22;

/// Most patches for which [`ProgressiveSolver`] keeps every pair's shaft test (one byte per pair:
/// 16 MiB at this many); above it, each row tests its pairs afresh.
pub(super) const PAIR_CACHE_MAX_PATCHES: usize = 4096;

/// Fewest vertices of a row that must lie on a patch for [`ProgressiveSolver`] to test the shaft
/// between that patch and the shooter: a hull test costs several vertex tests, and a pair
/// tested once is kept.
pub(super) const HULL_MIN_VERTICES: u32 = 6;

/// States of a pair of patches in [`ProgressiveSolver`]'s shaft cache: not tested yet,
/// nothing can come between them, something may.
pub(super) const PAIR_UNKNOWN: u8 = 0;
/// See [`PAIR_UNKNOWN`].
pub(super) const PAIR_CLEAR: u8 = 1;
/// See [`PAIR_UNKNOWN`].
pub(super) const PAIR_BLOCKED: u8 = 2;

/// A progressive-refinement radiosity solve over a scene. Deterministic: the same options and
/// seed give the same solution bit for bit on any number of threads.
pub struct ProgressiveSolver<'s> {
    pub(super) scene: &'s Scene,
    pub(super) options: Options,
    /// Patches (the shooters) and their elements (the receivers).
    pub(super) mesh: ElementMesh,
    /// Longest element edge before adaptive subdivision, scene units.
    pub(super) element_size: f32,
    /// Per vertex: reflectance, emitted exitance E = pi L_e.
    pub(super) rho: Vec<DVec3>,
    /// The elements' texture means the vertices' reflectances come from (textured scenes).
    pub(super) element_albedo: crate::albedo::ElementAlbedo,
    pub(super) emission: Vec<DVec3>,
    /// Per vertex: where it receives ([`ProgressiveSolver::receiving_point`]), and there, with its
    /// error bound on its scene triangle, where its shadow rays start; computed once instead of
    /// once per shooter.
    pub(super) receiving: Vec<DVec3>,
    pub(super) receivers: Vec<SurfacePoint>,
    /// Per vertex: whether it lies inside another object ([`crate::hidden`]).
    pub(super) hidden: Vec<bool>,
    /// Per vertex: irradiance from the lamps (shadows included), W/m^2; part of
    /// `received_emit`, kept apart for the dense solve's source term.
    pub(super) lamp: Vec<DVec3>,
    /// Per vertex: irradiance received from emitted and from reflected light, W/m^2.
    pub(super) received_emit: Vec<DVec3>,
    pub(super) received_refl: Vec<DVec3>,
    /// The specular transfer and the light it brought to the vertices, when the scene needs
    /// it ([`crate::specular::decide`]).
    pub(super) specular: Option<SpecularReceivers>,
    /// Per patch: unshot and shot radiosity, split by origin.
    pub(super) unshot_emit: Vec<DVec3>,
    pub(super) unshot_refl: Vec<DVec3>,
    pub(super) shot_emit: Vec<DVec3>,
    pub(super) shot_refl: Vec<DVec3>,
    /// Per patch: the power that arrived at it so far, W per channel (from shots, lamps and
    /// the specular transfer): what bounds its reflected light when the mesh is refined.
    pub(super) arrived: Vec<DVec3>,
    /// Per patch: its unshot power, W summed over channels (`|unshot_emit + unshot_refl|`
    /// times its area): what the next shooter is chosen by and the stop is decided by, kept
    /// up to date wherever the unshot radiosity changes ([`ProgressiveSolver::note_unshot`]) rather
    /// than recomputed for every patch on every shot.
    pub(super) unshot_power: Vec<f64>,
    /// Per patch: its elements (leaves), flat, with what every shot reads of them.
    pub(super) elements: PatchElements,
    /// Per patch: diffuse reflectance and area (scene units squared); patches never change.
    pub(super) patch_rho: Vec<DVec3>,
    pub(super) patch_area: Vec<f64>,
    /// Per patch: cached form factors (with visibility) to every vertex, once computed.
    pub(super) cache: Vec<Option<Vec<f32>>>,
    /// Per patch whose row is cached and that has shot on the current element mesh: its
    /// [`ProgressiveSolver::arrival_weights`], kept beside the row (a patch shoots several times)
    /// and dropped when the elements change.
    pub(super) weights: Vec<Option<Vec<f64>>>,
    /// Per pair of patches `(q, p)` at `q * n + p`, with shaft culling and at most
    /// [`PAIR_CACHE_MAX_PATCHES`] patches: whether the shaft between them is clear
    /// ([`PAIR_UNKNOWN`], [`PAIR_CLEAR`], [`PAIR_BLOCKED`]); patches never change, and every
    /// refinement asks again for the new vertices. Empty otherwise.
    pub(super) pair_clear: Vec<AtomicU8>,
    /// Bytes held by the cached rows and weights (at most [`Options::cache_bytes`]).
    pub(super) cached_bytes: usize,
    /// Rounds, time and power, kept as the other solver keeps them.
    pub(super) bookkeeping: Bookkeeping,
    /// Shots so far.
    pub(super) shots: u64,
    /// Shadow and specular-transfer rays cast so far.
    pub(super) rays: u64,
}
