//! Progressive refinement (Cohen, Chen, Wallace & Greenberg 1988) with ray-traced form factors
//! at the receiving vertices (Wallace, Elmquist & Haines 1989) and adaptive element subdivision,
//! plus the specular transfer of [`crate::specular`]: each shot also traces the shooter's light
//! through mirrors and glass and deposits it where it lands.

use std::ops::ControlFlow;
use std::sync::atomic::{AtomicU8, Ordering};
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::Rgb;
use twopass_brdf::colour::luminance_f64;
use twopass_scene::{Scene, SurfacePoint};

use crate::ambient::ambient;
use crate::element::ElementMesh;
use crate::error::SolveError;
use crate::form_factor::{self, RECEIVER_INSET, hash};
use crate::options::{AdaptiveOptions, Method, Options, check_common, participating};
use crate::report::{Bookkeeping, Finish, Residuals, SolveProgress};
use crate::solution::Solution;
use crate::specular::Specular;
use crate::specular_receivers::SpecularReceivers;

/// Most patches or elements a solve meshes before adaptive subdivision (about 2 GB of mesh,
/// form-factor rows and radiosities); smaller patch or element sizes are refused up front.
pub const MAX_ELEMENTS: usize = 4_000_000;

/// Approximate bytes per element: the node, its share of vertices with their per-vertex sums
/// and receiving points, the edge map and the patch lists.
const BYTES_PER_ELEMENT: f64 = 400.0;

/// Most form factors [`ProgressiveSolver::patch_rows`] computes in one parallel pass (16 MiB of
/// rows in flight beside the cache).
const ROW_BATCH: usize = 1 << 22;

/// Most patches for which [`ProgressiveSolver`] keeps every pair's shaft test (one byte per pair:
/// 16 MiB at this many); above it, each row tests its pairs afresh.
const PAIR_CACHE_MAX_PATCHES: usize = 4096;
/// Fewest vertices of a row that must lie on a patch for [`ProgressiveSolver`] to test the shaft
/// between that patch and the shooter: a hull test costs several vertex tests (the coarse
/// preview mesh of the Cornell box has 2.3 vertices per patch and was slower with every
/// pair tested), and a pair tested once is kept.
const HULL_MIN_VERTICES: u32 = 6;
/// States of a pair of patches in [`ProgressiveSolver`]'s shaft cache.
const PAIR_UNKNOWN: u8 = 0;
const PAIR_CLEAR: u8 = 1;
const PAIR_BLOCKED: u8 = 2;

/// A progressive-refinement radiosity solve over a scene. Deterministic: the same options and
/// seed give the same solution bit for bit on any number of threads.
pub struct ProgressiveSolver<'s> {
    scene: &'s Scene,
    options: Options,
    mesh: ElementMesh,
    element_size: f32,
    /// Per vertex: reflectance, emitted exitance E = pi L_e.
    rho: Vec<DVec3>,
    emission: Vec<DVec3>,
    /// Per vertex: where it receives ([`ProgressiveSolver::receiving_point`]), and there, with its
    /// error bound on its scene triangle, where its shadow rays start; computed once instead of
    /// once per shooter.
    receiving: Vec<DVec3>,
    receivers: Vec<SurfacePoint>,
    /// Per vertex: irradiance received from emitted and from reflected light, W/m^2.
    received_emit: Vec<DVec3>,
    received_refl: Vec<DVec3>,
    /// The specular transfer and the light it brought to the vertices, when the scene needs
    /// it ([`crate::specular::decide`]).
    specular: Option<SpecularReceivers>,
    /// Per patch: unshot and shot radiosity, split by origin.
    unshot_emit: Vec<DVec3>,
    unshot_refl: Vec<DVec3>,
    shot_emit: Vec<DVec3>,
    shot_refl: Vec<DVec3>,
    /// Per patch: its unshot power, W summed over channels (`|unshot_emit + unshot_refl|`
    /// times its area): what the next shooter is chosen by and the stop is decided by, kept
    /// up to date wherever the unshot radiosity changes ([`ProgressiveSolver::note_unshot`]) rather
    /// than recomputed for every patch on every shot.
    unshot_power: Vec<f64>,
    /// Per patch: its elements (leaves), flat, with what every shot reads of them.
    elements: PatchElements,
    /// Per patch: diffuse reflectance and area (scene units squared); patches never change.
    patch_rho: Vec<DVec3>,
    patch_area: Vec<f64>,
    /// Per patch: cached form factors (with visibility) to every vertex, once computed.
    cache: Vec<Option<Vec<f32>>>,
    /// Per patch whose row is cached and that has shot on the current element mesh: its
    /// [`ProgressiveSolver::arrival_weights`], kept beside the row (a patch shoots several times) and
    /// dropped when the elements change.
    weights: Vec<Option<Vec<f64>>>,
    /// Per pair of patches `(q, p)` at `q * n + p`, with shaft culling and at most
    /// [`PAIR_CACHE_MAX_PATCHES`] patches: whether the shaft between them is clear
    /// ([`PAIR_UNKNOWN`], [`PAIR_CLEAR`], [`PAIR_BLOCKED`]); patches never change, and every
    /// refinement asks again for the new vertices. Empty otherwise.
    pair_clear: Vec<AtomicU8>,
    cached_bytes: usize,
    /// Rounds, time and power, kept as the other solver keeps them.
    bookkeeping: Bookkeeping,
    shots: u64,
    rays: u64,
}

/// Every patch's elements (leaves) in one flat list, patch by patch in the mesh's leaf order:
/// patch `p` owns entries `start[p]..start[p + 1]`. Each shot reads every element, so their
/// vertices and areas sit here side by side rather than in the mesh's nodes.
#[derive(Default)]
struct PatchElements {
    start: Vec<usize>,
    leaf: Vec<u32>,
    vertices: Vec<[u32; 3]>,
    /// Scene units squared.
    area: Vec<f64>,
    /// Per mesh vertex: a patch on the vertex's own scene triangle whose elements use it (so
    /// the vertex lies on that patch), `u32::MAX` for none. Shaft culling between patches
    /// clears a vertex through it.
    vertex_patch: Vec<u32>,
}

impl PatchElements {
    /// Groups the mesh's leaves by patch (a stable counting sort: within a patch, the order of
    /// [`ElementMesh::leaves`]).
    fn new(mesh: &ElementMesh) -> Self {
        let leaves: Vec<u32> = mesh.leaves().collect();
        let mut start = vec![0usize; mesh.patches.len() + 1];
        for &l in &leaves {
            start[mesh.nodes[l as usize].patch as usize + 1] += 1;
        }
        for p in 0..mesh.patches.len() {
            start[p + 1] += start[p];
        }
        let mut next = start.clone();
        let mut leaf = vec![0u32; leaves.len()];
        for &l in &leaves {
            let p = mesh.nodes[l as usize].patch as usize;
            leaf[next[p]] = l;
            next[p] += 1;
        }
        let vertices = leaf
            .iter()
            .map(|&l| mesh.nodes[l as usize].vertices)
            .collect();
        let area = leaf
            .iter()
            .map(|&l| f64::from(mesh.nodes[l as usize].area))
            .collect();
        let mut vertex_patch = vec![u32::MAX; mesh.vertices.len()];
        for (p, &node) in mesh.patches.iter().enumerate() {
            let triangle = mesh.nodes[node as usize].scene_triangle;
            for &l in &leaf[start[p]..start[p + 1]] {
                for v in mesh.nodes[l as usize].vertices {
                    if mesh.vertices[v as usize].triangle == triangle {
                        vertex_patch[v as usize] = p as u32;
                    }
                }
            }
        }
        Self {
            start,
            leaf,
            vertices,
            area,
            vertex_patch,
        }
    }

    /// Entries of patch `p`.
    fn range(&self, p: usize) -> std::ops::Range<usize> {
        self.start[p]..self.start[p + 1]
    }

    /// The leaves of patch `p`.
    fn leaves(&self, p: usize) -> &[u32] {
        &self.leaf[self.range(p)]
    }
}

fn rgb(v: Rgb) -> DVec3 {
    v.as_dvec3()
}

impl<'s> ProgressiveSolver<'s> {
    /// Meshes the scene into patches and elements and sets up the emitters' unshot power.
    /// Only objects that reflect diffusely or emit take part; others still cast shadows.
    pub fn new(scene: &'s Scene, options: Options) -> Result<Self, SolveError> {
        if scene.emitters.is_empty() {
            return Err(SolveError::NoEmitters);
        }
        let diag = scene.bounds.diagonal();
        let patch_size = options.patch_size.unwrap_or(diag / 8.0);
        let element_size = options.element_size.unwrap_or(diag / 24.0).min(patch_size);
        for (name, v) in [("patch_size", patch_size), ("element_size", element_size)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(SolveError::Option {
                    name,
                    problem: format!("{v} must be finite and > 0 scene units"),
                });
            }
        }
        check_common(&options)?;
        let takes_part = participating(scene);
        if !takes_part.iter().any(|&t| t) {
            return Err(SolveError::NothingTakesPart);
        }
        // Refinement to a size makes, per triangle, at least one element per sqrt(3)/4 size^2
        // of area (the largest triangle whose longest edge is `size`), at least one per `size`
        // along its longest edge (a sliver is cut across), and at least one: refuse up front
        // what cannot fit rather than refine until memory runs out.
        let part: Vec<(f64, f64)> = (0..scene.mesh.triangles.len() as u32)
            .filter(|&t| takes_part[scene.mesh.triangle_object[t as usize] as usize])
            .map(|t| {
                let [a, b, c] = scene.mesh.corners(t);
                let longest = (b - a).length().max((c - b).length()).max((a - c).length());
                (f64::from(scene.mesh.areas[t as usize]), f64::from(longest))
            })
            .collect();
        let part_area: f64 = part.iter().map(|p| p.0).sum();
        for (name, v) in [("patch_size", patch_size), ("element_size", element_size)] {
            let s = f64::from(v);
            let at_least: f64 = part
                .iter()
                .map(|&(area, longest)| {
                    (area / (3f64.sqrt() / 4.0 * s * s))
                        .max((longest / s).ceil())
                        .max(1.0)
                })
                .sum();
            if at_least > MAX_ELEMENTS as f64 {
                return Err(SolveError::Option {
                    name,
                    problem: format!(
                        "{v} scene units would make at least {at_least:.3e} elements on {} \
                         triangles ({part_area:.3e} units^2), more than the {MAX_ELEMENTS} a \
                         solve holds; give a larger size",
                        part.len()
                    ),
                });
            }
        }
        // Bisection leaves of longest edge at most L have an area of L^2 / 8 or more: refuse
        // up front a mesh that would not fit instead of refining until the allocator gives up.
        let elements: f64 = scene
            .mesh
            .triangle_object
            .iter()
            .zip(&scene.mesh.areas)
            .filter(|&(&o, _)| takes_part[o as usize])
            .map(|(_, &a)| (8.0 * f64::from(a) / f64::from(element_size).powi(2)).max(1.0))
            .sum();
        let patches: f64 = scene
            .mesh
            .areas
            .iter()
            .map(|&a| (8.0 * f64::from(a) / f64::from(patch_size).powi(2)).max(1.0))
            .sum();
        let bytes = elements * BYTES_PER_ELEMENT
            + (patches * elements * 2.0).min(options.cache_bytes as f64);
        if bytes > options.memory_limit as f64 {
            return Err(SolveError::TooLarge {
                what: format!("about {elements:.3e} elements of {element_size} scene units"),
                bytes: bytes.min(u64::MAX as f64) as u64,
                limit: options.memory_limit,
            });
        }
        let specular = options
            .specular
            .and_then(|settings| Specular::new(scene, settings, &takes_part))
            .map(SpecularReceivers::new);
        let started = Instant::now();
        let mut mesh = ElementMesh::new(scene, &takes_part);
        mesh.refine_to(patch_size);
        mesh.mark_patches();
        mesh.refine_to(element_size);
        let mut s = Self {
            scene,
            options,
            mesh,
            element_size,
            rho: Vec::new(),
            emission: Vec::new(),
            receiving: Vec::new(),
            receivers: Vec::new(),
            received_emit: Vec::new(),
            received_refl: Vec::new(),
            specular,
            unshot_emit: Vec::new(),
            unshot_refl: Vec::new(),
            shot_emit: Vec::new(),
            shot_refl: Vec::new(),
            unshot_power: Vec::new(),
            elements: PatchElements::default(),
            patch_rho: Vec::new(),
            patch_area: Vec::new(),
            cache: Vec::new(),
            weights: Vec::new(),
            pair_clear: Vec::new(),
            cached_bytes: 0,
            bookkeeping: Bookkeeping::new(started, started.elapsed()),
            shots: 0,
            rays: 0,
        };
        s.sync_vertices();
        let n = s.mesh.patches.len();
        s.patch_area = (0..n)
            .map(|p| f64::from(s.mesh.nodes[s.mesh.patches[p] as usize].area))
            .collect();
        s.patch_rho = (0..n)
            .map(|p| {
                let o = &scene.objects[s.object_of_patch(p) as usize];
                rgb(scene.materials[o.material as usize]
                    .material
                    .diffuse_albedo())
            })
            .collect();
        s.unshot_refl = vec![DVec3::ZERO; n];
        s.shot_emit = vec![DVec3::ZERO; n];
        s.shot_refl = vec![DVec3::ZERO; n];
        s.cache = vec![None; n];
        s.weights = vec![None; n];
        if s.options.shaft_culling && s.options.occlusion && n <= PAIR_CACHE_MAX_PATCHES {
            s.pair_clear = (0..n * n).map(|_| AtomicU8::new(PAIR_UNKNOWN)).collect();
        }
        s.unshot_emit = (0..n).map(|p| s.patch_emission(p)).collect();
        s.bookkeeping.energy.emitted = (0..n).map(|p| s.unshot_emit[p] * s.patch_area(p)).sum();
        s.bookkeeping.energy.unshot = s.bookkeeping.energy.emitted;
        s.unshot_power = vec![0.0; n];
        for p in 0..n {
            s.note_unshot(p);
        }
        s.rebuild_patch_elements();
        s.resplat();
        Ok(s)
    }

    /// With the specular transfer: every deposit so far splatted afresh onto the current mesh
    /// ([`SpecularReceivers::resplat`]).
    fn resplat(&mut self) {
        if let Some(spec) = &mut self.specular {
            spec.resplat(&self.mesh);
        }
    }

    /// Irradiance received at vertex `v` from every path, W/m^2.
    fn received(&self, v: usize) -> DVec3 {
        let r = self.received_emit[v] + self.received_refl[v];
        match &self.specular {
            Some(spec) => r + spec.received[v],
            None => r,
        }
    }

    /// Irradiance at vertex `v` from light reflected at least once or carried through specular
    /// surfaces (what shadow rays to the emitters do not find), W/m^2.
    fn received_indirect(&self, v: usize) -> DVec3 {
        match &self.specular {
            Some(spec) => self.received_refl[v] + spec.received[v],
            None => self.received_refl[v],
        }
    }

    /// The specular transfer of the shot of patch `p`: each of its elements sends what its
    /// exitance changed by since it last sent ([`Specular::shoot_changes`]: from where the light
    /// leaves it, not as the uniform patch), what lands is splatted onto the vertices and
    /// handed to the receiving patches as unshot reflected radiosity, as the form factors'
    /// transfer does. Returns the power that arrived (W per channel).
    fn shoot_specular(&mut self, p: usize) -> DVec3 {
        let Some(spec) = &self.specular else {
            return DVec3::ZERO;
        };
        let mean = |node: &crate::element::Node, f: &dyn Fn(usize) -> DVec3| {
            node.vertices.iter().map(|&v| f(v as usize)).sum::<DVec3>() / 3.0
        };
        let changes: Vec<(u32, [DVec3; 2])> = self
            .elements
            .leaves(p)
            .iter()
            .map(|&leaf| {
                let node = &self.mesh.nodes[leaf as usize];
                let e = mean(node, &|v| self.emission[v]);
                let r = mean(node, &|v| self.rho[v] * self.received(v));
                let sent = spec.sent(&self.mesh, leaf);
                (leaf, [e - sent[0], r - sent[1]])
            })
            .collect();
        let key = hash(self.options.seed ^ hash(0x5bec_0000_0000_0000 ^ self.shots) ^ p as u64);
        let emitted = luminance_f64(self.bookkeeping.energy.emitted);
        let Some((mut deposits, rays)) = spec
            .transfer
            .shoot_changes(self.scene, &self.mesh, &changes, emitted, 0.0, key)
        else {
            return DVec3::ZERO;
        };
        let spec = self.specular.as_mut().expect("the transfer shot");
        spec.note_sent(&self.mesh, &changes);
        self.rays += rays;
        if deposits.is_empty() {
            spec.keep(deposits, rays);
            return DVec3::ZERO;
        }
        // Only the leaves around the vertices that received anything gain power: an element
        // receives its area times the mean of its vertices' irradiance.
        let delta = spec.splat(&self.mesh, Some(&mut deposits));
        let mut gains: Vec<(u32, DVec3)> = Vec::new();
        for &(v, e) in &delta {
            for &leaf in &spec.vertex_areas.leaves[v as usize] {
                let node = &self.mesh.nodes[leaf as usize];
                gains.push((node.patch, e * (f64::from(node.area) / 3.0)));
            }
        }
        gains.sort_by_key(|g| g.0);
        gains.dedup_by(|later, first| {
            if later.0 == first.0 {
                first.1 += later.1;
                true
            } else {
                false
            }
        });
        spec.keep(deposits, rays);
        let mut arrived = DVec3::ZERO;
        for (q, gained) in gains {
            arrived += gained;
            self.receive(q as usize, gained);
        }
        arrived
    }

    /// With the specular transfer: rays it cast and deposits it made so far; `None` when the
    /// scene does not need it ([`crate::specular::decide`]) or the options turned it off.
    pub fn specular_transfer(&self) -> Option<(u64, usize)> {
        self.specular.as_ref().map(SpecularReceivers::counts)
    }

    fn object_of_patch(&self, p: usize) -> u32 {
        let node = &self.mesh.nodes[self.mesh.patches[p] as usize];
        self.scene.mesh.triangle_object[node.scene_triangle as usize]
    }

    fn patch_emission(&self, p: usize) -> DVec3 {
        rgb(self.scene.objects[self.object_of_patch(p) as usize].emission) * std::f64::consts::PI
    }

    /// Patch `q` receives `gained` (W per channel): it absorbs `1 - rho` of it and keeps the
    /// rest as unshot exitance.
    fn receive(&mut self, q: usize, gained: DVec3) {
        let rho = self.patch_rho(q);
        self.bookkeeping.energy.absorbed += gained * (DVec3::ONE - rho);
        let a = self.patch_area(q);
        self.unshot_refl[q] += gained * rho / a;
        self.note_unshot(q);
        self.bookkeeping.energy.unshot += gained * rho;
    }

    /// Brings patch `p`'s entry of `unshot_power` up to date with its unshot radiosity.
    fn note_unshot(&mut self, p: usize) {
        self.unshot_power[p] = (self.unshot_emit[p] + self.unshot_refl[p])
            .abs()
            .element_sum()
            * self.patch_area(p);
    }

    fn patch_rho(&self, p: usize) -> DVec3 {
        self.patch_rho[p]
    }

    fn patch_area(&self, p: usize) -> f64 {
        self.patch_area[p]
    }

    /// Extends the per-vertex arrays to new vertices (reflectance, emission; zero received).
    fn sync_vertices(&mut self) {
        for v in self.rho.len()..self.mesh.vertices.len() {
            let o = &self.scene.objects[self.mesh.vertices[v].object as usize];
            self.rho.push(rgb(self.scene.materials[o.material as usize]
                .material
                .diffuse_albedo()));
            self.emission.push(rgb(o.emission) * std::f64::consts::PI);
            let x = self.receiving_point(v);
            self.receiving.push(x);
            self.receivers.push(
                self.scene
                    .mesh
                    .surface_point_at(self.mesh.vertices[v].triangle, x.as_vec3()),
            );
            self.received_emit.push(DVec3::ZERO);
            self.received_refl.push(DVec3::ZERO);
        }
    }

    /// Where vertex `v` receives, form factors and shadow rays alike: a hair inside its own
    /// scene triangle ([`RECEIVER_INSET`] of the way to its centroid). A vertex on a junction
    /// lies in the plane of the surface it meets, which it would see edge-on (F = 0), and half
    /// of its shadow rays would start a rounding error behind that surface and find it
    /// blocking; from inside its own surface it gets the limits both converge to.
    fn receiving_point(&self, v: usize) -> DVec3 {
        let vert = &self.mesh.vertices[v];
        let centroid = self
            .scene
            .mesh
            .corners(vert.triangle)
            .iter()
            .map(|c| c.as_dvec3())
            .sum::<DVec3>()
            / 3.0;
        vert.position.as_dvec3() + (centroid - vert.position.as_dvec3()) * RECEIVER_INSET
    }

    fn rebuild_patch_elements(&mut self) {
        self.elements = PatchElements::new(&self.mesh);
        for w in &mut self.weights {
            if let Some(w) = w.take() {
                self.cached_bytes -= std::mem::size_of_val(w.as_slice());
            }
        }
    }

    /// Per patch `q`, what it receives of a shot with form factors `row` (per vertex, to the
    /// shooter), per unit of the shooter's unshot exitance: the sum over its elements of area
    /// times the mean of the element's vertices' form factors (elements with a positive mean
    /// only), scene units squared. Patch `q` gains `exitance * weights[q]` W per channel.
    fn arrival_weights(&self, row: &[f32]) -> Vec<f64> {
        (0..self.mesh.patches.len())
            .map(|q| {
                let mut weight = 0.0;
                for (h, area) in self.element_means(q, |v| f64::from(row[v])) {
                    if h > 0.0 {
                        weight += h * area;
                    }
                }
                weight
            })
            .collect()
    }

    /// Form factors (with visibility) from every vertex in `vertices` to patch `p`, and the
    /// shadow rays cast. Parallel over vertices; each value depends only on (seed, vertex,
    /// patch), never on scheduling.
    fn form_factors(&self, p: usize, vertices: &[usize]) -> (Vec<f32>, u64) {
        let node = self.mesh.nodes[self.mesh.patches[p] as usize];
        let shooter = form_factor::Shooter::new(
            self.scene,
            self.mesh.corners(self.mesh.patches[p]),
            node.scene_triangle,
        );
        let ns = self.scene.mesh.geometric_normals[shooter.triangle as usize].as_dvec3();
        let hulls = self.patch_hulls(p, vertices);
        // A vertex's own shaft test costs about what one shadow ray does, and where its
        // patch's hull was tested and found blocked it rarely clears more: it pays only for
        // vertices whose hull was not tested (too few of them on their patch) and when it can
        // spare several rays. On the final Cornell box mesh testing every vertex made the
        // solve 1.09x slower at 4-16 rays a pair and 1.24x at one ray (`twopass bake
        // --visibility-rays`); on coarse meshes, without hulls, it saves 4-6 %.
        let vertex_shafts = self.options.shaft_culling && self.options.visibility.coarse() > 1;
        const CHUNK: usize = 64;
        let mut row = vec![0.0f32; vertices.len()];
        let mut rays = vec![0u64; vertices.len().div_ceil(CHUNK)];
        row.par_chunks_mut(CHUNK)
            .zip(rays.par_iter_mut())
            .zip(vertices.par_chunks(CHUNK))
            .for_each(|((row, rays), chunk)| {
                // The unoccluded form factors four vertices at a time.
                let mut x = [DVec3::ZERO; CHUNK];
                let mut n = [DVec3::ZERO; CHUNK];
                for (i, &v) in chunk.iter().enumerate() {
                    x[i] = self.receiving[v];
                    n[i] = self.mesh.vertices[v].normal.as_dvec3();
                }
                let mut unoccluded = [0.0; CHUNK];
                let count = chunk.len();
                shooter.source.form_factors_into(
                    &x[..count],
                    &n[..count],
                    Some(ns),
                    &mut unoccluded[..count],
                );
                for ((out, &v), &f) in row.iter_mut().zip(chunk).zip(&unoccluded) {
                    *out = f as f32;
                    if f <= 0.0 || !self.options.occlusion {
                        continue;
                    }
                    let from = &self.receivers[v];
                    let hull = self
                        .elements
                        .vertex_patch
                        .get(v)
                        .and_then(|&q| hulls.get(q as usize).copied())
                        .unwrap_or(PAIR_UNKNOWN);
                    if hull == PAIR_CLEAR
                        || hull == PAIR_UNKNOWN
                            && vertex_shafts
                            && form_factor::shaft_clear(self.scene, from, shooter.source.corners)
                    {
                        continue;
                    }
                    let seed = hash(self.options.seed ^ hash((v as u64) << 32 | p as u64));
                    let (vis, cast) = form_factor::visibility(
                        self.scene,
                        from,
                        self.mesh.vertices[v].normal,
                        &shooter,
                        self.options.visibility,
                        seed,
                    );
                    *out = (f * vis) as f32;
                    *rays += cast;
                }
            });
        (row, rays.iter().sum())
    }

    /// With shaft culling: per patch, whether nothing can come between it and shooter patch
    /// `p` ([`form_factor::patches_clear`]): [`PAIR_CLEAR`] or [`PAIR_BLOCKED`] for the
    /// patches at least [`HULL_MIN_VERTICES`] of `vertices` lie on, [`PAIR_UNKNOWN`] (not
    /// tested) for the others; empty without shaft culling. A vertex on a clear patch needs
    /// neither its own shaft test nor shadow rays: its segments to `p` lie in the hull.
    fn patch_hulls(&self, p: usize, vertices: &[usize]) -> Vec<u8> {
        if !(self.options.shaft_culling && self.options.occlusion) {
            return Vec::new();
        }
        let n = self.mesh.patches.len();
        let mut on = vec![0u32; n];
        for &v in vertices {
            if let Some(&q) = self.elements.vertex_patch.get(v)
                && (q as usize) < n
                && q as usize != p
            {
                on[q as usize] += 1;
            }
        }
        // Only the row's own vertices decide which pairs are tested, never what other rows
        // (computed in parallel) have put in the cache: a vertex must take the same path,
        // hull or its own test, on any thread count.
        let wanted: Vec<bool> = on.iter().map(|&c| c >= HULL_MIN_VERTICES).collect();
        let patch = |q: usize| {
            let node = self.mesh.patches[q];
            let tri = self.mesh.nodes[node as usize].scene_triangle;
            (
                self.mesh.corners(node),
                self.scene.mesh.geometric_normals[tri as usize],
            )
        };
        let shooter = patch(p);
        let cached = !self.pair_clear.is_empty();
        wanted
            .par_iter()
            .enumerate()
            .with_min_len(16)
            .map(|(q, &w)| {
                if !w {
                    return PAIR_UNKNOWN;
                }
                if cached {
                    match self.pair_clear[q * n + p].load(Ordering::Relaxed) {
                        PAIR_UNKNOWN => {}
                        state => return state,
                    }
                }
                // The lower index first, whichever row asks: the rounding then never
                // depends on which of the two rows (computed in parallel) asks first.
                let clear = if q < p {
                    form_factor::patches_clear(self.scene, patch(q), shooter)
                } else {
                    form_factor::patches_clear(self.scene, shooter, patch(q))
                };
                let state = if clear { PAIR_CLEAR } else { PAIR_BLOCKED };
                if cached {
                    self.pair_clear[q * n + p].store(state, Ordering::Relaxed);
                    self.pair_clear[p * n + q].store(state, Ordering::Relaxed);
                }
                state
            })
            .collect()
    }

    /// Each element (leaf) of patch `p`: the mean of the per-vertex `value` over its three
    /// vertices, and its area (scene units squared).
    fn element_means<'a, T>(
        &'a self,
        p: usize,
        value: impl Fn(usize) -> T + 'a,
    ) -> impl Iterator<Item = (T, f64)> + 'a
    where
        T: std::iter::Sum + std::ops::Div<f64, Output = T>,
    {
        self.elements.range(p).map(move |i| {
            let sum: T = self.elements.vertices[i]
                .iter()
                .map(|&v| value(v as usize))
                .sum();
            (sum / 3.0, self.elements.area[i])
        })
    }

    /// The form factors of every vertex to patch `p`: the cached row, extended to the
    /// vertices it lacks.
    fn patch_row(&mut self, p: usize) -> Vec<f32> {
        let n = self.mesh.vertices.len();
        let have = self.cached_len(p);
        if have == n {
            return self.cache[p].clone().expect("cached row");
        }
        let fresh = self.form_factors(p, &(have..n).collect::<Vec<_>>());
        self.extend_row(p, fresh)
    }

    /// How many vertices the cached row of patch `p` covers (from vertex 0).
    fn cached_len(&self, p: usize) -> usize {
        self.cache[p].as_ref().map_or(0, Vec::len)
    }

    /// The rows of `patches` (as [`ProgressiveSolver::patch_row`] gives them, in that order), with
    /// what they lack computed in parallel over patches and vertices at once: after a
    /// refinement every patch shot so far lacks the new vertices, and one small parallel
    /// pass per patch would cost more in starting and joining than in form factors. Rows go
    /// to `each` one by one, computed in batches of at most [`ROW_BATCH`] values.
    fn patch_rows(&mut self, patches: &[usize], mut each: impl FnMut(&mut Self, usize, &[f32])) {
        let n = self.mesh.vertices.len();
        let mut rest = patches;
        while !rest.is_empty() {
            let (mut take, mut values) = (0, 0);
            while take < rest.len() && (take == 0 || values + n <= ROW_BATCH) {
                values += n - self.cached_len(rest[take]);
                take += 1;
            }
            let (batch, tail) = rest.split_at(take);
            rest = tail;
            let fresh: Vec<(Vec<f32>, u64)> = batch
                .par_iter()
                .map(|&p| self.form_factors(p, &(self.cached_len(p)..n).collect::<Vec<_>>()))
                .collect();
            for (&p, fresh) in batch.iter().zip(fresh) {
                let row = self.extend_row(p, fresh);
                each(self, p, &row);
            }
        }
    }

    /// Appends `fresh` (the form factors of the vertices after the cached ones, and the rays
    /// they cast) to the row of patch `p`, caches the row while the cache has room, and
    /// returns it.
    fn extend_row(&mut self, p: usize, (fresh, rays): (Vec<f32>, u64)) -> Vec<f32> {
        self.rays += rays;
        let have = self.cached_len(p);
        let mut row = self.cache[p].take().unwrap_or_default();
        row.extend_from_slice(&fresh);
        let bytes = fresh.len() * 4;
        if self.cached_bytes + bytes <= self.options.cache_bytes {
            self.cached_bytes += bytes;
            self.cache[p] = Some(row.clone());
        } else if have > 0 {
            self.cached_bytes -= have * 4;
        }
        row
    }

    /// Shoots the patch with the most unshot power. Returns `false` when none has any.
    pub fn shoot(&mut self) -> bool {
        let Some((p, power)) = self
            .unshot_power
            .iter()
            .copied()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
        else {
            return false;
        };
        if power <= 0.0 {
            return false;
        }
        let (de, dr) = (self.unshot_emit[p], self.unshot_refl[p]);
        let row = self.patch_row(p);
        let area = self.patch_area(p);
        for (v, &f) in row.iter().enumerate() {
            if f > 0.0 {
                self.received_emit[v] += de * f64::from(f);
                self.received_refl[v] += dr * f64::from(f);
            }
        }
        // Power arriving at each patch: its elements' areas times the mean irradiance of their
        // vertices, from the weights kept beside the row (computed on the first shot).
        let weights = match self.weights[p].take() {
            Some(w) => {
                self.cached_bytes -= std::mem::size_of_val(w.as_slice());
                w
            }
            None => self.arrival_weights(&row),
        };
        let sent = de + dr;
        let mut arrived = DVec3::ZERO;
        for (q, &weight) in weights.iter().enumerate() {
            let gained = sent * weight;
            if weight > 0.0 && gained != DVec3::ZERO {
                arrived += gained;
                self.receive(q, gained);
            }
        }
        let bytes = std::mem::size_of_val(weights.as_slice());
        if self.cache[p].is_some() && self.cached_bytes + bytes <= self.options.cache_bytes {
            self.cached_bytes += bytes;
            self.weights[p] = Some(weights);
        }
        if self.specular.is_some() {
            arrived += self.shoot_specular(p);
        }
        let shot = (de + dr) * area;
        self.bookkeeping.energy.escaped += shot - arrived;
        self.bookkeeping.energy.unshot -= shot;
        self.shot_emit[p] += de;
        self.shot_refl[p] += dr;
        self.unshot_emit[p] -= de;
        self.unshot_refl[p] -= dr;
        self.note_unshot(p);
        self.shots += 1;
        self.bookkeeping.note_imbalance();
        true
    }

    /// Unshot power over emitted power (sums over channels).
    pub fn unshot_fraction(&self) -> f64 {
        let unshot: f64 = self.unshot_power.iter().sum();
        unshot
            / self
                .bookkeeping
                .energy
                .emitted
                .element_sum()
                .max(f64::MIN_POSITIVE)
    }

    /// Where the solve stands.
    pub fn progress(&self) -> SolveProgress {
        SolveProgress {
            shots: self.shots,
            unshot_fraction: self.unshot_fraction(),
            rays: self.rays,
            elements: self.elements.leaf.len(),
            vertices: self.mesh.vertices.len(),
            patches: self.mesh.patches.len(),
            ..self.bookkeeping.progress(Method::Progressive)
        }
    }

    /// Displayed radiosity of vertex `v` without the ambient term, W/m^2.
    fn radiosity(&self, v: usize) -> DVec3 {
        self.emission[v] + self.rho[v] * self.received(v)
    }

    /// One round of adaptive subdivision: splits (conformingly) every element whose vertices'
    /// luminances differ by more than the threshold, gathers the new vertices' radiosity from
    /// everything shot so far, and re-estimates the patches' unshot radiosity on the finer
    /// mesh. Returns how many elements were split.
    pub fn refine(&mut self, adaptive: &AdaptiveOptions) -> usize {
        let started = Instant::now();
        let splits = self.refine_round(adaptive);
        self.bookkeeping.refining += started.elapsed();
        splits
    }

    fn refine_round(&mut self, adaptive: &AdaptiveOptions) -> usize {
        let lum = luminance_f64;
        let (mut total, mut area) = (0.0, 0.0);
        let leaves: Vec<u32> = self.mesh.leaves().collect();
        for &l in &leaves {
            let node = &self.mesh.nodes[l as usize];
            let y: f64 = node
                .vertices
                .iter()
                .map(|&v| lum(self.radiosity(v as usize)))
                .sum::<f64>()
                / 3.0;
            total += y * f64::from(node.area);
            area += f64::from(node.area);
        }
        let mean = total / area.max(f64::MIN_POSITIVE);
        let min_size = adaptive.min_element_size.unwrap_or(self.element_size / 8.0);
        let split: Vec<u32> = leaves
            .into_iter()
            .filter(|&l| {
                let ys = self.mesh.nodes[l as usize]
                    .vertices
                    .map(|v| lum(self.radiosity(v as usize)));
                let spread = ys.iter().copied().fold(f64::MIN, f64::max)
                    - ys.iter().copied().fold(f64::MAX, f64::min);
                spread > f64::from(adaptive.threshold) * mean
                    && self.mesh.longest_edge_length(l) > 2.0 * min_size
            })
            .collect();
        let mut splits = 0;
        for l in split {
            splits += self.mesh.refine(l);
        }
        if splits == 0 {
            return 0;
        }
        let old = self.rho.len();
        self.sync_vertices();
        // New vertices gather everything shot so far.
        let shot: Vec<usize> = (0..self.mesh.patches.len())
            .filter(|&p| self.shot_emit[p] != DVec3::ZERO || self.shot_refl[p] != DVec3::ZERO)
            .collect();
        self.patch_rows(&shot, |s, p, row| {
            let (se, sr) = (s.shot_emit[p], s.shot_refl[p]);
            for (v, &f) in row.iter().enumerate().skip(old) {
                s.received_emit[v] += se * f64::from(f);
                s.received_refl[v] += sr * f64::from(f);
            }
        });
        self.rebuild_patch_elements();
        self.resplat();
        // Re-estimate each patch's reflected radiosity from its (finer) elements.
        for p in 0..self.mesh.patches.len() {
            let mut reflected = DVec3::ZERO;
            for (r, area) in self.element_means(p, |v| self.rho[v] * self.received(v)) {
                reflected += r * area;
            }
            let reflected = reflected / self.patch_area(p);
            let new_unshot = reflected - self.shot_refl[p];
            let change = (new_unshot - self.unshot_refl[p]) * self.patch_area(p);
            self.bookkeeping.energy.unshot += change;
            self.bookkeeping.energy.remeshing -= change;
            self.unshot_refl[p] = new_unshot;
            self.note_unshot(p);
        }
        self.bookkeeping.rounds += 1;
        splits
    }

    /// Runs the whole schedule: shooting, adaptive rounds (if enabled), shooting to the stop
    /// criteria. `observer` sees the solver after every shot: it can read
    /// [`ProgressiveSolver::progress`], take an intermediate [`ProgressiveSolver::solution`] (with the
    /// ambient term) or stop the solve early by returning `Break`; the solution is usable
    /// whenever this returns.
    pub fn run(&mut self, mut observer: impl FnMut(&Self) -> ControlFlow<()>) -> Finish {
        let stop = self.options.stop;
        let adaptive = self.options.adaptive;
        let mut rounds_left = adaptive.map_or(0, |a| a.rounds);
        loop {
            let target = match adaptive {
                Some(a) if rounds_left > 0 => a.at_unshot_fraction.max(stop.unshot_fraction),
                _ => stop.unshot_fraction,
            };
            // An adaptive round computes the new vertices' rows to every patch, which can take
            // as long as the shots so far: none is started past half the time budget.
            if stop
                .time_budget
                .is_some_and(|b| self.bookkeeping.started.elapsed() * 2 >= b)
            {
                rounds_left = 0;
            }
            if self.unshot_fraction() <= target {
                if let (Some(a), true) = (adaptive, rounds_left > 0) {
                    rounds_left -= 1;
                    if self.refine(&a) == 0 {
                        rounds_left = 0;
                    }
                    continue;
                }
                return Finish::Converged;
            }
            if stop.max_shots.is_some_and(|m| self.shots >= m) {
                return Finish::MaxShots;
            }
            if stop
                .time_budget
                .is_some_and(|b| self.bookkeeping.started.elapsed() >= b)
            {
                return Finish::TimeBudget;
            }
            if !self.shoot() {
                return Finish::Exhausted;
            }
            if observer(self).is_break() {
                return Finish::Cancelled;
            }
        }
    }

    /// The ambient term (Cohen et al. 1988): the unshot radiosity spread over the scene and
    /// multiplied by the interreflection factor 1 / (1 - mean reflectance), W/m^2.
    pub fn ambient(&self) -> DVec3 {
        let (mut unshot, mut rho, mut area) = (DVec3::ZERO, DVec3::ZERO, 0.0);
        for p in 0..self.mesh.patches.len() {
            let a = self.patch_area(p);
            unshot += (self.unshot_emit[p] + self.unshot_refl[p]) * a;
            rho += self.patch_rho(p) * a;
            area += a;
        }
        ambient(unshot, rho, area)
    }

    /// The current solution, with the ambient term for display of a partial solve.
    pub fn solution(&self) -> Solution {
        let ambient = self.ambient();
        let n = self.mesh.vertices.len();
        let solution = Solution::new(
            self.mesh.clone(),
            (0..n).map(|v| self.radiosity(v).as_vec3()).collect(),
            (0..n)
                .map(|v| (self.rho[v] * self.received_emit[v]).as_vec3())
                .collect(),
            (0..n)
                .map(|v| (self.rho[v] * self.received_indirect(v)).as_vec3())
                .collect(),
            (0..n).map(|v| (self.rho[v] * ambient).as_vec3()).collect(),
        );
        if let Some(spec) = &self.specular {
            solution.with_focused_caustics(
                (0..n)
                    .map(|v| (self.rho[v] * spec.focused[v]).as_vec3())
                    .collect(),
            )
        } else {
            solution
        }
    }

    /// Checks of the solve's consistency: the energy balance, the form-factor row sums of up
    /// to `samples` vertices (1 in a closed scene, less where light escapes) and the
    /// reciprocity A_p F_pq = A_q F_qp on up to `samples` pairs of patches, with the patch-to-
    /// patch form factors integrated from the vertex ones. Pairs are picked deterministically.
    pub fn residuals(&mut self, samples: usize) -> Residuals {
        let weights = self.patch_weights();
        let areas = self.patch_areas();
        let n_v = self.mesh.vertices.len();
        let n_p = self.mesh.patches.len();
        // A row sum costs one form factor per patch: take no more rows than a tenth of the
        // rays the solve cast pays for, so the report never rivals the solve.
        let per_row = (n_p as u64 * u64::from(self.options.visibility.min)).max(1);
        let rows = (samples as u64).min((self.rays / 10 / per_row).max(1)) as usize;
        let step = (n_v / rows.max(1)).max(1);
        let picked: Vec<usize> = (0..n_v).step_by(step).take(rows).collect();
        let mut sums = vec![0.0f64; picked.len()];
        for q in 0..n_p {
            for (s, f) in sums.iter_mut().zip(self.form_factors_at(q, &picked)) {
                *s += f64::from(f);
            }
        }
        // F_pq from the vertex form factors of p's vertices to q, area-weighted.
        let patch_ff = |s: &mut Self, p: usize, q: usize| {
            let vs: Vec<usize> = weights[p].iter().map(|&(v, _)| v as usize).collect();
            let f = s.form_factors_at(q, &vs);
            weights[p]
                .iter()
                .zip(f)
                .map(|(&(_, w), f)| w * f64::from(f))
                .sum::<f64>()
        };
        let mut pairs = Vec::new();
        for k in 0..samples as u64 {
            let (p, q) = (
                (hash(k) % n_p as u64) as usize,
                (hash(k ^ 0xABCD) % n_p as u64) as usize,
            );
            if p == q {
                continue;
            }
            pairs.push((
                areas[p] * patch_ff(self, p, q),
                areas[q] * patch_ff(self, q, p),
            ));
        }
        Residuals::from_samples(self.bookkeeping.worst_imbalance, &sums, pairs)
    }

    /// Form factors of the given vertices to patch `p`: from the cache where the row is
    /// cached, computed (and counted in the rays) where not.
    fn form_factors_at(&mut self, p: usize, vertices: &[usize]) -> Vec<f32> {
        if let Some(row) = &self.cache[p]
            && vertices.iter().all(|&v| v < row.len())
        {
            return vertices.iter().map(|&v| row[v]).collect();
        }
        let (f, rays) = self.form_factors(p, vertices);
        self.rays += rays;
        f
    }

    /// The element mesh.
    pub fn mesh(&self) -> &ElementMesh {
        &self.mesh
    }

    /// The scene being solved.
    pub fn scene(&self) -> &Scene {
        self.scene
    }

    /// Every vertex-to-patch form factor (with visibility), as the shots use them: row per
    /// patch. Computes what is not cached.
    pub fn form_factor_rows(&mut self) -> Vec<Vec<f32>> {
        (0..self.mesh.patches.len())
            .map(|p| self.patch_row(p))
            .collect()
    }

    /// Per patch: (vertex, weight) pairs with patch radiosity = sum of weight x vertex
    /// radiosity (area-weighted mean over the patch's elements).
    pub fn patch_weights(&self) -> Vec<Vec<(u32, f64)>> {
        (0..self.mesh.patches.len())
            .map(|p| {
                let mut w: Vec<(u32, f64)> = Vec::new();
                let a = self.patch_area(p);
                for &leaf in self.elements.leaves(p) {
                    let node = &self.mesh.nodes[leaf as usize];
                    for &v in &node.vertices {
                        let x = f64::from(node.area) / (3.0 * a);
                        match w.iter_mut().find(|e| e.0 == v) {
                            Some(e) => e.1 += x,
                            None => w.push((v, x)),
                        }
                    }
                }
                w
            })
            .collect()
    }

    /// Per vertex: reflectance and emitted exitance.
    pub fn vertex_terms(&self) -> (&[DVec3], &[DVec3]) {
        (&self.rho, &self.emission)
    }

    /// Displayed radiosity of every vertex without the ambient term, W/m^2.
    pub fn vertex_radiosity(&self) -> Vec<DVec3> {
        (0..self.mesh.vertices.len())
            .map(|v| self.radiosity(v))
            .collect()
    }

    /// Per patch: area, scene units squared.
    pub fn patch_areas(&self) -> Vec<f64> {
        (0..self.mesh.patches.len())
            .map(|p| self.patch_area(p))
            .collect()
    }
}
