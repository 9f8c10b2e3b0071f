//! Link refinement (BF refinement): deciding each candidate link (keep, drop or split an end),
//! splitting the element mesh where links need it, estimating partly blocked links again, and
//! re-refining with the converged radiosities.

use std::time::Instant;

use rayon::prelude::*;
use twopass_brdf::random::hash;

use super::link::{Eval, Link};
use super::state::{BATCH, HierarchicalSolver};
use crate::cluster::{Kind, NodeRef};

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

impl HierarchicalSolver<'_> {
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
        // blocker that `n` rays all missed can still take part of it. Such a link is confirmed
        // with the full count before it is trusted whenever one blocked ray would have made it
        // be refined (its whole transport over the threshold): were only the links whose rays
        // found a blocker looked at again, those whose rays all missed it would keep a
        // visibility of one, and on average the links would carry more than they should (a
        // room of small objects near a light created 2 % of its power that way). (A cluster
        // link's error is its whole transport already.)
        if let (Kind::Surface(_), Kind::Surface(_)) = (r.kind(), s.kind())
            && !self.out_of_time
            && !e.partial
            && e.rays > 0
            && e.rays < u64::from(vis.max)
        {
            let carried = self.ends(r).area
                * ((e.transport[0] + e.transport[1] + e.transport[2]) / 3.0 + e.area_correction);
            let doubt = Link {
                error: carried as f32,
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

    pub(super) fn deadline_passed(&self) -> bool {
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
    pub(super) fn refine(&mut self, candidates: Vec<(NodeRef, NodeRef, Option<Link>)>) -> usize {
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
    pub(super) fn refresh_visibility(&mut self) -> usize {
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

    /// Re-checks every link against the oracle with the current radiosities; refines those
    /// whose error is now too large. Returns how many were refined.
    pub(super) fn rerefine(&mut self) -> usize {
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
}
