//! Setting up a hierarchical solve: the checks, the element mesh and cluster tree, the
//! clusters' projected areas and normal cones, and the per-node arrays as the hierarchy grows.

use std::f64::consts::PI;
use std::time::{Duration, Instant};

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::colour::luminance_f64;
use twopass_brdf::random::hash;
use twopass_scene::Scene;

use super::directions::{DARK, DIRECTIONS, EMPTY, Facing, NOTHING, directions};
use super::geometry::merge_cones;
use super::state::{BYTES_PER_CLUSTER, BYTES_PER_LINK, BYTES_PER_NODE, HierarchicalSolver};
use crate::cluster::{Clusters, Kind, NodeRef};
use crate::element::ElementMesh;
use crate::error::SolveError;
use crate::lamps::{lamp_power, vertex_lamp_irradiance};
use crate::options::{MIN_LINK_TOLERANCE, Options, check_common, participating};
use crate::report::Bookkeeping;
use crate::specular::Specular;
use crate::specular_receivers::SpecularReceivers;

impl<'s> HierarchicalSolver<'s> {
    /// Builds the cluster tree over the participating triangles. Objects that neither emit
    /// nor reflect diffusely still cast shadows.
    pub fn new(scene: &'s Scene, options: Options) -> Result<Self, SolveError> {
        if !scene.has_light() {
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
        if !(h.link_tolerance.is_finite() && h.link_tolerance >= MIN_LINK_TOLERANCE) {
            return Err(SolveError::Option {
                name: "link_tolerance",
                problem: format!(
                    "{} must be finite and at least {MIN_LINK_TOLERANCE:e} (f32's precision)",
                    h.link_tolerance
                ),
            });
        }
        check_common(&options)?;
        let takes_part = participating(scene);
        if !takes_part.iter().any(|&t| t) {
            return Err(SolveError::NothingTakesPart);
        }
        let triangles = (0..scene.mesh.triangle_count() as u32)
            .filter(|&t| takes_part[scene.mesh.object_of(t) as usize])
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
        let tri_rho: Vec<DVec3> = (0..scene.mesh.triangle_count())
            .map(|t| {
                let o = &scene.objects[scene.mesh.object_of(t as u32) as usize];
                scene.materials[o.material as usize]
                    .material
                    .diffuse_albedo()
                    .as_dvec3()
            })
            .collect();
        let tri_emission: Vec<DVec3> = (0..scene.mesh.triangle_count())
            .map(|t| {
                scene.objects[scene.mesh.object_of(t as u32) as usize]
                    .emission
                    .as_dvec3()
                    * PI
            })
            .collect();
        let rho_lum: Vec<f64> = tri_rho.iter().map(|&r| luminance_f64(r)).collect();
        let emitting: Vec<bool> = tri_emission.iter().map(|e| *e != DVec3::ZERO).collect();
        let clusters =
            Clusters::build(&mesh, &rho_lum, &emitting).ok_or(SolveError::NothingTakesPart)?;
        let spare = options.memory_limit - base;
        let mut s = Self {
            scene,
            mesh,
            clusters,
            min_size,
            error_threshold: 0.0,
            tri_rho,
            tri_emission,
            node_rho: Vec::new(),
            links: Vec::new(),
            receivers: Vec::new(),
            gathered: Vec::new(),
            exitance: Vec::new(),
            send_weight: Vec::new(),
            sending: Vec::new(),
            bounding: false,
            settled: 0,
            spread: Vec::new(),
            cluster_spread: Vec::new(),
            corners_in: Vec::new(),
            cluster_gathered: Vec::new(),
            cluster_exitance: Vec::new(),
            radiant: Vec::new(),
            radiant_linear: Vec::new(),
            projected: Vec::new(),
            projected_linear: Vec::new(),
            cones: Vec::new(),
            cone_sines: Vec::new(),
            dirs: directions(),
            residual: DVec3::ZERO,
            residual_fraction: 1.0,
            emitted: DVec3::ZERO,
            lamp: Vec::new(),
            lamp_power: lamp_power(scene),
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
            .sum::<DVec3>()
            + s.lamp_power;
        s.error_threshold = h.link_tolerance * luminance_f64(s.emitted).max(f64::MIN_POSITIVE);
        s.refine_for_lamps();
        // Lamp light through mirrors and glass: deposits the first gather splats.
        if let Some(spec) = &mut s.specular {
            let key = hash(s.options.seed ^ 0x1a3b_5bec_0000_0000);
            let (deposits, rays) = spec
                .transfer
                .shoot_lamps(scene, luminance_f64(s.emitted), key);
            s.rays += rays;
            spec.keep(deposits, rays);
            s.specular_stale = true;
        }
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
        let mut linear = vec![DVec3::ZERO; self.clusters.nodes.len()];
        let mut cones = vec![(DVec3::Z, 0.0); self.clusters.nodes.len()];
        for c in (0..self.clusters.nodes.len()).rev() {
            let mut sum = [0.0f64; DIRECTIONS];
            let mut vector = DVec3::ZERO;
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
                        vector += linear[cc as usize];
                    }
                    Kind::Surface(n) => {
                        let node = &self.mesh.nodes[n as usize];
                        let normal = self
                            .scene
                            .mesh
                            .geometric_normal(node.scene_triangle)
                            .as_dvec3();
                        for (s, d) in sum.iter_mut().zip(&self.dirs) {
                            *s += f64::from(node.area) * normal.dot(*d).max(0.0);
                        }
                        vector += f64::from(node.area) * normal;
                    }
                }
            }
            projected[c] = sum.map(|s| s as f32);
            linear[c] = vector;
        }
        self.projected = projected;
        self.projected_linear = linear;
        self.cone_sines = cones.iter().map(|c| Facing::sine(c.1)).collect();
        self.cones = cones;
    }

    /// Extends the per-node arrays to new surface nodes and clusters.
    pub(super) fn grow_arrays(&mut self) {
        let n = self.mesh.nodes.len();
        self.gathered.resize(n, [[DVec3::ZERO; 4]; 2]);
        self.exitance.resize(n, [DVec3::ZERO; 2]);
        self.spread.resize(n, 0.0);
        self.corners_in.resize(n, [[DVec3::ZERO; 4]; 2]);
        if self.scene.has_textures() {
            let (scene, mesh) = (self.scene, &self.mesh);
            let new: Vec<DVec3> = (self.node_rho.len() as u32..n as u32)
                .into_par_iter()
                .map(|k| crate::albedo::node_albedo(scene, mesh, k))
                .collect();
            self.node_rho.extend(new);
        }
        let c = self.clusters.nodes.len();
        self.cluster_gathered.resize(c, NOTHING);
        self.cluster_exitance.resize(c, [DVec3::ZERO; 2]);
        self.radiant.resize(c, EMPTY);
        self.radiant_linear.resize(c, DARK);
        self.cluster_spread.resize(c, 0.0);
        if let Some(spec) = &mut self.specular {
            spec.sent.resize(n, None);
            self.specular_stale = true;
        }
        // New vertices get the lamps' and the sky's light at once, whatever split made them.
        let (lamp, rays) =
            vertex_lamp_irradiance(self.scene, &self.mesh, self.lamp.len(), self.options.seed);
        self.lamp.extend(lamp);
        self.rays += rays;
    }
}
