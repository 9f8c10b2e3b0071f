//! The links' form factors bounded so that no surface sends more light than it has: for every
//! leaf, the form factors of the links leaving it and its ancestors sum to at most one (within
//! the seven-point averages' error), once a gather has shown the links creating light.
//!
//! A link's transport is point form factors at the receiver's corners and a seven-point area
//! average. Where two surfaces are closer than the elements resolve (a light a hair's breadth
//! from a wall, facing it), an element partly under the source sees it as a whole hemisphere
//! at the points that lie under it, and its average over-counts: summed over the receivers,
//! the source would send more than it emits, and a closed gap trading light back and forth
//! multiplies that. The exact sum is one at most (the source sees one hemisphere), so a leaf
//! whose links (its own and its ancestors', which carry its light averaged with its
//! neighbours') sum above one sends through them only a share of its exitance: no leaf sends
//! more than it has, and a leaf whose links are right sends all of it. Reciprocity gives each
//! link's form factor from the source's side, A_r F_r->s / A_s.

use super::state::HierarchicalSolver;

/// Share of the emitted power that a gather may deliver beyond what its sources sent
/// ([`crate::Energy::excess`]) before the leaves' shares are applied for the rest of the solve.
/// An ordinary scene's links overshoot and undershoot by a few percent here and there and
/// cancel (the Cornell box: under 0.1 %); cutting them there would only lose light.
const BOUND_TRIGGER: f64 = 0.01;

/// How far above one a leaf's form factors may sum before its shares are cut. The seven-point
/// area averages of an ordinary mesh err by up to a quarter either way (a closed cube's leaves
/// sum to 0.75-1.25, 4 % of the area over one and 4.5 % under on average), errors that cancel
/// over a room and that cutting at one would turn into a loss of light (cut at 1.02, a closed
/// cube with a light 1e-2 from a wall loses 3.6 % of its light). Surfaces closer than the mesh resolves sum far beyond (a wall's pieces under
/// a light a hair's breadth in front of it, to 2), and are cut to this.
const SUM_TOLERANCE: f64 = 0.25;
use crate::cluster::Kind;

/// A leaf's own links summing to at least this see its whole hemisphere (the form factor of a
/// piece of wall wholly under a light a hair's breadth in front of it is one to within the
/// gap's share of its size).
const WHOLE: f64 = 0.999;

/// How far above one such a leaf's own and its ancestors' links may sum together.
const WHOLE_TOLERANCE: f64 = 0.02;

impl HierarchicalSolver<'_> {
    /// Each leaf's share of its exitance that its links send (`send_weight`), so that none
    /// sends more than it has (see the module's comment). Links from clusters are far-field
    /// estimates between separated ends and are left alone.
    pub(super) fn bound_links(&mut self) {
        let nodes = &self.mesh.nodes;
        // Per surface node: the form factor of the links it is the source of, from its side.
        let mut sum = vec![0.0f64; nodes.len()];
        for l in &self.links {
            let Kind::Surface(s) = l.source.kind() else {
                continue;
            };
            sum[s as usize] += self.form_factor_from_source(l, s);
        }
        // Down the trees (a node's children come after it): per node, what a leaf below sends
        // through this node's links and its ancestors'.
        let mut parent = vec![u32::MAX; nodes.len()];
        for (n, node) in nodes.iter().enumerate() {
            if let Some(ch) = node.children {
                for c in ch {
                    parent[c as usize] = n as u32;
                }
            }
        }
        let mut above = vec![0.0f64; nodes.len()];
        for n in 0..nodes.len() {
            if let Some(&p) = parent.get(n).filter(|&&p| p != u32::MAX) {
                above[n] = above[p as usize] + sum[p as usize];
            }
        }
        // Each leaf sends through its own links, then through its ancestors', a share of its
        // exitance: all of it while the form factors sum to 1 + SUM_TOLERANCE at most. Beyond,
        // its own links (the finest, their visibility its own) keep what they can of that
        // budget and the ancestors' links share the rest: a wall's piece in the shadow of a
        // light a hair's breadth in front of it sends its light to the light, not to the room
        // that its ancestors' coarser links see around the light.
        let most = 1.0 + SUM_TOLERANCE;
        self.send_weight = sum
            .iter()
            .zip(&above)
            .map(|(&own, &up)| {
                let w_own = if own > most { most / own } else { 1.0 };
                // A leaf whose own links already see its whole hemisphere (they sum to one, as
                // a wall's piece under a light a hair's breadth away does) has nothing left
                // for its ancestors' coarser links, which see around what it sees.
                let budget = if own >= WHOLE {
                    1.0 + WHOLE_TOLERANCE
                } else {
                    most
                };
                let left = (budget - own * w_own).max(0.0);
                let w_up = if up > left { left / up } else { 1.0 };
                [w_own, w_up]
            })
            .collect();
    }

    /// What each surface node sends through its links ([`HierarchicalSolver::source_value`]): a
    /// leaf, its exitance times its own links' share; a node above, the area average of its
    /// leaves' exitance, each times its ancestors' links' share (`send_weight`). Empty where
    /// every share is whole (the exitance itself is sent), and until a gather has delivered
    /// more than [`BOUND_TRIGGER`] beyond what was sent. From the current exitance, after a
    /// push-pull.
    pub(super) fn weigh_sending(&mut self) {
        let nodes = &self.mesh.nodes;
        if !self.bounding && self.bookkeeping.energy.excess_fraction() > BOUND_TRIGGER {
            self.bounding = true;
        }
        if !self.bounding
            || self.send_weight.len() != nodes.len()
            || self.send_weight.iter().all(|w| w[0] >= 1.0 && w[1] >= 1.0)
        {
            self.sending.clear();
            return;
        }
        // Up the trees (a node's children come after it): the power each node sends.
        let mut power = vec![[glam::DVec3::ZERO; 2]; nodes.len()];
        self.sending = vec![[glam::DVec3::ZERO; 2]; nodes.len()];
        for n in (0..nodes.len()).rev() {
            let a = f64::from(nodes[n].area);
            let e = self.exitance[n];
            power[n] = match nodes[n].children {
                None => {
                    self.sending[n] = e.map(|v| v * self.send_weight[n][0]);
                    e.map(|v| v * (a * self.send_weight[n][1]))
                }
                Some([x, y]) => {
                    let (x, y) = (power[x as usize], power[y as usize]);
                    let p = [x[0] + y[0], x[1] + y[1]];
                    self.sending[n] = p.map(|v| v / a.max(f64::MIN_POSITIVE));
                    p
                }
            };
        }
    }

    /// The form factor of link `l` from its surface source `s`'s side: the power it carries per
    /// unit of the source's power. A surface receiver gets its area times its area-averaged
    /// irradiance per unit exitance (reciprocity: A_r F_r->s / A_s); a cluster receiver its
    /// projected area times the flux density (the link's `area_correction`).
    fn form_factor_from_source(&self, l: &super::link::Link, s: u32) -> f64 {
        let a_s = f64::from(self.mesh.nodes[s as usize].area).max(f64::MIN_POSITIVE);
        let k = |i: usize| f64::from(l.transport[i]);
        match l.receiver.kind() {
            Kind::Surface(r) => {
                let average = ((k(0) + k(1) + k(2)) / 3.0 + f64::from(l.area_correction)).max(0.0);
                f64::from(self.mesh.nodes[r as usize].area) * average / a_s
            }
            Kind::Cluster(_) => f64::from(l.area_correction).max(0.0) / a_s,
        }
    }
}
