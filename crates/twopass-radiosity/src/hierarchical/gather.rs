//! A gather iteration: every link's transport summed into its receiver (Jacobi), push-pull
//! down and up the hierarchy, the light sent through mirrors and glass, and the power
//! bookkeeping.

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::colour::luminance_f64;
use twopass_brdf::random::hash;

use super::directions::{DIRECTIONS, Incoming, NOTHING};
use super::state::HierarchicalSolver;
use crate::cluster::Kind;

impl HierarchicalSolver<'_> {
    /// One Jacobi gather over every link, then push-pull. Updates the residual.
    pub(super) fn iterate(&mut self) {
        self.weigh_sending();
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
                        let u = toward.unit();
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
        // Energy: what the sources sent (their exitance before this gather, and the lamps)
        // against what arrived, was absorbed, and is reflected but not yet passed on.
        let (mut arrived, mut absorbed) = (DVec3::ZERO, DVec3::ZERO);
        for n in self.mesh.leaves() {
            let node = &self.mesh.nodes[n as usize];
            let [e, r] = self.corners_in[n as usize];
            let irr = (e[0] + e[1] + e[2] + r[0] + r[1] + r[2]) / 3.0 + e[3] + r[3];
            let a = f64::from(node.area);
            arrived += irr * a;
            absorbed += irr * a * (DVec3::ONE - self.node_rho(n));
        }
        self.residual = after - before;
        self.bookkeeping.energy.absorbed = absorbed;
        let sent = before + self.lamp_power;
        self.bookkeeping.energy.escaped = sent - arrived;
        self.bookkeeping.energy.sent = before;
        self.bookkeeping.energy.excess = (arrived - sent).max(DVec3::ZERO);
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
