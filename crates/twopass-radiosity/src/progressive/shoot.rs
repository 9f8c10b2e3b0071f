//! Shooting: the patch with the most unshot power sends it to every vertex through the form
//! factors and through mirrors and glass; the receiving patches keep what they reflect as
//! unshot power, and the power bookkeeping follows every step.

use glam::DVec3;
use twopass_brdf::colour::luminance_f64;
use twopass_brdf::random::hash;

use super::state::ProgressiveSolver;
use crate::element::Node;
use crate::specular::Deposit;

/// How far above one the form factors of a shot may sum before the shot is scaled to deliver
/// what it sends: the vertex form factors of an ordinary mesh sum to one within a few percent
/// (a closed cube's within 0.5 %, two plates a micrometre apart 3.4 % over), with errors of
/// both signs that cancel over the shots; scaling every shot above one would turn them into
/// a loss that a bright closed room (albedo 0.99) multiplies a hundredfold.
const OVERSHOOT_TOLERANCE: f64 = 0.05;

impl ProgressiveSolver<'_> {
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
        // What each patch receives of the shot, bounded so the shot creates no power. A
        // receiver a hair's breadth from the shooter has vertices that see the shooter as a
        // whole hemisphere, and interpolated over elements larger than the shooter that light
        // would carry more than the shooter sends. So no patch receives more than the whole
        // shot (A_q F_qp = A_p F_pq <= A_p: weights are scene units squared), and a shot whose
        // receivers would still get more than it sends, by more than the vertex form factors'
        // discretization, is scaled to deliver what it sends. The vertices' irradiance is a
        // point value and is left alone (scaling it would darken a small receiver for a large
        // one's interpolation). What was kept out is reported.
        let raw: f64 = weights.iter().filter(|&&w| w > 0.0).sum();
        let bounded: f64 = weights.iter().map(|&w| w.clamp(0.0, area)).sum();
        let scale = if bounded > area * (1.0 + OVERSHOOT_TOLERANCE) {
            area / bounded
        } else {
            1.0
        };
        if raw > bounded * scale {
            self.bookkeeping.energy.excess += sent * (raw - bounded * scale);
        }
        for (v, &f) in row.iter().enumerate() {
            if f > 0.0 {
                self.received_emit[v] += de * f64::from(f);
                self.received_refl[v] += dr * f64::from(f);
            }
        }
        let mut arrived = DVec3::ZERO;
        for (q, &weight) in weights.iter().enumerate() {
            let gained = sent * (weight.min(area) * scale);
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
        self.bookkeeping.energy.escaped += sent * area - arrived;
        self.bookkeeping.energy.sent += sent * area;
        self.bookkeeping.energy.unshot -= sent * area;
        self.shot_emit[p] += de;
        self.shot_refl[p] += dr;
        self.unshot_emit[p] -= de;
        self.unshot_refl[p] -= dr;
        self.note_unshot(p);
        self.shots += 1;
        self.bookkeeping.note_imbalance();
        true
    }

    /// Patch `q` receives `gained` (W per channel): it absorbs `1 - rho` of it and keeps the
    /// rest as unshot exitance.
    pub(super) fn receive(&mut self, q: usize, gained: DVec3) {
        let rho = self.patch_rho(q);
        self.arrived[q] += gained;
        self.bookkeeping.energy.absorbed += gained * (DVec3::ONE - rho);
        let a = self.patch_area(q);
        self.unshot_refl[q] += gained * rho / a;
        self.note_unshot(q);
        self.bookkeeping.energy.unshot += gained * rho;
    }

    /// Brings patch `p`'s entry of `unshot_power` up to date with its unshot radiosity.
    pub(super) fn note_unshot(&mut self, p: usize) {
        self.unshot_power[p] = (self.unshot_emit[p] + self.unshot_refl[p])
            .abs()
            .element_sum()
            * self.patch_area(p);
    }

    pub(super) fn patch_rho(&self, p: usize) -> DVec3 {
        self.patch_rho[p]
    }

    pub(super) fn patch_area(&self, p: usize) -> f64 {
        self.patch_area[p]
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

    /// Irradiance received at vertex `v` from every path, W/m^2.
    pub(super) fn received(&self, v: usize) -> DVec3 {
        let r = self.received_emit[v] + self.received_refl[v];
        match &self.specular {
            Some(spec) => r + spec.received[v],
            None => r,
        }
    }

    /// Irradiance at vertex `v` from light reflected at least once or carried through specular
    /// surfaces (what shadow rays to the emitters do not find), W/m^2.
    pub(super) fn received_indirect(&self, v: usize) -> DVec3 {
        match &self.specular {
            Some(spec) => self.received_refl[v] + spec.received[v],
            None => self.received_refl[v],
        }
    }

    /// Displayed radiosity of vertex `v` without the ambient term, W/m^2.
    pub(super) fn radiosity(&self, v: usize) -> DVec3 {
        self.emission[v] + self.rho[v] * self.received(v)
    }

    /// The specular transfer of the shot of patch `p`: each of its elements sends what its exitance
    /// changed by since it last sent
    /// ([`Specular::shoot_changes`](crate::specular::Specular::shoot_changes): from where the light
    /// leaves it, not as the uniform patch), what lands is splatted onto the vertices and handed to
    /// the receiving patches as unshot reflected radiosity, as the form factors' transfer does.
    /// Returns the power that arrived (W per channel).
    fn shoot_specular(&mut self, p: usize) -> DVec3 {
        let Some(spec) = &self.specular else {
            return DVec3::ZERO;
        };
        let mean = |node: &Node, f: &dyn Fn(usize) -> DVec3| {
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
        let Some((deposits, rays)) = spec
            .transfer
            .shoot_changes(self.scene, &self.mesh, &changes, emitted, 0.0, key)
        else {
            return DVec3::ZERO;
        };
        self.specular
            .as_mut()
            .expect("the transfer shot")
            .note_sent(&self.mesh, &changes);
        self.land(deposits, rays)
    }

    /// Splats `deposits` of the specular transfer (from a shot that cast `rays`) onto the
    /// vertices and hands what they bring to the receiving patches as unshot reflected
    /// radiosity, as the form factors' transfer does; keeps them for later resplats. Returns
    /// the power that arrived (W per channel).
    pub(super) fn land(&mut self, mut deposits: Vec<Deposit>, rays: u64) -> DVec3 {
        let Some(spec) = self.specular.as_mut() else {
            return DVec3::ZERO;
        };
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
}
