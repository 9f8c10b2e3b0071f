//! Setting up a progressive solve: the checks and memory estimates, the patch and element
//! mesh, the per-vertex and per-patch arrays, and keeping them in step with the mesh.

use std::sync::atomic::AtomicU8;
use std::time::Instant;

use glam::DVec3;
use twopass_brdf::colour::luminance_f64;
use twopass_brdf::random::hash;
use twopass_scene::Scene;

use super::patch_elements::PatchElements;
use super::state::{
    BYTES_PER_ELEMENT, MAX_ELEMENTS, MAX_SWEEP_FORM_FACTORS, PAIR_CACHE_MAX_PATCHES, PAIR_UNKNOWN,
    ProgressiveSolver,
};
use crate::element::ElementMesh;
use crate::error::SolveError;
use crate::form_factor::receiving_point;
use crate::lamps::{lamp_power, vertex_lamp_irradiance};
use crate::options::{Options, check_common, participating};
use crate::report::Bookkeeping;
use crate::specular::Specular;
use crate::specular_receivers::SpecularReceivers;

impl<'s> ProgressiveSolver<'s> {
    /// Meshes the scene into patches and elements and sets up the emitters' unshot power.
    /// Only objects that reflect diffusely or emit take part; others still cast shadows.
    pub fn new(scene: &'s Scene, options: Options) -> Result<Self, SolveError> {
        if !scene.has_light() {
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
        let part: Vec<(f64, f64)> = (0..scene.mesh.triangle_count() as u32)
            .filter(|&t| takes_part[scene.mesh.object_of(t) as usize])
            .map(|t| {
                let [a, b, c] = scene.mesh.corners(t);
                let longest = (b - a).length().max((c - b).length()).max((a - c).length());
                (f64::from(scene.mesh.area(t)), f64::from(longest))
            })
            .collect();
        let part_area: f64 = part.iter().map(|p| p.0).sum();
        let mut fewest = [0.0; 2];
        for (i, (name, v)) in [("patch_size", patch_size), ("element_size", element_size)]
            .into_iter()
            .enumerate()
        {
            let s = f64::from(v);
            let at_least: f64 = part
                .iter()
                .map(|&(area, longest)| {
                    (area / (3f64.sqrt() / 4.0 * s * s))
                        .max((longest / s).ceil())
                        .max(1.0)
                })
                .sum();
            fewest[i] = at_least;
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
        // Every patch that holds light shoots to every vertex at least once: the work grows as
        // patches x vertices, and a mesh that fits in memory can still take hours. A
        // triangulation of E elements has at least E / 2 vertices, so this bound is a floor of
        // one sweep's form factors.
        let [patches_at_least, elements_at_least] = fewest;
        let sweep = patches_at_least * (elements_at_least / 2.0);
        if sweep > MAX_SWEEP_FORM_FACTORS {
            return Err(SolveError::Option {
                name: "element_size",
                problem: format!(
                    "{element_size} scene units (patches of {patch_size}) would have progressive \
                     refinement compute at least {sweep:.3e} form factors a sweep (at least \
                     {patches_at_least:.3e} patches x {:.3e} vertices), more than the \
                     {MAX_SWEEP_FORM_FACTORS:.0e} it takes on; give a larger element size or use \
                     the hierarchical solver",
                    elements_at_least / 2.0
                ),
            });
        }
        // Bisection leaves of longest edge at most L have an area of L^2 / 8 or more: refuse
        // up front a mesh that would not fit instead of refining until the allocator gives up.
        let elements: f64 = (0..scene.mesh.triangle_count() as u32)
            .filter(|&t| takes_part[scene.mesh.object_of(t) as usize])
            .map(|t| {
                (8.0 * f64::from(scene.mesh.area(t)) / f64::from(element_size).powi(2)).max(1.0)
            })
            .sum();
        let patches: f64 = scene
            .mesh
            .areas()
            .map(|a| (8.0 * f64::from(a) / f64::from(patch_size).powi(2)).max(1.0))
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
            element_albedo: Default::default(),
            emission: Vec::new(),
            receiving: Vec::new(),
            receivers: Vec::new(),
            hidden: Vec::new(),
            lamp: Vec::new(),
            received_emit: Vec::new(),
            received_refl: Vec::new(),
            specular,
            unshot_emit: Vec::new(),
            unshot_refl: Vec::new(),
            arrived: Vec::new(),
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
        s.patch_area = visible_patch_areas(&s.mesh, &s.hidden);
        s.patch_rho = (0..n)
            .map(|p| crate::albedo::node_albedo(scene, &s.mesh, s.mesh.patches[p]))
            .collect();
        s.unshot_refl = vec![DVec3::ZERO; n];
        s.arrived = vec![DVec3::ZERO; n];
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
        s.receive_lamps();
        Ok(s)
    }

    /// The lamps' light, already in the vertices' received light, as the patches' unshot
    /// reflected radiosity: each patch receives its elements' areas times the mean of their
    /// vertices' lamp irradiance, as from a shot, and what the lamps send through mirrors and
    /// glass lands as a shot's specular transfer does. The lamps' power joins the emitted power;
    /// what lands on no element (light leaving an open scene, the discretization of the
    /// irradiance over the elements) is escaped.
    fn receive_lamps(&mut self) {
        let power = lamp_power(self.scene);
        if power == DVec3::ZERO {
            return;
        }
        self.bookkeeping.energy.emitted += power;
        let mut arrived = DVec3::ZERO;
        for p in 0..self.mesh.patches.len() {
            let gained: DVec3 = self
                .element_means(p, |v| self.lamp[v])
                .map(|(e, a)| e * a)
                .sum();
            if gained != DVec3::ZERO {
                arrived += gained;
                self.receive(p, gained);
            }
        }
        // Lamp light through mirrors and glass: deposits as from a shot of the lamps.
        if let Some(spec) = &self.specular {
            let key = hash(self.options.seed ^ 0x1a3b_5bec_0000_0000);
            let emitted = luminance_f64(self.bookkeeping.energy.emitted);
            let (deposits, rays) = spec.transfer.shoot_lamps(self.scene, emitted, key);
            arrived += self.land(deposits, rays);
        }
        self.bookkeeping.energy.escaped += power - arrived;
    }

    fn object_of_patch(&self, p: usize) -> u32 {
        let node = &self.mesh.nodes[self.mesh.patches[p] as usize];
        self.scene.mesh.object_of(node.scene_triangle)
    }

    fn patch_emission(&self, p: usize) -> DVec3 {
        self.scene.objects[self.object_of_patch(p) as usize]
            .emission
            .as_dvec3()
            * std::f64::consts::PI
    }

    /// Extends the per-vertex arrays to new vertices (reflectance, emission; received: the
    /// lamps' light, exact at each new vertex, and nothing shot yet).
    pub(super) fn sync_vertices(&mut self) {
        let old = self.rho.len();
        for v in self.rho.len()..self.mesh.vertices.len() {
            let o = &self.scene.objects[self.mesh.vertices[v].object as usize];
            self.rho.push(
                self.scene.materials[o.material as usize]
                    .material
                    .diffuse_albedo()
                    .as_dvec3(),
            );
            self.emission
                .push(o.emission.as_dvec3() * std::f64::consts::PI);
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
        // Without occlusion every point sees everything: none is hidden.
        if self.options.occlusion {
            let hidden = crate::hidden::hidden_points(
                self.scene,
                &self.receivers[old..],
                old,
                self.options.seed,
            );
            self.rays += u64::from(crate::hidden::HIDDEN_RAYS) * hidden.len() as u64;
            self.hidden.extend(hidden);
        } else {
            self.hidden.resize(self.receivers.len(), false);
        }
        if let Some(rho) = self.element_albedo.vertex_albedo(self.scene, &self.mesh) {
            self.rho = rho;
        }
        let (lamp, rays) = vertex_lamp_irradiance(self.scene, &self.mesh, old, self.options.seed);
        for (v, e) in (old..).zip(lamp) {
            self.received_emit[v] += e;
            self.lamp.push(e);
        }
        self.rays += rays;
    }

    /// Where vertex `v` receives ([`receiving_point`]).
    pub(super) fn receiving_point(&self, v: usize) -> DVec3 {
        receiving_point(self.scene, &self.mesh.vertices[v])
    }

    pub(super) fn rebuild_patch_elements(&mut self) {
        self.elements = PatchElements::new(&self.mesh);
        for w in &mut self.weights {
            if let Some(w) = w.take() {
                self.cached_bytes -= std::mem::size_of_val(w.as_slice());
            }
        }
    }

    /// With the specular transfer: every deposit so far splatted afresh onto the current mesh
    /// ([`SpecularReceivers::resplat`]).
    pub(super) fn resplat(&mut self) {
        if let Some(spec) = &mut self.specular {
            spec.resplat(&self.mesh);
        }
    }
}

/// Each patch's area that light leaves from, scene units squared: its elements' areas, each
/// counting the share of its corners that are not hidden inside another object
/// ([`crate::hidden`]). A patch's reflected light is its received power over this area, so
/// the part under a box standing on it does not dilute the light its visible part sends. At
/// least a thousandth of the patch's area, so a patch wholly inside an object stays finite.
fn visible_patch_areas(mesh: &ElementMesh, hidden: &[bool]) -> Vec<f64> {
    let mut visible = vec![0.0f64; mesh.patches.len()];
    for leaf in mesh.leaves() {
        let node = &mesh.nodes[leaf as usize];
        let shown = node
            .vertices
            .iter()
            .filter(|&&v| !hidden[v as usize])
            .count();
        visible[node.patch as usize] += f64::from(node.area) * shown as f64 / 3.0;
    }
    mesh.patches
        .iter()
        .zip(visible)
        .map(|(&p, a)| {
            let whole = f64::from(mesh.nodes[p as usize].area);
            a.clamp(whole * 1e-3, whole)
        })
        .collect()
}
