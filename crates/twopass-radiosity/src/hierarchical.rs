//! Hierarchical radiosity with clustering (Hanrahan, Salzman & Aupperle 1991; Smits, Arvo &
//! Greenberg 1994; Sillion 1994).
//!
//! The hierarchy: a cluster tree over the participating triangles ([`Clusters`]) above the
//! triangles' bisection trees ([`ElementMesh`]). Light moves along **links** between pairs of
//! nodes. Linking starts with the root linked to itself and refines a link, by splitting the
//! larger end, while its estimated transport error (BF refinement: the source's radiosity
//! times the link's form-factor error times the receiver's area and reflectance) exceeds
//! [`HierarchicalOptions::link_tolerance`] of the emitted power, or while an end is a cluster too
//! close to the other end for the far-field estimate. So distant groups exchange light through
//! one link and the initial linking is not all-pairs.
//!
//! Transport of a link, as irradiance at the receiver per unit exitance of the source:
//! - surface to surface: the exact differential-area-to-polygon form factor (Lambert's contour
//!   integral) at the receiver's three corners, so irradiance varies linearly over an element
//!   and the leaves get per-vertex values; its error estimate is the spread of the form factor
//!   over the corners and the centroid;
//! - with a cluster at either end: the isotropic cluster (Sillion 1994): a cluster of area A
//!   seen from any direction shows a projected area A / 4, as a closed convex object does;
//!   its error estimate is the whole transport;
//! - times the visible fraction of a few stratified shadow rays between the two ends; a
//!   partially visible link counts its whole transport as error, so it is refined.
//!
//! Each gather iteration (Jacobi) sums every link's transport into its receiver, then
//! **push-pull** moves irradiance down the hierarchy (linearly interpolated at surface nodes)
//! and area-averaged radiosity back up. The convergence measure is the one progressive
//! refinement stops on: the residual power, the change the last iteration made, over the
//! emitted power. Links are re-refined with the converged radiosities (BF refinement needs B)
//! until no link needs it. The leaves are the element mesh: bisection with conforming
//! neighbour splits keeps it free of cracks and T-vertices.
//!
//! Light through mirrors and glass ([`crate::specular`]): after every gather the leaves whose
//! exitance changed since they last sent send that change through the specular surfaces
//! (`shoot_specular`); what lands is splatted onto the vertices and joins the leaves'
//! reflected light at the next gather.

use std::f64::consts::PI;
use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use glam::{DMat3, DVec2, DVec3, Vec2, Vec3, Vec4};
use rayon::prelude::*;
use twopass_brdf::colour::luminance_f64;
use twopass_brdf::random::unit_f64;
use twopass_scene::{Scene, SurfacePoint};

use crate::ambient::ambient;
use crate::cluster::{Clusters, Kind, NodeRef};
use crate::element::{ElementMesh, barycentric_2d};
use crate::error::SolveError;
use crate::form_factor::{self, hash};
use crate::options::{Method, Options, check_common, participating};
use crate::report::{Bookkeeping, Finish, Residuals, SolveProgress};
use crate::solution::Solution;
use crate::specular::{self, Specular};
use crate::specular_receivers::SpecularReceivers;

/// A link: light from `source` gathered at `receiver`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Link {
    receiver: NodeRef,
    source: NodeRef,
    /// Transport per unit of what the source sends (its exitance for a surface, its radiant
    /// table entry `dir` for a cluster), visibility included: irradiance at the receiver's
    /// three corners for a surface receiver (point values: what the vertices display); flux
    /// density from direction `dir ^ OPPOSITE` for a cluster receiver (three equal values).
    transport: [f32; 3],
    /// The direction from the source's centre to the receiver's, as table bins.
    dir: Dir,
    /// Area-averaged irradiance per unit source exitance less the mean of `transport`: what the
    /// linear interpolant of the corner values misses of the light the receiver gets (surface
    /// pairs; zero otherwise), added uniformly over the receiver.
    area_correction: f32,
    /// Estimated error of the transport per unit source exitance luminance and receiver
    /// reflectance, as power: receiver area (scene units squared) times form-factor error.
    error: f32,
    /// Shadow rays found the pair partly or wholly blocked: its visibility depends on where
    /// the source's light comes from, and is estimated again once the radiosities are known
    /// (see [`HierarchicalSolver::refresh_visibility`]).
    partial: bool,
}

/// What refinement does with a candidate pair.
enum Step {
    Keep(Link),
    Drop,
    /// A cluster linked to itself: link every pair of its children.
    SelfPair(NodeRef),
    SplitReceiver(Link),
    SplitSource(Link),
}

/// What refinement has done with the pieces of a link it split.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Piece {
    /// None decided yet.
    Untouched,
    /// At least one decided: the link is gone for good.
    Decided,
    /// Out of time before any was decided: the link was kept whole, the pieces are skipped.
    Restored,
}

/// A link's evaluation.
struct Eval {
    transport: [f64; 3],
    /// `transport` before visibility.
    open: [f64; 3],
    dir: Dir,
    area_correction: f64,
    error: f64,
    /// An end is a cluster overlapping the other end's bounding sphere: the far-field estimate
    /// does not hold, the link must be refined.
    near: bool,
    /// Visibility is partial (some rays blocked, some not).
    partial: bool,
    rays: u64,
}

/// Directions of the clusters' tables: 16 spread over a hemisphere (a Fibonacci spiral) and
/// their opposites, so that bin `j ^ OPPOSITE` is the opposite of bin `j`.
const DIRECTIONS: usize = 32;
/// `j ^ OPPOSITE` is the bin opposite bin `j` (`DIRECTIONS / 2`, a power of two).
const OPPOSITE: u8 = (DIRECTIONS / 2) as u8;

fn directions() -> [DVec3; DIRECTIONS] {
    let half = DIRECTIONS / 2;
    let golden = PI * (3.0 - 5f64.sqrt());
    std::array::from_fn(|j| {
        let i = j % half;
        let z = 1.0 - (i as f64 + 0.5) / half as f64;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as f64;
        let d = DVec3::new(r * phi.cos(), r * phi.sin(), z);
        if j < half { d } else { -d }
    })
}

/// A direction as a blend of the three nearest table directions: weights `w / 255` (summing
/// to 1) chosen so that the blend points along the direction (barycentric coordinates in the
/// spherical triangle of the three). A surface facing `n` then takes close to `n . u` of a
/// beam from `u`, not the cosine to the nearest table direction, up to 20 degrees off with
/// 32 directions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Dir {
    bins: [u8; 3],
    w: [u8; 3],
}

impl Dir {
    /// The blend for unit direction `u`.
    fn new(dirs: &[DVec3; DIRECTIONS], u: DVec3) -> Self {
        let mut best = [(0usize, f64::NEG_INFINITY); 3];
        for (j, d) in dirs.iter().enumerate() {
            let c = d.dot(u);
            if c > best[2].1 {
                best[2] = (j, c);
                best.sort_by(|a, b| b.1.total_cmp(&a.1));
            }
        }
        let m = DMat3::from_cols(dirs[best[0].0], dirs[best[1].0], dirs[best[2].0]);
        let raw = if m.determinant().abs() > 1e-9 {
            (m.inverse() * u).max(DVec3::ZERO)
        } else {
            DVec3::X
        };
        let sum = raw.element_sum();
        let raw = if sum > 0.0 { raw / sum } else { DVec3::X };
        let mut w = raw.to_array().map(|x| (x * 255.0).round() as u8);
        // Rounding must not lose or add weight: the largest takes the difference.
        let total: u32 = w.iter().map(|&x| u32::from(x)).sum();
        w[0] = (i64::from(w[0]) + 255 - i64::from(total)).clamp(0, 255) as u8;
        Self {
            bins: best.map(|b| b.0 as u8),
            w,
        }
    }

    /// The opposite direction.
    fn opposite(self) -> Self {
        Self {
            bins: self.bins.map(|b| b ^ OPPOSITE),
            w: self.w,
        }
    }

    /// The blend's (bin, weight) pairs.
    fn parts(self) -> impl Iterator<Item = (usize, f64)> {
        (0..3).map(move |i| (usize::from(self.bins[i]), f64::from(self.w[i]) / 255.0))
    }

    /// A per-direction quantity read along this direction.
    fn read(self, values: &[f32; DIRECTIONS]) -> f64 {
        self.parts().map(|(j, w)| w * f64::from(values[j])).sum()
    }

    /// A per-direction colour read along this direction.
    fn read_rgb(self, values: &[Vec3; DIRECTIONS]) -> DVec3 {
        self.parts().map(|(j, w)| values[j].as_dvec3() * w).sum()
    }
}

/// A table over the directions, per origin (emitted, reflected light), in f32 to keep
/// clusters small.
type Table = [[Vec3; DIRECTIONS]; 2];

const EMPTY: Table = [[Vec3::ZERO; DIRECTIONS]; 2];

fn add_tables(a: &Table, b: &Table) -> Table {
    std::array::from_fn(|o| std::array::from_fn(|j| a[o][j] + b[o][j]))
}

/// Light arriving at a cluster: per table direction, the flux density (W/m^2 through a plane
/// facing the light) and where within the bin it comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Incoming {
    flux: Table,
    /// Per bin: the luminance-weighted sum of the unit directions toward the light's sources
    /// (xyz) and the weights' sum (w), so that xyz / w is the mean direction the bin's light
    /// comes from.
    aim: [Vec4; DIRECTIONS],
}

const NOTHING: Incoming = Incoming {
    flux: EMPTY,
    aim: [Vec4::ZERO; DIRECTIONS],
};

impl Incoming {
    fn add(&self, other: &Self) -> Self {
        Self {
            flux: add_tables(&self.flux, &other.flux),
            aim: std::array::from_fn(|j| self.aim[j] + other.aim[j]),
        }
    }

    /// Irradiance on a surface facing `n`. Each bin's light is taken along the mean direction
    /// it came from, not along the bin's own direction: a beam from `u` is split over the
    /// three bins around `u` (see [`Dir`]), and clamping the cosine to each of those bins'
    /// directions gives a surface nearly edge-on to `u` light from the bin on its side, up to
    /// 20 degrees past its terminator. The spheres' sides that see only grazing light were
    /// 7-17 % too bright that way (a 10k-triangle room against progressive refinement and a
    /// path tracer). Along the mean direction one beam gives exactly `max(0, n . u)`.
    fn facing(&self, dirs: &[DVec3; DIRECTIONS], n: DVec3) -> [DVec3; 2] {
        let along: [f64; DIRECTIONS] = std::array::from_fn(|j| {
            let a = self.aim[j];
            let m = if a.w > 0.0 {
                a.truncate().as_dvec3() / f64::from(a.w)
            } else {
                dirs[j]
            };
            n.dot(m)
        });
        std::array::from_fn(|o| {
            let mut e = DVec3::ZERO;
            for (j, &c) in along.iter().enumerate() {
                if c > 0.0 && self.flux[o][j] != Vec3::ZERO {
                    e += self.flux[o][j].as_dvec3() * c;
                }
            }
            e
        })
    }
}

/// The angle between two unit vectors, radians.
fn angle(a: DVec3, b: DVec3) -> f64 {
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// The smallest cone (unit axis, half-angle) around two cones.
fn merge_cones(a: (DVec3, f64), b: (DVec3, f64)) -> (DVec3, f64) {
    let between = angle(a.0, b.0);
    if between + b.1 <= a.1 {
        return a;
    }
    if between + a.1 <= b.1 {
        return b;
    }
    let half = (between + a.1 + b.1) / 2.0;
    if half >= PI || !(1e-12..=PI - 1e-6).contains(&between) {
        return (a.0, if between < 1e-12 { half } else { PI });
    }
    // Turn a's axis toward b's by (half - a's half-angle).
    let t = (half - a.1) / between;
    let axis = (a.0 * ((1.0 - t) * between).sin() + b.0 * (t * between).sin()) / between.sin();
    (axis.normalize_or(a.0), half)
}

impl Eval {
    /// Whether the link carries no light: no corner and no part of the receiver gets any.
    fn carries_nothing(&self) -> bool {
        self.transport.iter().all(|&v| v <= 0.0) && self.area_correction <= 0.0
    }
}

/// Node geometry the link estimates need.
struct Ends {
    center: DVec3,
    radius: f64,
    area: f64,
}

/// Approximate bytes per surface node (mesh node, vertex share, per-node sums and corners).
const BYTES_PER_NODE: u64 = 480;
/// Bytes per cluster (about one per triangle): its node, its incoming light, the light it sends
/// by direction and its projected area by direction.
const BYTES_PER_CLUSTER: u64 = (std::mem::size_of::<Incoming>()
    + std::mem::size_of::<Table>()
    + std::mem::size_of::<[f32; DIRECTIONS]>()
    + 120) as u64;
/// Approximate bytes per link (the link, sorting and the candidates of a refinement pass).
const BYTES_PER_LINK: u64 = 96;
/// Candidates evaluated between two looks at the clock.
const BATCH: usize = 1 << 14;
/// A link with a cluster at an end is near, and must be refined, unless the ends' centres
/// are farther apart than this many times the sum of their bounding radii: the isotropic
/// far-field estimate holds only well away from a cluster.
const SEPARATION: f64 = 2.0;
/// How far a surface node's receiving corners sit inside it, as a fraction of the way to its
/// centroid. A corner on an edge that the node shares with a perpendicular surface must lie
/// clearly in front of that surface's plane, or the form factor counts it as in the plane
/// and gives 0 where the true value is near 1/2: with the smallest elements 200 times finer
/// than the largest surfaces and the plane test at 1e-6 of the source's size, 2e-3 keeps a
/// margin of about 2.5 (at 1e-5 a cube's edge vertices showed 10 % too little light once
/// refinement reached the smallest elements there).
const CORNER_INSET: f64 = 2e-3;
/// Re-refinements with converged radiosities at most.
const MAX_ROUNDS: u32 = 6;

/// A hierarchical radiosity solve with clustering over a scene. Deterministic: the same
/// options and seed give the same solution bit for bit on any number of threads (without a
/// time budget).
pub struct HierarchicalSolver<'s> {
    scene: &'s Scene,
    options: Options,
    mesh: ElementMesh,
    clusters: Clusters,
    min_size: f32,
    /// Link error threshold, W (luminance, scene units).
    error_threshold: f64,
    /// Per scene triangle: reflectance and emitted exitance E = pi L_e.
    tri_rho: Vec<DVec3>,
    tri_emission: Vec<DVec3>,
    /// Links, sorted by receiver, and where each receiver's run starts.
    links: Vec<Link>,
    receivers: Vec<(NodeRef, u32)>,
    /// Per surface node: irradiance its own links gathered at its corners (from emitted and
    /// from reflected light), and its area-averaged exitance (emitted, reflected).
    gathered: Vec<[[DVec3; 4]; 2]>,
    exitance: Vec<[DVec3; 2]>,
    /// Surface nodes at the last push-pull: those from this index on were split off since, and
    /// have sent nothing yet.
    settled: usize,
    /// Per surface node and per cluster: the range (largest less smallest) of the exitance
    /// luminance of the leaves below, W/m^2: how far from uniform a source is.
    spread: Vec<f64>,
    cluster_spread: Vec<f64>,
    /// Per surface leaf: irradiance at its corners after push (emitted, reflected light).
    corners_in: Vec<[[DVec3; 4]; 2]>,
    /// Per cluster: the same, one value per cluster.
    /// Per cluster: the flux density arriving from each table direction (from the cluster
    /// toward the sources), gathered by its own links; pushed down, each surface inside takes
    /// it by its orientation.
    cluster_gathered: Vec<Incoming>,
    cluster_exitance: Vec<[DVec3; 2]>,
    /// Per cluster: its radiant intensity times pi toward each table direction, W: the sum
    /// over its triangles of exitance x area x clamped cosine. A cluster source sends this.
    radiant: Vec<Table>,
    /// Per cluster: its projected area toward each table direction, scene units squared.
    projected: Vec<[f32; DIRECTIONS]>,
    /// Per cluster: a cone (unit axis, half-angle in radians) holding the normals of every
    /// triangle inside, geometric and shading: what cannot face a node is never linked to it.
    cones: Vec<(DVec3, f64)>,
    dirs: [DVec3; DIRECTIONS],
    /// Residual power of the last iteration per channel (signed), and its fraction.
    residual: DVec3,
    residual_fraction: f64,
    emitted: DVec3,
    /// Rounds, time and power, kept as the other solver keeps them.
    bookkeeping: Bookkeeping,
    iterations: u64,
    rays: u64,
    linked: bool,
    /// Past the time budget: links still being decided get the first, coarse visibility
    /// estimate only (no confirmation, no finer count, no visibility per corner), so that the
    /// candidates left when the budget runs out cost a few rays each, not dozens.
    out_of_time: bool,
    /// The partly blocked links have had their visibility estimated again with the
    /// converged radiosities.
    refreshed: bool,
    max_links: usize,
    max_nodes: usize,
    /// The specular transfer, when the scene needs it ([`specular::decide`]): light the
    /// leaves send through mirrors and glass, deposited on the vertices it lands near.
    specular: Option<SpecularReceivers>,
    /// The mesh changed since the deposits were last splatted onto it.
    specular_stale: bool,
}

/// A random affine permutation `m -> (mult m + off) mod n` of `0..n` from hash `h`: `off`
/// uniform in `0..n`, `mult` coprime to `n`.
fn pairing(h: u64, n: u64) -> (u64, u64) {
    fn gcd(a: u64, b: u64) -> u64 {
        if b == 0 { a } else { gcd(b, a % b) }
    }
    let n = n.max(1);
    let mut mult = 1 + hash(h) % n;
    while gcd(mult, n) != 1 {
        mult = mult % n + 1;
    }
    (mult, h % n)
}

/// The visible fraction from weighted ray counts `[geometric, geometric x source exitance]`:
/// by the exitance-weighted sums when the source points sent anything, else by the geometric
/// ones; 0 when no weight at all (every pair at a grazing angle).
fn weighted_fraction(seen: [f64; 2], all: [f64; 2]) -> f64 {
    if all[1] > 0.0 {
        (seen[1] / all[1]).clamp(0.0, 1.0)
    } else if all[0] > 0.0 {
        (seen[0] / all[0]).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

impl<'s> HierarchicalSolver<'s> {
    /// Builds the cluster tree over the participating triangles. Objects that neither emit
    /// nor reflect diffusely still cast shadows.
    pub fn new(scene: &'s Scene, options: Options) -> Result<Self, SolveError> {
        if scene.emitters.is_empty() {
            return Err(SolveError::NoEmitters);
        }
        let diag = scene.bounds.diagonal();
        let h = options.hierarchical;
        let min_size = h.min_element_size.unwrap_or(diag / 200.0);
        if !(min_size.is_finite() && min_size > 0.0) {
            return Err(SolveError::Option {
                name: "min_element_size",
                problem: format!("{min_size} must be finite and > 0 scene units"),
            });
        }
        if !(h.link_tolerance.is_finite() && h.link_tolerance > 0.0) {
            return Err(SolveError::Option {
                name: "link_tolerance",
                problem: format!("{} must be finite and > 0", h.link_tolerance),
            });
        }
        check_common(&options)?;
        let takes_part = participating(scene);
        if !takes_part.iter().any(|&t| t) {
            return Err(SolveError::NothingTakesPart);
        }
        let triangles = scene
            .mesh
            .triangle_object
            .iter()
            .filter(|&&o| takes_part[o as usize])
            .count() as u64;
        // The triangles themselves, their clusters, and room for links: refuse up front what
        // cannot fit.
        let base = triangles * (BYTES_PER_NODE + BYTES_PER_CLUSTER);
        if base > options.memory_limit {
            return Err(SolveError::TooLarge {
                what: format!("the hierarchy over {triangles} triangles"),
                bytes: base,
                limit: options.memory_limit,
            });
        }
        let started = Instant::now();
        let mesh = ElementMesh::new(scene, &takes_part);
        let tri_rho: Vec<DVec3> = (0..scene.mesh.triangles.len())
            .map(|t| {
                let o = &scene.objects[scene.mesh.triangle_object[t] as usize];
                scene.materials[o.material as usize]
                    .material
                    .diffuse_albedo()
                    .as_dvec3()
            })
            .collect();
        let tri_emission: Vec<DVec3> = (0..scene.mesh.triangles.len())
            .map(|t| {
                scene.objects[scene.mesh.triangle_object[t] as usize]
                    .emission
                    .as_dvec3()
                    * PI
            })
            .collect();
        let rho_lum: Vec<f64> = tri_rho.iter().map(|&r| luminance_f64(r)).collect();
        let clusters = Clusters::build(&mesh, &rho_lum).ok_or(SolveError::NothingTakesPart)?;
        let spare = options.memory_limit - base;
        let mut s = Self {
            scene,
            mesh,
            clusters,
            min_size,
            error_threshold: 0.0,
            tri_rho,
            tri_emission,
            links: Vec::new(),
            receivers: Vec::new(),
            gathered: Vec::new(),
            exitance: Vec::new(),
            settled: 0,
            spread: Vec::new(),
            cluster_spread: Vec::new(),
            corners_in: Vec::new(),
            cluster_gathered: Vec::new(),
            cluster_exitance: Vec::new(),
            radiant: Vec::new(),
            projected: Vec::new(),
            cones: Vec::new(),
            dirs: directions(),
            residual: DVec3::ZERO,
            residual_fraction: 1.0,
            emitted: DVec3::ZERO,
            bookkeeping: Bookkeeping::new(started, Duration::ZERO),
            iterations: 0,
            rays: 0,
            linked: false,
            out_of_time: false,
            refreshed: false,
            max_links: (spare / 2 / BYTES_PER_LINK) as usize,
            max_nodes: (spare / 2 / BYTES_PER_NODE) as usize,
            specular: options
                .specular
                .and_then(|settings| Specular::new(scene, settings, &takes_part))
                .map(SpecularReceivers::new),
            specular_stale: false,
            options,
        };
        s.grow_arrays();
        s.project();
        s.emitted = s
            .mesh
            .leaves()
            .map(|n| {
                let node = &s.mesh.nodes[n as usize];
                s.tri_emission[node.scene_triangle as usize] * f64::from(node.area)
            })
            .sum();
        s.error_threshold = h.link_tolerance * luminance_f64(s.emitted).max(f64::MIN_POSITIVE);
        // Before the first gather every node's exitance is its emission.
        s.push_pull();
        s.bookkeeping.energy.emitted = s.emitted;
        s.bookkeeping.energy.unshot = s.emitted;
        s.bookkeeping.meshing = started.elapsed();
        Ok(s)
    }

    /// Each cluster's projected area toward the table directions (children come after their
    /// parent, so a reverse sweep sees every child first).
    fn project(&mut self) {
        let mut projected = vec![[0.0f32; DIRECTIONS]; self.clusters.nodes.len()];
        let mut cones = vec![(DVec3::Z, 0.0); self.clusters.nodes.len()];
        for c in (0..self.clusters.nodes.len()).rev() {
            let mut sum = [0.0f64; DIRECTIONS];
            let children = self.clusters.nodes[c].children;
            let cone = |x: NodeRef| match x.kind() {
                Kind::Cluster(cc) => cones[cc as usize],
                Kind::Surface(n) => self.surface_cone(n),
            };
            cones[c] = merge_cones(cone(children[0]), cone(children[1]));
            for child in children {
                match child.kind() {
                    Kind::Cluster(cc) => {
                        for (s, p) in sum.iter_mut().zip(&projected[cc as usize]) {
                            *s += f64::from(*p);
                        }
                    }
                    Kind::Surface(n) => {
                        let node = &self.mesh.nodes[n as usize];
                        let normal = self.scene.mesh.geometric_normals
                            [node.scene_triangle as usize]
                            .as_dvec3();
                        for (s, d) in sum.iter_mut().zip(&self.dirs) {
                            *s += f64::from(node.area) * normal.dot(*d).max(0.0);
                        }
                    }
                }
            }
            projected[c] = sum.map(|s| s as f32);
        }
        self.projected = projected;
        self.cones = cones;
    }

    /// The normal cone of a surface node: its geometric normal, widened to its corners'
    /// shading normals.
    fn surface_cone(&self, n: u32) -> (DVec3, f64) {
        let node = &self.mesh.nodes[n as usize];
        let g = self.scene.mesh.geometric_normals[node.scene_triangle as usize].as_dvec3();
        let spread = node
            .vertices
            .iter()
            .map(|&v| angle(g, self.mesh.vertices[v as usize].normal.as_dvec3()))
            .fold(0.0, f64::max);
        (g, spread)
    }

    fn cone(&self, r: NodeRef) -> (DVec3, f64) {
        match r.kind() {
            Kind::Cluster(c) => self.cones[c as usize],
            Kind::Surface(n) => self.surface_cone(n),
        }
    }

    /// Whether no surface of `s` can send light to any surface of `r` (normal-cone culling,
    /// Shirman & Abi-Ezzi 1993): every normal of the source points away from every direction
    /// toward the receiver, or every normal of the receiver away from the source. Two parts of
    /// one convex object are never linked.
    fn faces_away(&self, r: NodeRef, s: NodeRef) -> bool {
        let (er, es) = (self.ends(r), self.ends(s));
        let d = er.center - es.center;
        let dist = d.length();
        let reach = er.radius + es.radius;
        if dist <= reach {
            return false;
        }
        let u = d / dist;
        let spread = (reach / dist).asin();
        let right = std::f64::consts::FRAC_PI_2;
        let (a_s, t_s) = self.cone(s);
        let (a_r, t_r) = self.cone(r);
        angle(a_s, u) - t_s - spread >= right || angle(a_r, -u) - t_r - spread >= right
    }

    /// Extends the per-node arrays to new surface nodes and clusters.
    fn grow_arrays(&mut self) {
        let n = self.mesh.nodes.len();
        self.gathered.resize(n, [[DVec3::ZERO; 4]; 2]);
        self.exitance.resize(n, [DVec3::ZERO; 2]);
        self.spread.resize(n, 0.0);
        self.corners_in.resize(n, [[DVec3::ZERO; 4]; 2]);
        let c = self.clusters.nodes.len();
        self.cluster_gathered.resize(c, NOTHING);
        self.cluster_exitance.resize(c, [DVec3::ZERO; 2]);
        self.radiant.resize(c, EMPTY);
        self.cluster_spread.resize(c, 0.0);
        if let Some(spec) = &mut self.specular {
            spec.sent.resize(n, None);
            self.specular_stale = true;
        }
    }

    /// With the specular transfer: every deposit so far splatted afresh onto the current mesh
    /// ([`SpecularReceivers::resplat`]; after a refinement the deposits land on the finer
    /// leaves).
    fn resplat(&mut self) {
        self.specular_stale = false;
        if let Some(spec) = &mut self.specular {
            spec.resplat(&self.mesh);
        }
    }

    /// With the specular transfer: every leaf sends what its exitance changed by since it last
    /// sent through the specular surfaces ([`Specular::shoot_changes`]); changes totalling
    /// under a tenth of the stop's unshot fraction of the emitted power wait for the next
    /// gather. The deposits are splatted onto the vertices as irradiance, which the next gather
    /// adds to the leaves' reflected light.
    fn shoot_specular(&mut self) {
        let Some(spec) = &self.specular else {
            return;
        };
        let changes: Vec<(u32, [DVec3; 2])> = self
            .mesh
            .leaves()
            .map(|n| {
                let sent = spec.sent(&self.mesh, n);
                let [e, r] = self.exitance[n as usize];
                (n, [e - sent[0], r - sent[1]])
            })
            .collect();
        let emitted = luminance_f64(self.emitted).max(f64::MIN_POSITIVE);
        let key = hash(self.options.seed ^ hash(0x5bec_4e00_0000_0000 ^ self.iterations));
        let threshold = 0.1 * self.options.stop.unshot_fraction * emitted;
        let Some((mut deposits, cast)) = spec
            .transfer
            .shoot_changes(self.scene, &self.mesh, &changes, emitted, threshold, key)
        else {
            return;
        };
        let spec = self.specular.as_mut().expect("the transfer shot");
        spec.note_sent(&self.mesh, &changes);
        self.rays += cast;
        spec.splat(&self.mesh, Some(&mut deposits));
        spec.keep(deposits, cast);
    }

    /// With the specular transfer: rays it cast and deposits it made so far; `None` when the
    /// scene does not need it ([`specular::decide`]) or the options turned it off.
    pub fn specular_transfer(&self) -> Option<(u64, usize)> {
        self.specular.as_ref().map(SpecularReceivers::counts)
    }

    /// The links node `r` receives (they are sorted by receiver).
    fn received(&self, r: NodeRef) -> &[Link] {
        match self.receivers.binary_search_by_key(&r, |&(x, _)| x) {
            Ok(i) => {
                let start = self.receivers[i].1 as usize;
                let end = self
                    .receivers
                    .get(i + 1)
                    .map_or(self.links.len(), |&(_, e)| e as usize);
                &self.links[start..end]
            }
            Err(_) => &[],
        }
    }

    /// The deepest ancestor of surface node `n` that took part in the last push-pull (`n`
    /// itself if it did).
    fn settled_ancestor(&self, n: u32) -> u32 {
        let path = self.mesh.path_to(n);
        path.iter()
            .rev()
            .copied()
            .find(|&a| (a as usize) < self.settled)
            .unwrap_or(path[0])
    }

    /// The oracle: estimated error of a link's transport, as power (W, luminance).
    fn link_error(&self, l: &Link) -> f64 {
        let mut e = self.source_value(l);
        // A piece of a source split in this refinement pass has sent nothing yet. Judged by
        // that, a partly blocked link from a piece of an emitter looked harmless and was kept
        // or dropped on a few rays, never refined around the shadow (a sphere 84 % hidden
        // from the light got 0.13 of its direct light). Such a link is judged by what the
        // piece's parent sent. Only partly blocked links: refining unblocked ones by it too
        // refines a closed room's creases to the smallest elements in the first pass.
        if let (true, Kind::Surface(n)) = (l.partial, l.source.kind())
            && n as usize >= self.settled
        {
            e = self.exitance[self.settled_ancestor(n) as usize];
        }
        // A surface source's departure from uniform exitance (a cluster link's error is its
        // whole transport already).
        let s = match l.source.kind() {
            Kind::Cluster(_) => 0.0,
            Kind::Surface(n) => self.spread[n as usize],
        };
        let mean_k =
            (f64::from(l.transport[0]) + f64::from(l.transport[1]) + f64::from(l.transport[2]))
                / 3.0;
        // Form-factor error at the source's mean exitance, plus the source's own departure
        // from uniform exitance carried at the link's mean form factor.
        self.rho_lum(l.receiver)
            * (luminance_f64(e[0] + e[1]) * f64::from(l.error)
                + s * mean_k * self.ends(l.receiver).area)
    }

    fn ends(&self, r: NodeRef) -> Ends {
        match r.kind() {
            Kind::Cluster(c) => {
                let cl = &self.clusters.nodes[c as usize];
                Ends {
                    center: cl.center,
                    radius: cl.radius,
                    area: cl.area,
                }
            }
            Kind::Surface(n) => {
                let p = self.mesh.corners(n);
                let center = (p[0] + p[1] + p[2]) / 3.0;
                let radius = p.iter().map(|q| (*q - center).length()).fold(0.0, f64::max);
                Ends {
                    center,
                    radius,
                    area: f64::from(self.mesh.nodes[n as usize].area),
                }
            }
        }
    }

    /// Reflectance luminance of a receiver (the largest inside a cluster).
    fn rho_lum(&self, r: NodeRef) -> f64 {
        match r.kind() {
            Kind::Cluster(c) => self.clusters.nodes[c as usize].rho_max,
            Kind::Surface(n) => {
                luminance_f64(self.tri_rho[self.mesh.nodes[n as usize].scene_triangle as usize])
            }
        }
    }

    /// What a link's source sends (emitted, reflected light), per unit of the link's `transport`:
    /// a surface's area-averaged exitance (W/m^2), a cluster's radiant table entry toward
    /// the receiver (W).
    fn source_value(&self, l: &Link) -> [DVec3; 2] {
        match l.source.kind() {
            Kind::Cluster(c) => {
                let t = &self.radiant[c as usize];
                [l.dir.read_rgb(&t[0]), l.dir.read_rgb(&t[1])]
            }
            Kind::Surface(n) => self.exitance[n as usize],
        }
    }

    fn splittable(&self, r: NodeRef) -> bool {
        match r.kind() {
            Kind::Cluster(_) => true,
            Kind::Surface(n) => {
                self.mesh.nodes[n as usize].children.is_some()
                    || self.mesh.longest_edge_length(n) > self.min_size
            }
        }
    }

    fn children(&self, r: NodeRef) -> [NodeRef; 2] {
        match r.kind() {
            Kind::Cluster(c) => self.clusters.nodes[c as usize].children,
            Kind::Surface(n) => self.mesh.nodes[n as usize]
                .children
                .expect("a split surface node has children")
                .map(NodeRef::surface),
        }
    }

    /// A point on node `r` for three uniform numbers: area-uniform over a surface node; over a
    /// cluster, a triangle picked by area and a uniform point on it. Also the leaf of the
    /// element mesh it lies on.
    fn sample_point(&self, r: NodeRef, u: [f64; 3]) -> (SurfacePoint, u32) {
        let (t, uv, from) = match r.kind() {
            Kind::Surface(n) => {
                let node = &self.mesh.nodes[n as usize];
                let s = u[0].sqrt();
                let w = [1.0 - s, s * (1.0 - u[1]), s * u[1]];
                let b = node.uv[0].as_dvec2() * w[0]
                    + node.uv[1].as_dvec2() * w[1]
                    + node.uv[2].as_dvec2() * w[2];
                (node.scene_triangle, b, n)
            }
            Kind::Cluster(c) => {
                let (t, _) = self.clusters.pick_triangle(c, u[0]);
                let s = u[1].sqrt();
                let b = DVec2::new(s * (1.0 - u[2]), s * u[2]);
                (t, b, self.mesh.roots[t as usize])
            }
        };
        let point = self
            .scene
            .mesh
            .surface_point(t, [(1.0 - uv.x - uv.y) as f32, uv.x as f32, uv.y as f32]);
        (point, self.descend(from, uv.as_vec2()))
    }

    /// The leaf below surface node `n` that holds the point `uv` (triangle parameters).
    fn descend(&self, mut n: u32, uv: Vec2) -> u32 {
        while let Some([c0, c1]) = self.mesh.nodes[n as usize].children {
            // The first child is (a, m, c), cut from its sibling along m-c.
            let [a, m, c] = self.mesh.nodes[c0 as usize].uv;
            let side = |q: Vec2| (c - m).perp_dot(q - m);
            n = if side(uv) * side(a) >= 0.0 { c0 } else { c1 };
        }
        n
    }

    /// How much a shadow ray from `to` (on the receiving end) to `from` (on the sending end,
    /// on `leaf`) stands for: the source's exitance luminance there (W/m^2, its last gathered
    /// value) times the pair's geometric term cos cos / d^2, the distance held above a tenth of
    /// the ends' size so that a pair of points at a shared edge does not take all the weight.
    /// Zero when the source point sends nothing yet (before the first gather); the caller then
    /// falls back to the geometric term alone.
    fn ray_weight(
        &self,
        to: &SurfacePoint,
        from: &SurfacePoint,
        leaf: u32,
        near2: f64,
    ) -> [f64; 2] {
        let d = (from.position - to.position).as_dvec3();
        let l2 = d.length_squared().max(f64::MIN_POSITIVE);
        let cos2 = (to.normal.as_dvec3().dot(d) * -from.normal.as_dvec3().dot(d)).max(0.0) / l2;
        let g = cos2 / l2.max(near2);
        let [e, r] = self.exitance[leaf as usize];
        [g, g * luminance_f64(e + r).max(0.0)]
    }

    /// The visible fraction between two nodes from about `count` stratified shadow rays
    /// between points on both, each ray weighted by what it carries: the geometric term of its
    /// two ends and the exitance of its source point (see [`Self::ray_weight`]), so that a
    /// bright part of the source that the receiver sees and a dark part it does not (the
    /// floor in a sphere's shadow, hidden by the same sphere) are not averaged into a
    /// uniform source half seen. Pairs of points that face away from each other do not count:
    /// orientation is the form factor's business, the rays only look for what stands between.
    /// When no pair faces, a grid four times as fine is drawn (a few samples can all land on
    /// the far side of a cluster by chance); when it finds none either, the two ends do not
    /// face each other and nothing passes.
    fn visibility(&self, r: NodeRef, s: NodeRef, count: u32, seed: u64) -> (f64, u64) {
        let mut k = (f64::from(count).sqrt().round() as u32).max(1);
        let near = 0.1 * self.ends(r).radius.min(self.ends(s).radius);
        for _ in 0..2 {
            let mut total = 0u32;
            let (mut seen, mut all) = ([0.0f64; 2], [0.0f64; 2]);
            // Both ends are stratified k x k; receiver stratum `m` is paired with source
            // stratum `(mult m + off) mod k^2`, a permutation drawn per link. A fixed pairing
            // would tie one part of the receiver to one part of the source for every link, and
            // a blocker between those parts would be seen by all of them or none: a bias that
            // only finer strata remove. With a random permutation each pair is uniform over
            // both ends (the test's sphere 84 % hidden from the light: 0.13 of its direct
            // light with the fixed pairing, 0.35 with this one alone).
            let n = u64::from(k * k);
            let (mult, off) = pairing(hash(seed ^ 0x9e37_79b9), n);
            for m in 0..n {
                let (i, j) = ((m / u64::from(k)) as u32, (m % u64::from(k)) as u32);
                let p = (mult * m + off) % n;
                let (pi, pj) = ((p / u64::from(k)) as u32, (p % u64::from(k)) as u32);
                let h = hash(seed ^ (u64::from(k) << 48 | u64::from(i) << 24 | u64::from(j)));
                let kf = f64::from(k);
                let (a, _) = self.sample_point(
                    r,
                    [
                        (f64::from(i) + unit_f64(h)) / kf,
                        (f64::from(j) + unit_f64(hash(h))) / kf,
                        unit_f64(hash(h ^ 1)),
                    ],
                );
                let (b, leaf) = self.sample_point(
                    s,
                    [
                        (f64::from(pi) + unit_f64(hash(h ^ 2))) / kf,
                        (f64::from(pj) + unit_f64(hash(h ^ 3))) / kf,
                        unit_f64(hash(h ^ 4)),
                    ],
                );
                let d = b.position - a.position;
                if d.dot(a.normal) <= 0.0 || d.dot(b.normal) >= 0.0 {
                    continue;
                }
                total += 1;
                let w = self.ray_weight(&a, &b, leaf, near * near);
                if !self.scene.occluded_between(&a, &b) {
                    seen[0] += w[0];
                    seen[1] += w[1];
                }
                all[0] += w[0];
                all[1] += w[1];
            }
            if total > 0 {
                return (weighted_fraction(seen, all), u64::from(total));
            }
            k *= 2;
        }
        (0.0, 0)
    }

    /// The visible fraction of node `s` from surface point `from`, by about `count` stratified
    /// shadow rays to points of `s` that face it, weighted as in [`Self::visibility`]; 1 when
    /// none does (the form factor, which is zero then or nearly, has the last word).
    fn point_visibility(
        &self,
        from: &SurfacePoint,
        s: NodeRef,
        count: u32,
        seed: u64,
    ) -> (f64, u64) {
        let k = (f64::from(count).sqrt().round() as u32).max(1);
        let near = 0.1 * self.ends(s).radius;
        let mut total = 0u32;
        let (mut seen, mut all) = ([0.0f64; 2], [0.0f64; 2]);
        for i in 0..k {
            for j in 0..k {
                let h = hash(seed ^ (u64::from(i) << 24 | u64::from(j)));
                let (fi, fj, kf) = (f64::from(i), f64::from(j), f64::from(k));
                let (b, leaf) = self.sample_point(
                    s,
                    [
                        (fi + unit_f64(h)) / kf,
                        (fj + unit_f64(hash(h))) / kf,
                        unit_f64(hash(h ^ 1)),
                    ],
                );
                if (b.position - from.position).dot(b.normal) >= 0.0 {
                    continue;
                }
                total += 1;
                let w = self.ray_weight(from, &b, leaf, near * near);
                if !self.scene.occluded_between(from, &b) {
                    seen[0] += w[0];
                    seen[1] += w[1];
                }
                all[0] += w[0];
                all[1] += w[1];
            }
        }
        if total == 0 {
            return (1.0, 0);
        }
        (weighted_fraction(seen, all), u64::from(total))
    }

    /// The receiving points of a surface node: its corners, a hair inside (junction vertices
    /// receive from just inside their own surface, as in progressive refinement), and their
    /// receiving normals; plus the centroid and its normal.
    fn receiving_points(&self, n: u32) -> ([DVec3; 7], [DVec3; 7]) {
        let node = &self.mesh.nodes[n as usize];
        let p = self.mesh.corners(n);
        let c = (p[0] + p[1] + p[2]) / 3.0;
        let normals = node
            .vertices
            .map(|v| self.mesh.vertices[v as usize].normal.as_dvec3());
        let blend = |a: DVec3, b: DVec3| (a + b).try_normalize().unwrap_or(a);
        let nc = blend(normals[0] + normals[1], normals[2]);
        let inset = |q: DVec3| q + (c - q) * CORNER_INSET;
        let mid = |i: usize, j: usize| inset((p[i] + p[j]) * 0.5);
        (
            [
                inset(p[0]),
                inset(p[1]),
                inset(p[2]),
                c,
                mid(0, 1),
                mid(1, 2),
                mid(2, 0),
            ],
            [
                normals[0],
                normals[1],
                normals[2],
                nc,
                blend(normals[0], normals[1]),
                blend(normals[1], normals[2]),
                blend(normals[2], normals[0]),
            ],
        )
    }

    /// Unoccluded transport from surface node `q` to surface node `p`, per unit exitance of
    /// `q`: the point form factors at `p`'s seven receiving points (corners first), the shift
    /// (area average less the corners' mean) and the form-factor error estimate (per unit
    /// receiver area).
    fn surface_transport(&self, p: u32, q: u32) -> ([f64; 7], f64, f64) {
        let (x, n) = self.receiving_points(p);
        let (source, ns) = self.source_polygon(q);
        let mut f = [0.0; 7];
        source.form_factors_into(&x, &n, Some(ns), &mut f);
        // The corners keep their exact point values; the receiver's area-averaged form factor
        // sets the light it gets (interpolating a curved F linearly would lose or add light
        // with a consistent sign), by the seven-point rule exact for cubics (corners 1/20, edge
        // midpoints 2/15, centroid 9/20). The error estimate: how far that average is from the
        // corners' and from the quadratic rule's (corners 1/12, centroid 3/4), plus a part of
        // the spread.
        let mean = (f[0] + f[1] + f[2]) / 3.0;
        let average =
            (f[0] + f[1] + f[2]) / 20.0 + (f[4] + f[5] + f[6]) * (2.0 / 15.0) + f[3] * (9.0 / 20.0);
        let quadratic = mean / 4.0 + f[3] * 0.75;
        let (lo, hi) = f
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &v| (a.min(v), b.max(v)));
        (
            f,
            average - mean,
            (average - mean).abs() + (average - quadratic).abs() + 0.25 * (hi - lo),
        )
    }

    /// Unoccluded point form factors from surface node `q` at surface node `p`'s three
    /// receiving corners.
    fn corner_form_factors(&self, p: u32, q: u32) -> [f64; 3] {
        let (x, n) = self.receiving_points(p);
        let (source, ns) = self.source_polygon(q);
        let mut f = [0.0; 3];
        source.form_factors_into(&x[..3], &n[..3], Some(ns), &mut f);
        f
    }

    /// Surface node `q` as a source of point form factors (its corners, prepared) and its scene
    /// triangle's unit normal.
    fn source_polygon(&self, q: u32) -> (form_factor::SourceTriangle, DVec3) {
        let ns = self.scene.mesh.geometric_normals
            [self.mesh.nodes[q as usize].scene_triangle as usize]
            .as_dvec3();
        (form_factor::SourceTriangle::new(self.mesh.corners(q)), ns)
    }

    /// Transport, error estimate and visibility of the link `s -> r`, with `rays` shadow rays.
    fn evaluate(&self, r: NodeRef, s: NodeRef, rays: u32) -> Eval {
        let (er, es) = (self.ends(r), self.ends(s));
        let reach = SEPARATION * (er.radius + es.radius);
        let d2 = (es.center - er.center).length_squared();
        let near = d2 <= reach * reach;
        let far2 = d2.max(reach * reach).max(f64::MIN_POSITIVE);
        let dir = Dir::new(&self.dirs, (er.center - es.center).normalize_or(DVec3::Z));
        let mut near_cluster = false;
        let mut shift = 0.0;
        let (k, error) = match (r.kind(), s.kind()) {
            (Kind::Surface(p), Kind::Surface(q)) => {
                let (f, s, error) = self.surface_transport(p, q);
                shift = s;
                ([f[0], f[1], f[2]], er.area * error)
            }
            (Kind::Surface(p), Kind::Cluster(_)) => {
                // Irradiance at each corner per unit of the cluster's radiant table entry
                // toward it (intensity x pi): cos / (pi l^2).
                near_cluster = near;
                let (x, n) = self.receiving_points(p);
                let k: [f64; 3] = std::array::from_fn(|i| {
                    let d = es.center - x[i];
                    let l2 = d.length_squared().max(far2 * 0.25);
                    (n[i].dot(d) / l2.sqrt()).max(0.0) / (PI * l2)
                });
                (k, er.area * (k[0] + k[1] + k[2]) / 3.0)
            }
            (Kind::Cluster(c), Kind::Surface(q)) => {
                // Flux density at the cluster per unit source exitance: A cos / (pi l^2).
                near_cluster = near;
                let nq = self.scene.mesh.geometric_normals
                    [self.mesh.nodes[q as usize].scene_triangle as usize]
                    .as_dvec3();
                let d = er.center - es.center;
                let cos = (nq.dot(d) / d2.sqrt().max(f64::MIN_POSITIVE)).max(0.0);
                let v = es.area * cos / (PI * far2);
                ([v; 3], v * dir.opposite().read(&self.projected[c as usize]))
            }
            (Kind::Cluster(c), Kind::Cluster(_)) => {
                // Flux density per unit of the source's radiant table entry: 1 / (pi l^2).
                near_cluster = near;
                let v = 1.0 / (PI * far2);
                ([v; 3], v * dir.opposite().read(&self.projected[c as usize]))
            }
        };
        let mut e = Eval {
            transport: k,
            open: k,
            dir,
            area_correction: shift,
            error,
            near: near_cluster,
            partial: false,
            rays: 0,
        };
        // A near link is split whatever its visibility: no rays for it.
        if e.near || e.carries_nothing() || !self.options.occlusion {
            return e;
        }
        let seed = hash(self.options.seed ^ hash(u64::from(r.id()) << 32 | u64::from(s.id())));
        let (vis, cast) = self.visibility(r, s, rays, seed);
        e.rays = cast;
        // A few rays that all miss or all hit say little about a large pair: a blocked link is
        // counted as uncertain (its unoccluded transport is the error) so that it is refined
        // until its pieces are small or surely blocked, instead of dropped with its light.
        e.partial = vis < 1.0;
        // The light the receiver gets unoccluded: its area-averaged form factor (the corners
        // can all miss a source that the inside of a large element sees).
        let average =
            ((e.transport[0] + e.transport[1] + e.transport[2]) / 3.0 + e.area_correction).max(0.0);
        e.error = e.error * vis + if e.partial { er.area * average } else { 0.0 };
        e.transport = e.transport.map(|v| v * vis);
        e.area_correction *= vis;
        e
    }

    /// Whether a node can ever send light: it emits or reflects.
    fn may_shine(&self, s: NodeRef) -> bool {
        match s.kind() {
            Kind::Cluster(c) => {
                let cl = &self.clusters.nodes[c as usize];
                cl.rho_max > 0.0 || self.cluster_exitance[c as usize][0] != DVec3::ZERO
            }
            Kind::Surface(n) => {
                let t = self.mesh.nodes[n as usize].scene_triangle as usize;
                self.tri_rho[t] != DVec3::ZERO || self.tri_emission[t] != DVec3::ZERO
            }
        }
    }

    /// What to do with the candidate link `s -> r` (pure: safe to run in parallel).
    fn decide(&self, r: NodeRef, s: NodeRef, allow_split: bool) -> (Step, u64) {
        if r == s {
            return match r.kind() {
                Kind::Cluster(_) => (Step::SelfPair(r), 0),
                // A planar element sends nothing to itself.
                Kind::Surface(_) => (Step::Drop, 0),
            };
        }
        if self.rho_lum(r) <= 0.0 || !self.may_shine(s) || self.faces_away(r, s) {
            return (Step::Drop, 0);
        }
        if let (Kind::Surface(p), Kind::Surface(q)) = (r.kind(), s.kind())
            && self.mesh.nodes[p as usize].scene_triangle
                == self.mesh.nodes[q as usize].scene_triangle
        {
            return (Step::Drop, 0);
        }
        let vis = self.options.visibility;
        let mut e = self.evaluate(r, s, vis.min);
        let mut rays = e.rays;
        if !e.near && e.error <= 0.0 && e.carries_nothing() {
            return (Step::Drop, rays);
        }
        let link = |e: &Eval| Link {
            receiver: r,
            source: s,
            transport: e.transport.map(|v| v as f32),
            dir: e.dir,
            area_correction: e.area_correction as f32,
            error: e.error as f32,
            partial: e.partial,
        };
        // A few rays that all pass say little about a surface pair that carries much light: a
        // blocker that `n` rays all missed can still take about 1/(n + 1) of it (Laplace's
        // rule). Such a link is confirmed with the full count before it is trusted. (A
        // cluster link's error is its whole transport already.)
        if let (Kind::Surface(_), Kind::Surface(_)) = (r.kind(), s.kind())
            && !self.out_of_time
            && !e.partial
            && e.rays > 0
            && e.rays < u64::from(vis.max)
        {
            let carried = self.ends(r).area
                * ((e.transport[0] + e.transport[1] + e.transport[2]) / 3.0 + e.area_correction);
            let doubt = Link {
                error: (carried / (e.rays + 1) as f64) as f32,
                ..link(&e)
            };
            if self.link_error(&doubt) > self.error_threshold {
                e = self.evaluate(r, s, vis.max);
                rays += e.rays;
            }
        }
        if e.near || self.link_error(&link(&e)) > self.error_threshold {
            let (sr, ss) = (self.splittable(r), self.splittable(s));
            let receiver_first = match (sr, ss) {
                (false, false) => None,
                (true, false) => Some(true),
                (false, true) => Some(false),
                (true, true) => Some(match (r.kind(), s.kind()) {
                    (Kind::Surface(p), Kind::Surface(q)) => {
                        self.mesh.nodes[p as usize].area >= self.mesh.nodes[q as usize].area
                    }
                    _ => self.ends(r).radius >= self.ends(s).radius,
                }),
            };
            match receiver_first {
                // Past the time or memory budget nothing is split, near links included: they
                // are kept with their (bounded) far-field estimate.
                Some(true) if allow_split => return (Step::SplitReceiver(link(&e)), rays),
                Some(false) if allow_split => return (Step::SplitSource(link(&e)), rays),
                _ => {
                    // Nothing left to split: a finer visibility estimate is all that helps.
                    if e.partial && vis.max > vis.min && e.error > 0.0 && !self.out_of_time {
                        let more = self.evaluate(r, s, vis.max);
                        rays += more.rays;
                        e = more;
                    }
                }
            }
        }
        // A kept link between two surfaces that is partly blocked: the element keeps the light
        // its own visibility lets through (corners' mean plus shift), and the corners show one
        // visibility each, so that a shadow edge or an occluder standing on the element is
        // not smeared over the corners it spares.
        if let (true, false, Kind::Surface(p), Kind::Surface(_)) =
            (e.partial, self.out_of_time, r.kind(), s.kind())
        {
            let (x, _) = self.receiving_points(p);
            let tri = self.mesh.nodes[p as usize].scene_triangle;
            let total =
                (e.transport[0] + e.transport[1] + e.transport[2]) / 3.0 + e.area_correction;
            let mut corners = e.open;
            for (c, k) in corners.iter_mut().enumerate() {
                let from = self.scene.mesh.surface_point_at(tri, x[c].as_vec3());
                let seed = hash(
                    self.options.seed
                        ^ hash(u64::from(r.id()) << 32 | u64::from(s.id()))
                        ^ (c as u64 + 1),
                );
                let (v, cast) = self.point_visibility(&from, s, vis.max, seed);
                *k *= v;
                rays += cast;
            }
            e.transport = corners;
            e.area_correction = total - (corners[0] + corners[1] + corners[2]) / 3.0;
        }
        if e.carries_nothing() {
            return (Step::Drop, rays);
        }
        (Step::Keep(link(&e)), rays)
    }

    fn deadline_passed(&self) -> bool {
        self.options
            .stop
            .time_budget
            .is_some_and(|b| self.bookkeeping.started.elapsed() >= b)
    }

    /// Refines candidate pairs into links until every link is accurate enough, the nodes
    /// cannot be split, or a budget (time, memory) says stop. Each candidate may come from a
    /// link that was split (`Some(link)`): once the time budget has run out, such a link is
    /// kept whole instead of deciding its pieces (which costs shadow rays for each), unless a
    /// piece was decided already. Returns how many links it made.
    fn refine(&mut self, candidates: Vec<(NodeRef, NodeRef, Option<Link>)>) -> usize {
        let started = Instant::now();
        let before = self.links.len();
        // The links split on this level and what became of their pieces.
        let mut parents: Vec<(Link, Piece)> = Vec::new();
        let mut level: Vec<(NodeRef, NodeRef, u32)> = candidates
            .into_iter()
            .map(|(r, s, parent)| {
                let p = parent.map_or(u32::MAX, |l| {
                    parents.push((l, Piece::Untouched));
                    parents.len() as u32 - 1
                });
                (r, s, p)
            })
            .collect();
        while !level.is_empty() {
            let mut next = Vec::new();
            let mut next_parents: Vec<(Link, Piece)> = Vec::new();
            for batch in level.chunks(BATCH) {
                self.out_of_time = self.deadline_passed();
                let allow = !self.out_of_time
                    && self.links.len() + level.len() < self.max_links
                    && self.mesh.nodes.len() < self.max_nodes;
                // Past the budget, a split link none of whose pieces was decided comes back
                // whole (once); its other pieces are skipped.
                let mut todo = Vec::with_capacity(batch.len());
                for &(r, s, p) in batch {
                    match parents.get_mut(p as usize) {
                        Some((link, state)) if self.out_of_time && *state == Piece::Untouched => {
                            self.links.push(*link);
                            *state = Piece::Restored;
                        }
                        Some((_, Piece::Restored)) => {}
                        Some((_, state)) => {
                            *state = Piece::Decided;
                            todo.push((r, s));
                        }
                        None => todo.push((r, s)),
                    }
                }
                let steps: Vec<(Step, u64)> = todo
                    .par_iter()
                    .with_min_len(8)
                    .map(|&(r, s)| self.decide(r, s, allow))
                    .collect();
                // Split the surface leaves the steps need (conformingly), in a fixed order.
                let mut split: Vec<u32> = steps
                    .iter()
                    .filter_map(|(st, _)| match st {
                        Step::SplitReceiver(l) => Some(l.receiver),
                        Step::SplitSource(l) => Some(l.source),
                        _ => None,
                    })
                    .filter_map(|r| match r.kind() {
                        Kind::Surface(n) if self.mesh.nodes[n as usize].children.is_none() => {
                            Some(n)
                        }
                        _ => None,
                    })
                    .collect();
                split.sort_unstable();
                split.dedup();
                for n in split {
                    if self.mesh.nodes[n as usize].children.is_none() {
                        self.mesh.refine(n);
                    }
                }
                self.grow_arrays();
                for (st, rays) in steps {
                    self.rays += rays;
                    match st {
                        Step::Keep(l) => self.links.push(l),
                        Step::Drop => {}
                        Step::SelfPair(c) => {
                            let ch = self.children(c);
                            for a in ch {
                                for b in ch {
                                    next.push((a, b, u32::MAX));
                                }
                            }
                        }
                        Step::SplitReceiver(l) => {
                            next_parents.push((l, Piece::Untouched));
                            let p = next_parents.len() as u32 - 1;
                            for a in self.children(l.receiver) {
                                next.push((a, l.source, p));
                            }
                        }
                        Step::SplitSource(l) => {
                            next_parents.push((l, Piece::Untouched));
                            let p = next_parents.len() as u32 - 1;
                            for b in self.children(l.source) {
                                next.push((l.receiver, b, p));
                            }
                        }
                    }
                }
            }
            level = next;
            parents = next_parents;
        }
        self.sort_links();
        // New leaves take their ancestors' irradiance (interpolated) until the next gather.
        self.push_pull();
        self.bookkeeping.refining += started.elapsed();
        self.links.len().saturating_sub(before)
    }

    /// Estimates again the visibility of every partly blocked link, its rays now weighted by
    /// the converged exitance of the source points (the first estimate, made before the
    /// light was known, weighted by geometry alone; see [`Self::visibility`]). Returns how
    /// many links it estimated again.
    fn refresh_visibility(&mut self) -> usize {
        let started = Instant::now();
        let links = std::mem::take(&mut self.links);
        let redone = links.iter().filter(|l| l.partial).count();
        let results: Vec<(Option<Link>, u64)> = links
            .par_iter()
            .with_min_len(8)
            .map(|l| {
                if !l.partial {
                    return (Some(*l), 0);
                }
                match self.decide(l.receiver, l.source, false) {
                    (Step::Keep(n), rays) => (Some(n), rays),
                    (Step::Drop, rays) => (None, rays),
                    // Nothing splits when splitting is not allowed.
                    (_, rays) => (Some(*l), rays),
                }
            })
            .collect();
        for (l, rays) in results {
            self.rays += rays;
            self.links.extend(l);
        }
        self.sort_links();
        self.bookkeeping.refining += started.elapsed();
        redone
    }

    fn sort_links(&mut self) {
        self.links
            .par_sort_unstable_by_key(|l| (l.receiver, l.source));
        self.receivers.clear();
        for (i, l) in self.links.iter().enumerate() {
            if self.receivers.last().is_none_or(|&(r, _)| r != l.receiver) {
                self.receivers.push((l.receiver, i as u32));
            }
        }
    }

    /// Re-checks every link against the oracle with the current radiosities; refines those
    /// whose error is now too large. Returns how many were refined.
    fn rerefine(&mut self) -> usize {
        let error_threshold = self.error_threshold;
        let (keep, redo): (Vec<Link>, Vec<Link>) =
            std::mem::take(&mut self.links).into_iter().partition(|l| {
                !(self.link_error(l) > error_threshold
                    && (self.splittable(l.receiver) || self.splittable(l.source)))
            });
        self.links = keep;
        if redo.is_empty() || self.deadline_passed() {
            self.links.extend(redo);
            self.sort_links();
            return 0;
        }
        let n = redo.len();
        // Each goes through the refinement again from its own ends: it is re-evaluated and
        // split where the oracle says so.
        self.refine(
            redo.iter()
                .map(|l| (l.receiver, l.source, Some(*l)))
                .collect(),
        );
        n
    }

    /// One Jacobi gather over every link, then push-pull. Updates the residual.
    fn iterate(&mut self) {
        let links = &self.links;
        let receivers = &self.receivers;
        // A cluster's incoming light is boxed: most receivers are surfaces, and an unboxed
        // table per receiver was the largest transient of a large solve.
        type Gathered = ([[DVec3; 4]; 2], Option<Box<Incoming>>);
        let sums: Vec<Gathered> = receivers
            .par_iter()
            .enumerate()
            .with_min_len(64)
            .map(|(i, &(r, start))| {
                let end = receivers
                    .get(i + 1)
                    .map_or(links.len(), |&(_, e)| e as usize);
                let mut acc = [[DVec3::ZERO; 4]; 2];
                let mut flux = [[DVec3::ZERO; DIRECTIONS]; 2];
                let mut aim = [DVec3::ZERO; DIRECTIONS];
                let mut aim_weight = [0.0f64; DIRECTIONS];
                let cluster = matches!(r.kind(), Kind::Cluster(_));
                for l in &links[start as usize..end] {
                    let [be, br] = self.source_value(l);
                    if cluster {
                        // Arriving from the source's side: the opposite of `dir`.
                        let k = f64::from(l.transport[0]);
                        let toward = l.dir.opposite();
                        let u = toward
                            .parts()
                            .map(|(j, w)| self.dirs[j] * w)
                            .sum::<DVec3>()
                            .normalize_or(self.dirs[toward.parts().next().map_or(0, |p| p.0)]);
                        let y = luminance_f64(be + br) * k;
                        for (j, w) in toward.parts() {
                            flux[0][j] += be * k * w;
                            flux[1][j] += br * k * w;
                            aim[j] += u * (y * w);
                            aim_weight[j] += y * w;
                        }
                        continue;
                    }
                    for (c, &k) in l.transport.iter().enumerate() {
                        let k = f64::from(k);
                        acc[0][c] += be * k;
                        acc[1][c] += br * k;
                    }
                    let s = f64::from(l.area_correction);
                    acc[0][3] += be * s;
                    acc[1][3] += br * s;
                }
                let table = cluster.then(|| {
                    Box::new(Incoming {
                        flux: std::array::from_fn(|o| {
                            std::array::from_fn(|j| flux[o][j].as_vec3())
                        }),
                        aim: std::array::from_fn(|j| aim[j].as_vec3().extend(aim_weight[j] as f32)),
                    })
                });
                (acc, table)
            })
            .collect();
        for g in &mut self.gathered {
            *g = [[DVec3::ZERO; 4]; 2];
        }
        for g in &mut self.cluster_gathered {
            *g = NOTHING;
        }
        for (&(r, _), (s, table)) in self.receivers.iter().zip(sums) {
            match r.kind() {
                Kind::Surface(n) => self.gathered[n as usize] = s,
                Kind::Cluster(c) => {
                    self.cluster_gathered[c as usize] = table.map_or(NOTHING, |t| *t);
                }
            }
        }
        if self.specular_stale {
            self.resplat();
        }
        let before = self.leaf_power();
        self.push_pull();
        let after = self.leaf_power();
        self.shoot_specular();
        // Energy: what the sources sent (their exitance before this gather) against what
        // arrived, was absorbed, and is reflected but not yet passed on.
        let (mut arrived, mut absorbed) = (DVec3::ZERO, DVec3::ZERO);
        for n in self.mesh.leaves() {
            let node = &self.mesh.nodes[n as usize];
            let [e, r] = self.corners_in[n as usize];
            let irr = (e[0] + e[1] + e[2] + r[0] + r[1] + r[2]) / 3.0 + e[3] + r[3];
            let a = f64::from(node.area);
            arrived += irr * a;
            absorbed += irr * a * (DVec3::ONE - self.tri_rho[node.scene_triangle as usize]);
        }
        self.residual = after - before;
        self.bookkeeping.energy.absorbed = absorbed;
        self.bookkeeping.energy.escaped = before - arrived;
        self.bookkeeping.energy.unshot = self.residual;
        self.bookkeeping.energy.emitted = self.emitted;
        self.residual_fraction =
            self.residual.abs().element_sum() / self.emitted.element_sum().max(f64::MIN_POSITIVE);
        self.bookkeeping.note_imbalance();
        self.iterations += 1;
    }

    /// Power leaving all leaves, W per channel.
    fn leaf_power(&self) -> DVec3 {
        self.mesh
            .leaves()
            .map(|n| {
                let [e, r] = self.exitance[n as usize];
                (e + r) * f64::from(self.mesh.nodes[n as usize].area)
            })
            .sum()
    }

    /// Push irradiance down to the leaves (linearly interpolated inside surfaces), compute the
    /// leaves' exitance, pull area-averaged exitance back up.
    fn push_pull(&mut self) {
        let root = self.clusters.root;
        match root.kind() {
            Kind::Cluster(c) => {
                self.push_cluster(c, &NOTHING);
            }
            Kind::Surface(n) => {
                self.push_surface(n, [[DVec3::ZERO; 4]; 2]);
            }
        }
        // Every node has sent its own light now.
        self.settled = self.mesh.nodes.len();
    }

    /// Returns the cluster's area-weighted exitance sum (W) and the range of its leaves'
    /// exitance luminance.
    fn push_cluster(&mut self, c: u32, inherited: &Incoming) -> ([DVec3; 2], (f64, f64)) {
        let here = inherited.add(&self.cluster_gathered[c as usize]);
        let mut radiant = EMPTY;
        let mut power = [DVec3::ZERO; 2];
        let mut range = (f64::INFINITY, f64::NEG_INFINITY);
        for child in self.clusters.nodes[c as usize].children {
            let (p, r) = match child.kind() {
                Kind::Cluster(cc) => {
                    let out = self.push_cluster(cc, &here);
                    radiant = add_tables(&radiant, &self.radiant[cc as usize]);
                    out
                }
                Kind::Surface(n) => {
                    // Each corner gets the cluster's light by its receiving normal.
                    let normals = self.mesh.nodes[n as usize]
                        .vertices
                        .map(|v| self.mesh.vertices[v as usize].normal.as_dvec3());
                    let at = normals.map(|nk| here.facing(&self.dirs, nk));
                    let out = self.push_surface(
                        n,
                        std::array::from_fn(|o| [at[0][o], at[1][o], at[2][o], DVec3::ZERO]),
                    );
                    // The triangle's power toward each direction: exitance x area x cos.
                    let normal = self.scene.mesh.geometric_normals
                        [self.mesh.nodes[n as usize].scene_triangle as usize]
                        .as_dvec3();
                    for (j, d) in self.dirs.iter().enumerate() {
                        let c = normal.dot(*d);
                        if c > 0.0 {
                            for (o, p) in out.0.iter().enumerate() {
                                radiant[o][j] += (*p * c).as_vec3();
                            }
                        }
                    }
                    out
                }
            };
            power[0] += p[0];
            power[1] += p[1];
            range = (range.0.min(r.0), range.1.max(r.1));
        }
        let area = self.clusters.nodes[c as usize].area.max(f64::MIN_POSITIVE);
        self.cluster_exitance[c as usize] = [power[0] / area, power[1] / area];
        self.cluster_spread[c as usize] = range.1 - range.0;
        self.radiant[c as usize] = radiant;
        (power, range)
    }

    /// Returns the surface node's area-weighted exitance sum (W) and the range of its leaves'
    /// exitance luminance.
    fn push_surface(&mut self, n: u32, inherited: [[DVec3; 4]; 2]) -> ([DVec3; 2], (f64, f64)) {
        let node = self.mesh.nodes[n as usize];
        let g = self.gathered[n as usize];
        let here: [[DVec3; 4]; 2] =
            std::array::from_fn(|o| std::array::from_fn(|k| inherited[o][k] + g[o][k]));
        let area = f64::from(node.area);
        let (power, range) = match node.children {
            None => {
                let t = node.scene_triangle as usize;
                // What arrived through mirrors and glass, per vertex: reflected light (vertices
                // made since the last splat get theirs at the next gather).
                let mut here = here;
                for (k, &v) in node.vertices.iter().enumerate() {
                    if let Some(e) = self
                        .specular
                        .as_ref()
                        .and_then(|s| s.received.get(v as usize))
                    {
                        here[1][k] += *e;
                    }
                }
                // The light the leaf gets: its corners' linear interpolant plus the shifts of
                // the links above it (see [`Link::area_correction`]).
                let mean = |o: usize| (here[o][0] + here[o][1] + here[o][2]) / 3.0 + here[o][3];
                let b = [self.tri_emission[t], self.tri_rho[t] * (mean(0) + mean(1))];
                self.corners_in[n as usize] = here;
                let y = luminance_f64(b[0] + b[1]);
                ([b[0] * area, b[1] * area], (y, y))
            }
            Some(children) => {
                let mut power = [DVec3::ZERO; 2];
                let mut range = (f64::INFINITY, f64::NEG_INFINITY);
                for ch in children {
                    let child_uv = self.mesh.nodes[ch as usize].uv;
                    let w = child_uv.map(|p| barycentric_2d(node.uv, p));
                    let down: [[DVec3; 4]; 2] = std::array::from_fn(|o| {
                        std::array::from_fn(|k| match w.get(k) {
                            Some(w) => {
                                here[o][0] * f64::from(w[0])
                                    + here[o][1] * f64::from(w[1])
                                    + here[o][2] * f64::from(w[2])
                            }
                            None => here[o][3],
                        })
                    });
                    let (p, r) = self.push_surface(ch, down);
                    power[0] += p[0];
                    power[1] += p[1];
                    range = (range.0.min(r.0), range.1.max(r.1));
                }
                (power, range)
            }
        };
        let a = area.max(f64::MIN_POSITIVE);
        self.exitance[n as usize] = [power[0] / a, power[1] / a];
        self.spread[n as usize] = range.1 - range.0;
        (power, range)
    }

    /// Links the hierarchy (first call), then gathers to the stop criteria, re-refining links
    /// with the radiosities found. `observer` sees the solver after every iteration and can
    /// stop it by returning `Break`; the solution is usable whenever this returns.
    pub fn run(&mut self, mut observer: impl FnMut(&Self) -> ControlFlow<()>) -> Finish {
        let stop = self.options.stop;
        if !self.linked {
            let root = self.clusters.root;
            self.refine(vec![(root, root, None)]);
            self.linked = true;
        }
        // First converge coarsely, re-refine with those radiosities, then to the tolerance.
        let mut target = stop.unshot_fraction.max(1e-2);
        let mut last = f64::INFINITY;
        let mut stalled = 0;
        loop {
            if stop.max_shots.is_some_and(|m| self.iterations >= m) {
                return Finish::MaxShots;
            }
            // One gather at least, so a solution cut short still has its direct light.
            if self.deadline_passed() && self.iterations > 0 {
                return Finish::TimeBudget;
            }
            self.iterate();
            if observer(self).is_break() {
                return Finish::Cancelled;
            }
            if self.residual_fraction <= target {
                let refined = if self.bookkeeping.rounds < MAX_ROUNDS {
                    self.bookkeeping.rounds += 1;
                    self.rerefine()
                } else {
                    0
                };
                if refined == 0 && target <= stop.unshot_fraction {
                    if self.refreshed || self.deadline_passed() {
                        return Finish::Converged;
                    }
                    self.refreshed = true;
                    if self.refresh_visibility() == 0 {
                        return Finish::Converged;
                    }
                }
                if refined == 0 {
                    target = stop.unshot_fraction;
                }
                last = f64::INFINITY;
                stalled = 0;
                continue;
            }
            // Jacobi shrinks the residual by the scene's reflectance every iteration; when it
            // stops shrinking (rounding), nothing more is to be had.
            if self.residual_fraction >= last {
                stalled += 1;
                if stalled >= 8 {
                    return Finish::Exhausted;
                }
            } else {
                stalled = 0;
            }
            last = self.residual_fraction;
        }
    }

    /// Where the solve stands.
    pub fn progress(&self) -> SolveProgress {
        SolveProgress {
            iterations: self.iterations,
            links: self.links.len(),
            clusters: self.clusters.nodes.len(),
            unshot_fraction: self.residual_fraction,
            rays: self.rays,
            elements: self.mesh.leaves().count(),
            vertices: self.mesh.vertices.len(),
            ..self.bookkeeping.progress(Method::Hierarchical)
        }
    }

    /// The ambient term (as in progressive refinement): the residual power spread over the
    /// scene times the interreflection factor 1 / (1 - mean reflectance), W/m^2.
    pub fn ambient(&self) -> DVec3 {
        if self.iterations == 0 {
            return DVec3::ZERO;
        }
        let (mut rho, mut area) = (DVec3::ZERO, 0.0);
        for n in self.mesh.leaves() {
            let node = &self.mesh.nodes[n as usize];
            let a = f64::from(node.area);
            rho += self.tri_rho[node.scene_triangle as usize] * a;
            area += a;
        }
        ambient(self.residual.max(DVec3::ZERO), rho, area)
    }

    /// The current solution: per-vertex radiosity over the leaves, the area-weighted mean of
    /// the leaves' corner values at each vertex.
    /// The light each leaf's corners show: [`Self::corners_in`] with every unblocked
    /// surface-to-surface link above the leaf evaluated again at the leaf's own corners (a
    /// final gather at the vertices through the link hierarchy).
    ///
    /// A link attached above a leaf reaches the leaf's corners by linear interpolation of its
    /// corner values, and a uniform shift makes up what that interpolant misses of the
    /// receiver's area average. That is right for the power the receiver gets, and wrong
    /// pointwise wherever the form factor is curved over the receiver: a piece of the wall
    /// across a crease that touches the receiver's corner gives that corner close to 1/2
    /// (the half-plane limit) whatever its size, while a point a little way along the crease
    /// gets far less from it. Interpolated, that value spreads along the whole edge, and the
    /// links of every level above a crease vertex added up to 1.1-1.3 times its irradiance
    /// (a closed cube's crease vertices showed 13 % too much radiosity once refinement
    /// reached the smallest elements there). The sources linked above a receiver partition
    /// what it sees, so their exact point values at a vertex sum to its point irradiance.
    /// Those links show their point values and no shift; the leaf's power, and so the
    /// transport between leaves, is unchanged: only what the vertices show. Partly blocked
    /// links keep their per-corner visibility (the shadow edges) and cluster links their
    /// far-field values.
    fn display_corners(&self) -> Vec<[[DVec3; 4]; 2]> {
        let mut out = self.corners_in.clone();
        if self.links.is_empty() {
            return out;
        }
        // The unblocked surface-to-surface links a surface node receives.
        let received = |n: u32| {
            self.received(NodeRef::surface(n))
                .iter()
                .filter(|l| matches!(l.source.kind(), Kind::Surface(_)) && !l.partial)
        };
        let fixes: Vec<(u32, [[DVec3; 4]; 2])> = self
            .mesh
            .roots
            .par_iter()
            .filter(|&&root| (root as usize) < self.mesh.nodes.len())
            .flat_map_iter(|&root| {
                let mut fixes = Vec::new();
                // A node and the links above it, each with the node it is attached to and its
                // visible fraction.
                type Above = Vec<(Link, u32, f64)>;
                let mut stack: Vec<(u32, Above)> = vec![(root, Vec::new())];
                while let Some((n, mut above)) = stack.pop() {
                    let node = &self.mesh.nodes[n as usize];
                    if let Some(children) = node.children {
                        above.extend(received(n).filter_map(|l| {
                            let Kind::Surface(q) = l.source.kind() else {
                                return None;
                            };
                            // What the link carries over what its receiver's corners see of
                            // the source unoccluded (1 unless a later visibility estimate
                            // found some of it blocked).
                            let open: f64 = self.corner_form_factors(n, q).iter().sum();
                            let k: f64 = l.transport.iter().map(|&k| f64::from(k)).sum();
                            (open > 0.0).then(|| (*l, n, (k / open).clamp(0.0, 1.0)))
                        }));
                        stack.push((children[0], above.clone()));
                        stack.push((children[1], above));
                        continue;
                    }
                    let mut fix = [[DVec3::ZERO; 4]; 2];
                    for (l, a, vis) in &above {
                        let Kind::Surface(q) = l.source.kind() else {
                            continue;
                        };
                        let f = self.corner_form_factors(n, q);
                        let at = &self.mesh.nodes[*a as usize];
                        let sv = self.source_value(l);
                        for c in 0..3 {
                            let w = barycentric_2d(at.uv, node.uv[c]);
                            let interpolated = f64::from(l.transport[0]) * f64::from(w[0])
                                + f64::from(l.transport[1]) * f64::from(w[1])
                                + f64::from(l.transport[2]) * f64::from(w[2]);
                            let d = f[c] * vis - interpolated;
                            fix[0][c] += sv[0] * d;
                            fix[1][c] += sv[1] * d;
                        }
                        fix[0][3] -= sv[0] * f64::from(l.area_correction);
                        fix[1][3] -= sv[1] * f64::from(l.area_correction);
                    }
                    // The leaf's own links are exact at its corners already: no shift.
                    for l in received(n) {
                        let sv = self.source_value(l);
                        fix[0][3] -= sv[0] * f64::from(l.area_correction);
                        fix[1][3] -= sv[1] * f64::from(l.area_correction);
                    }
                    fixes.push((n, fix));
                }
                fixes
            })
            .collect();
        for (n, fix) in fixes {
            for (o, f) in fix.iter().enumerate() {
                for (k, d) in f.iter().enumerate() {
                    out[n as usize][o][k] += *d;
                }
            }
        }
        out
    }

    /// The current solution: per-vertex radiosity over the leaves, the area-weighted mean of
    /// the leaves' corner values at each vertex. Each vertex shows the point values of the
    /// unblocked surface links above it (a final gather), not their linear interpolation.
    pub fn solution(&self) -> Solution {
        let corners = self.display_corners();
        let nv = self.mesh.vertices.len();
        let mut sum = vec![[DVec3::ZERO; 2]; nv];
        let mut weight = vec![0.0f64; nv];
        for n in self.mesh.leaves() {
            let node = &self.mesh.nodes[n as usize];
            let a = f64::from(node.area).max(f64::MIN_POSITIVE);
            let [e, r] = corners[n as usize];
            for (k, &v) in node.vertices.iter().enumerate() {
                // Corner values plus the links' shifts, so the displayed light is the light
                // the leaf gets (see [`Link::area_correction`]).
                sum[v as usize][0] += (e[k] + e[3]) * a;
                sum[v as usize][1] += (r[k] + r[3]) * a;
                weight[v as usize] += a;
            }
        }
        let ambient = self.ambient();
        let (mut radiosity, mut direct, mut indirect, mut amb) = (
            Vec::with_capacity(nv),
            Vec::with_capacity(nv),
            Vec::with_capacity(nv),
            Vec::with_capacity(nv),
        );
        for (v, vert) in self.mesh.vertices.iter().enumerate() {
            let t = vert.triangle as usize;
            let (rho, e) = (self.tri_rho[t], self.tri_emission[t]);
            let w = weight[v].max(f64::MIN_POSITIVE);
            let d = rho * sum[v][0] / w;
            let i = rho * sum[v][1] / w;
            radiosity.push((e + d + i).as_vec3());
            direct.push(d.as_vec3());
            indirect.push(i.as_vec3());
            amb.push((rho * ambient).as_vec3());
        }
        let solution = Solution::new(self.mesh.clone(), radiosity, direct, indirect, amb);
        if let Some(spec) = &self.specular {
            // Splatted afresh when the mesh changed since the last gather.
            let fresh;
            let per_vertex = if self.specular_stale {
                let areas = specular::VertexAreas::new(&self.mesh);
                let mut deposits = spec.transfer.deposits.clone();
                let mut values = vec![DVec3::ZERO; nv];
                let part = specular::focused;
                specular::splat(
                    &self.mesh,
                    &areas,
                    &mut deposits,
                    &mut Vec::new(),
                    part,
                    &mut values,
                );
                fresh = values;
                &fresh
            } else {
                &spec.focused
            };
            let focused = self
                .mesh
                .vertices
                .iter()
                .zip(per_vertex)
                .map(|(vert, &f)| (self.tri_rho[vert.triangle as usize] * f).as_vec3())
                .collect();
            solution.with_focused_caustics(focused)
        } else {
            solution
        }
    }

    /// Consistency checks, their cost bounded by `samples`: the energy balance; the row sums
    /// (irradiance per unit exitance of every source: 1 in a closed scene) of up to `samples`
    /// leaves; and reciprocity A_r K_rs = A_s K_sr of up to `samples` surface-to-surface links,
    /// each against a fresh estimate of its reverse link.
    pub fn residuals(&mut self, samples: usize) -> Residuals {
        // Row sums: gather with every source at unit exitance, pushed down to the leaves.
        let leaves: Vec<u32> = self.mesh.leaves().collect();
        let step = (leaves.len() / samples.max(1)).max(1);
        let picked: Vec<u32> = leaves.iter().copied().step_by(step).take(samples).collect();
        let sums: Vec<f64> = picked.par_iter().map(|&leaf| self.row_sum(leaf)).collect();
        let ss: Vec<Link> = self
            .links
            .iter()
            .filter(|l| {
                matches!(
                    (l.receiver.kind(), l.source.kind()),
                    (Kind::Surface(_), Kind::Surface(_))
                )
            })
            .copied()
            .collect();
        let step = (ss.len() / samples.max(1)).max(1);
        let pairs: Vec<(f64, f64)> = ss
            .iter()
            .step_by(step)
            .take(samples)
            .collect::<Vec<_>>()
            .par_iter()
            .map(|l| {
                let back = self.evaluate(l.source, l.receiver, self.options.visibility.max);
                let fwd = self.evaluate(l.receiver, l.source, self.options.visibility.max);
                // Area-averaged form factors: the corners' mean plus the shift.
                let average = |e: &Eval| {
                    (e.transport[0] + e.transport[1] + e.transport[2]) / 3.0 + e.area_correction
                };
                (
                    self.ends(l.receiver).area * average(&fwd),
                    self.ends(l.source).area * average(&back),
                )
            })
            .collect();
        Residuals::from_samples(self.bookkeeping.worst_imbalance, &sums, pairs)
    }

    /// The sum of the transport coefficients that reach `leaf` (its own links and its
    /// ancestors', interpolated to it), averaged over its corners.
    fn row_sum(&self, leaf: u32) -> f64 {
        // Walk from the root to the leaf, summing the links of every node on the way.
        let path = self.mesh.path_to(leaf);
        let t = self.mesh.nodes[leaf as usize].scene_triangle;
        let sum_links = |r: NodeRef| -> f64 {
            self.received(r)
                .iter()
                .map(|l| self.unit_transport(l))
                .sum()
        };
        let mut total: f64 = path.iter().map(|&n| sum_links(NodeRef::surface(n))).sum();
        // Then the clusters above the triangle, up to the root.
        let mut c = self.clusters.triangle_parent[t as usize];
        while c != u32::MAX {
            total += sum_links(NodeRef::cluster(c));
            c = self.clusters.nodes[c as usize].parent;
        }
        total
    }

    /// A link's mean irradiance at its receiver per unit exitance of a uniform source: a
    /// cluster source sends its projected area toward the receiver, a cluster receiver spreads
    /// what it intercepts over its area.
    fn unit_transport(&self, l: &Link) -> f64 {
        let mean =
            (f64::from(l.transport[0]) + f64::from(l.transport[1]) + f64::from(l.transport[2]))
                / 3.0;
        let sent = match l.source.kind() {
            Kind::Cluster(c) => l.dir.read(&self.projected[c as usize]),
            Kind::Surface(_) => 1.0,
        };
        match l.receiver.kind() {
            Kind::Cluster(c) => {
                mean * sent * l.dir.opposite().read(&self.projected[c as usize])
                    / self.clusters.nodes[c as usize].area.max(f64::MIN_POSITIVE)
            }
            Kind::Surface(_) => (mean + f64::from(l.area_correction)) * sent,
        }
    }

    /// The element mesh (the leaves of the surface hierarchy).
    pub fn mesh(&self) -> &ElementMesh {
        &self.mesh
    }

    /// The scene being solved.
    pub fn scene(&self) -> &Scene {
        self.scene
    }

    /// Links now.
    pub fn link_count(&self) -> usize {
        self.links.len()
    }
}
