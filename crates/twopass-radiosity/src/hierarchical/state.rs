//! The hierarchical solver's state ([`HierarchicalSolver`]) and the sizes and limits its jobs
//! share.

use glam::DVec3;
use twopass_scene::Scene;

use super::directions::{DIRECTIONS, Incoming, Linear, Table};
use super::link::Link;
use crate::cluster::{Clusters, NodeRef};
use crate::element::ElementMesh;
use crate::options::Options;
use crate::report::Bookkeeping;
use crate::specular_receivers::SpecularReceivers;

/// Approximate bytes per surface node (mesh node, vertex share, per-node sums and corners).
pub(super) const BYTES_PER_NODE: u64 = 480;

/// Bytes per cluster (about one per triangle): its node, its incoming light, the light it sends
/// by direction and its projected area by direction.
pub(super) const BYTES_PER_CLUSTER: u64 = (std::mem::size_of::<Incoming>()
    + std::mem::size_of::<Table>()
    + std::mem::size_of::<[f32; DIRECTIONS]>()
    + std::mem::size_of::<Linear>()
    + std::mem::size_of::<glam::DVec3>()
    + 120) as u64;

/// Approximate bytes per link (the link, sorting and the candidates of a refinement pass).
pub(super) const BYTES_PER_LINK: u64 = 96;

/// Candidates evaluated between two looks at the clock.
pub(super) const BATCH: usize = 1 << 14;

/// A link with a cluster at an end is near, and must be refined, unless the ends' centres
/// are farther apart than this many times the sum of their bounding radii: the isotropic
/// far-field estimate holds only well away from a cluster.
pub(super) const SEPARATION: f64 = 2.0;

/// How far a surface node's receiving corners sit inside it, as a fraction of the way to its
/// centroid. A corner on an edge that the node shares with a perpendicular surface must lie
/// clearly in front of that surface's plane, or the form factor counts it as in the plane
/// and gives 0 where the true value is near 1/2: with the smallest elements 200 times finer
/// than the largest surfaces and the plane test at 1e-6 of the source's size, 2e-3 keeps a
/// margin of about 2.5.
pub(super) const CORNER_INSET: f64 = 2e-3;

/// Re-refinements with converged radiosities at most.
pub(super) const MAX_ROUNDS: u32 = 6;

/// A hierarchical radiosity solve with clustering over a scene. Deterministic: the same
/// options and seed give the same solution bit for bit on any number of threads (without a
/// time budget).
pub struct HierarchicalSolver<'s> {
    pub(super) scene: &'s Scene,
    pub(super) options: Options,
    /// The surface hierarchy: every participating triangle's bisection tree; its leaves are
    /// the elements the solution is given on.
    pub(super) mesh: ElementMesh,
    /// The cluster tree above the triangles.
    pub(super) clusters: Clusters,
    /// Surface nodes are not split below this longest edge, scene units.
    pub(super) min_size: f32,
    /// Link error threshold, W (luminance, scene units).
    pub(super) error_threshold: f64,
    /// Per scene triangle: reflectance and emitted exitance E = pi L_e.
    pub(super) tri_rho: Vec<DVec3>,
    pub(super) tri_emission: Vec<DVec3>,
    /// Per surface node, in a scene with textures: the texture's mean reflectance over it
    /// ([`crate::albedo::node_albedo`]); empty otherwise (the triangle's reflectance holds).
    pub(super) node_rho: Vec<DVec3>,
    /// Links, sorted by receiver, and where each receiver's run starts.
    pub(super) links: Vec<Link>,
    pub(super) receivers: Vec<(NodeRef, u32)>,
    /// Per surface node: irradiance its own links gathered at its corners (from emitted and
    /// from reflected light), and its area-averaged exitance (emitted, reflected).
    pub(super) gathered: Vec<[[DVec3; 4]; 2]>,
    pub(super) exitance: Vec<[DVec3; 2]>,
    /// Per surface leaf: the share of its exitance its own links send and the share its
    /// ancestors' links send (one each, less where the form factors would sum above one);
    /// per surface node, what it sends through its links, those shares applied (empty while
    /// every share is whole). See `bound`.
    pub(super) send_weight: Vec<[f64; 2]>,
    pub(super) sending: Vec<[DVec3; 2]>,
    /// The shares are applied: a gather delivered more than its sources sent.
    pub(super) bounding: bool,
    /// Surface nodes at the last push-pull: those from this index on were split off since, and
    /// have sent nothing yet.
    pub(super) settled: usize,
    /// Per surface node and per cluster: the range (largest less smallest) of the exitance
    /// luminance of the leaves below, W/m^2: how far from uniform a source is.
    pub(super) spread: Vec<f64>,
    pub(super) cluster_spread: Vec<f64>,
    /// Per surface leaf: irradiance at its corners after push (emitted, reflected light).
    pub(super) corners_in: Vec<[[DVec3; 4]; 2]>,
    /// Per cluster: the flux density arriving from each table direction (from the cluster
    /// toward the sources), gathered by its own links; pushed down, each surface inside takes
    /// it by its orientation.
    pub(super) cluster_gathered: Vec<Incoming>,
    /// Per cluster: its area-averaged exitance (emitted, reflected), W/m^2.
    pub(super) cluster_exitance: Vec<[DVec3; 2]>,
    /// Per cluster: its radiant intensity times pi toward each table direction, W: the sum
    /// over its triangles of exitance x area x clamped cosine. A cluster source sends this.
    pub(super) radiant: Vec<Table>,
    /// Per cluster: the exact linear form of the same, for directions every triangle inside
    /// faces (see [`super::directions::Facing`]).
    pub(super) radiant_linear: Vec<Linear>,
    /// Per cluster: its projected area toward each table direction, scene units squared.
    pub(super) projected: Vec<[f32; DIRECTIONS]>,
    /// Per cluster: the sum of its triangles' area x unit normal, scene units squared: its
    /// projected area toward any direction every triangle inside faces.
    pub(super) projected_linear: Vec<DVec3>,
    /// Per cluster: a cone (unit axis, half-angle in radians) holding the normals of every
    /// triangle inside, geometric and shading: what cannot face a node is never linked to it.
    pub(super) cones: Vec<(DVec3, f64)>,
    /// Per cluster: [`super::directions::Facing::sine`] of its cone's half-angle.
    pub(super) cone_sines: Vec<f64>,
    /// The table directions (unit vectors, see [`super::directions::directions`]).
    pub(super) dirs: [DVec3; DIRECTIONS],
    /// Residual power of the last iteration per channel (signed), and its fraction.
    pub(super) residual: DVec3,
    pub(super) residual_fraction: f64,
    /// Power the emitters send, W per channel (the lamps' included).
    pub(super) emitted: DVec3,
    /// Per element-mesh vertex: the irradiance the lamps give it directly, W/m^2; a source
    /// term every push-pull adds to the leaves' corners as emitted light.
    pub(super) lamp: Vec<DVec3>,
    /// Power the lamps send, W per channel ([`crate::lamps::lamp_power`]).
    pub(super) lamp_power: DVec3,
    /// Rounds, time and power, kept as the other solver keeps them.
    pub(super) bookkeeping: Bookkeeping,
    /// Gather iterations so far.
    pub(super) iterations: u64,
    /// Shadow and specular-transfer rays cast so far.
    pub(super) rays: u64,
    /// The initial linking (from the root linked to itself) is done.
    pub(super) linked: bool,
    /// Past the time budget: links still being decided get the first, coarse visibility
    /// estimate only (no confirmation, no finer count, no visibility per corner), so that the
    /// candidates left when the budget runs out cost a few rays each, not dozens.
    pub(super) out_of_time: bool,
    /// The partly blocked links have had their visibility estimated again with the
    /// converged radiosities.
    pub(super) refreshed: bool,
    /// Most links and surface nodes the memory limit leaves room for: refinement stops
    /// splitting when either is reached.
    pub(super) max_links: usize,
    pub(super) max_nodes: usize,
    /// The specular transfer, when the scene needs it ([`crate::specular::decide`]): light the
    /// leaves send through mirrors and glass, deposited on the vertices it lands near.
    pub(super) specular: Option<SpecularReceivers>,
    /// The mesh changed since the deposits were last splatted onto it.
    pub(super) specular_stale: bool,
}
