//! The links as a whole: sorted by receiver and looked up by it, what a link's source sends,
//! and the refinement oracle's error estimate.

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::colour::luminance_f64;

use super::link::Link;
use super::state::HierarchicalSolver;
use crate::cluster::{Kind, NodeRef};

impl HierarchicalSolver<'_> {
    /// The links node `r` receives (they are sorted by receiver).
    pub(super) fn received(&self, r: NodeRef) -> &[Link] {
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
    pub(super) fn link_error(&self, l: &Link) -> f64 {
        let mut e = self.source_value(l);
        // A piece of a source split in this refinement pass has sent nothing yet. Judged by that, a
        // partly blocked link from a piece of an emitter would look harmless and be kept or dropped
        // on a few rays, never refined around the shadow. Such a link is judged by what the piece's
        // parent sent. Only partly blocked links: refining unblocked ones by it too refines a
        // closed room's creases to the smallest elements in the first pass.
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

    /// What a link's source sends (emitted, reflected light), per unit of the link's `transport`:
    /// a surface's area-averaged exitance (W/m^2), a cluster's radiant table entry toward
    /// the receiver (W).
    pub(super) fn source_value(&self, l: &Link) -> [DVec3; 2] {
        match l.source.kind() {
            Kind::Cluster(c) => {
                let t = &self.radiant[c as usize];
                [l.dir.read_rgb(&t[0]), l.dir.read_rgb(&t[1])]
            }
            Kind::Surface(n) => match self.sending.get(n as usize) {
                Some(&sent) => sent,
                None => self.exitance[n as usize],
            },
        }
    }

    /// Whether a node can ever send light: it emits or reflects.
    pub(super) fn may_shine(&self, s: NodeRef) -> bool {
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

    /// Sorts the links by receiver, indexes their runs and bounds what they send
    /// ([`HierarchicalSolver::bound_links`]): every change to the links ends here.
    pub(super) fn sort_links(&mut self) {
        self.links
            .par_sort_unstable_by_key(|l| (l.receiver, l.source));
        self.receivers.clear();
        for (i, l) in self.links.iter().enumerate() {
            if self.receivers.last().is_none_or(|&(r, _)| r != l.receiver) {
                self.receivers.push((l.receiver, i as u32));
            }
        }
        self.bound_links();
    }
}
