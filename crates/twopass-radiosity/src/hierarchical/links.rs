//! The links as a whole: sorted by receiver and looked up by it, what a link's source sends,
//! and the refinement oracle's error estimate.

use glam::DVec3;
use rayon::prelude::*;
use twopass_brdf::colour::luminance_f64;

use super::directions::{Dir, Facing};
use super::link::Link;
use super::state::HierarchicalSolver;
use crate::cluster::{Kind, NodeRef};

/// Levels below a cluster whose surfaces face a direction only in part that its light and
/// projected area are summed over (each part exact where it faces the direction wholly)
/// before the direction table is read.
pub(super) const RESOLVE_DEPTH: u32 = 3;

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
            Kind::Cluster(c) => self.cluster_radiant(c, l.dir),
            Kind::Surface(n) => match self.sending.get(n as usize) {
                Some(&sent) => sent,
                None => self.exitance[n as usize],
            },
        }
    }

    /// Cluster `c`'s radiant intensity times pi toward `dir` (emitted, reflected light), W:
    /// exact where every triangle inside faces `dir`; where only some do, summed over its
    /// parts down to [`RESOLVE_DEPTH`] levels (each exact where it faces `dir` wholly), then
    /// from the table.
    pub(super) fn cluster_radiant(&self, c: u32, dir: Dir) -> [DVec3; 2] {
        self.radiant_at(c, dir, dir.unit(), RESOLVE_DEPTH)
    }

    fn radiant_at(&self, c: u32, dir: Dir, u: DVec3, depth: u32) -> [DVec3; 2] {
        match self.facing(c, u) {
            Facing::All => self.radiant_linear[c as usize]
                .map(|m| (m * u.as_vec3()).as_dvec3().max(DVec3::ZERO)),
            Facing::None => [DVec3::ZERO; 2],
            Facing::Some if depth > 0 => {
                let mut sum = [DVec3::ZERO; 2];
                for child in self.clusters.nodes[c as usize].children {
                    let part = match child.kind() {
                        Kind::Cluster(cc) => self.radiant_at(cc, dir, u, depth - 1),
                        Kind::Surface(n) => {
                            let a = self.surface_projected(n, u);
                            self.exitance[n as usize].map(|e| e * a)
                        }
                    };
                    sum[0] += part[0];
                    sum[1] += part[1];
                }
                sum
            }
            Facing::Some => {
                let t = &self.radiant[c as usize];
                [dir.read_rgb(&t[0]), dir.read_rgb(&t[1])]
            }
        }
    }

    /// Cluster `c`'s projected area toward `dir`, scene units squared, by the same rule as
    /// [`Self::cluster_radiant`].
    pub(super) fn cluster_projected(&self, c: u32, dir: Dir) -> f64 {
        self.projected_at(c, Some(dir), dir.unit(), RESOLVE_DEPTH)
    }

    /// Cluster `c`'s projected area toward unit direction `u` as [`Self::cluster_projected`]
    /// gives it; the table's blend is made only when it is needed (`dir`, when given, is `u`'s).
    pub(super) fn projected_at(&self, c: u32, dir: Option<Dir>, u: DVec3, depth: u32) -> f64 {
        match self.facing(c, u) {
            Facing::All => self.projected_linear[c as usize].dot(u).max(0.0),
            Facing::None => 0.0,
            Facing::Some if depth > 0 => self.clusters.nodes[c as usize]
                .children
                .iter()
                .map(|&child| match child.kind() {
                    Kind::Cluster(cc) => self.projected_at(cc, dir, u, depth - 1),
                    Kind::Surface(n) => self.surface_projected(n, u),
                })
                .sum(),
            Facing::Some => dir
                .unwrap_or_else(|| Dir::new(&self.dirs, u))
                .read(&self.projected[c as usize]),
        }
    }

    /// Surface node `n`'s projected area toward unit direction `u`, scene units squared.
    pub(super) fn surface_projected(&self, n: u32, u: DVec3) -> f64 {
        let t = self.mesh.nodes[n as usize].scene_triangle as usize;
        let cos = self
            .scene
            .mesh
            .geometric_normal(t as u32)
            .as_dvec3()
            .dot(u)
            .max(0.0);
        f64::from(self.mesh.nodes[n as usize].area) * cos
    }

    /// Which of cluster `c`'s surfaces face unit direction `u`.
    fn facing(&self, c: u32, u: DVec3) -> Facing {
        Facing::of(self.cones[c as usize].0, self.cone_sines[c as usize], u)
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
