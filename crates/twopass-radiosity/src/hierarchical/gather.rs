//! A gather iteration: every link's transport summed into its receiver (Jacobi), push-pull
//! down and up the hierarchy, the light sent through mirrors and glass, and the power
//! bookkeeping.

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::colour::luminance_f64;
use twopass_brdf::random::hash;

use super::directions::{DIRECTIONS, EMPTY, Incoming, NOTHING, add_tables};
use super::state::HierarchicalSolver;
use crate::cluster::Kind;
use crate::element::barycentric_2d;

impl HierarchicalSolver<'_> {
    /// One Jacobi gather over every link, then push-pull. Updates the residual.
    pub(super) fn iterate(&mut self) {
        let links = &self.links;
        let receivers = &self.receivers;
        // A cluster's incoming light is boxed: most receivers are surfaces, and an unboxed
        // table per receiver would be the largest transient of a large solve.
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
    pub(super) fn push_pull(&mut self) {
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

    /// With the specular transfer: every deposit so far splatted afresh onto the current mesh
    /// ([`SpecularReceivers::resplat`](crate::specular_receivers::SpecularReceivers::resplat);
    /// after a refinement the deposits land on the finer leaves).
    fn resplat(&mut self) {
        self.specular_stale = false;
        if let Some(spec) = &mut self.specular {
            spec.resplat(&self.mesh);
        }
    }

    /// With the specular transfer: every leaf sends what its exitance changed by since it last sent
    /// through the specular surfaces
    /// ([`Specular::shoot_changes`](crate::specular::Specular::shoot_changes)); changes totalling
    /// under a tenth of the stop's unshot fraction of the emitted power wait for the next gather.
    /// The deposits are splatted onto the vertices as irradiance, which the next gather adds to the
    /// leaves' reflected light.
    pub(super) fn shoot_specular(&mut self) {
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
}
