//! The schedule of a hierarchical solve: link the hierarchy, gather to the stop criteria and
//! re-refine with the radiosities found.

use std::ops::ControlFlow;

use super::state::{HierarchicalSolver, MAX_ROUNDS};
use crate::report::Finish;

impl HierarchicalSolver<'_> {
    /// Links the hierarchy (first call), then gathers to the stop criteria, re-refining links
    /// with the radiosities found. `observer` sees the solver after every iteration and can
    /// stop it by returning `Break`; the solution is usable whenever this returns.
    pub fn run(&mut self, mut observer: impl FnMut(&Self) -> ControlFlow<()>) -> Finish {
        let stop = self.options.stop;
        if !self.linked {
            let root = self.clusters.root;
            self.refine(vec![(root, root, None)]);
            self.linked = true;
        }
        // First converge coarsely, re-refine with those radiosities, then to the tolerance.
        let mut target = stop.unshot_fraction.max(1e-2);
        let mut last = f64::INFINITY;
        let mut stalled = 0;
        loop {
            if stop.max_shots.is_some_and(|m| self.iterations >= m) {
                return Finish::MaxShots;
            }
            // One gather at least, so a solution cut short still has its direct light.
            if self.deadline_passed() && self.iterations > 0 {
                return Finish::TimeBudget;
            }
            self.iterate();
            if observer(self).is_break() {
                return Finish::Cancelled;
            }
            if self.residual_fraction <= target {
                let refined = if self.bookkeeping.rounds < MAX_ROUNDS {
                    self.bookkeeping.rounds += 1;
                    self.rerefine()
                } else {
                    0
                };
                if refined == 0 && target <= stop.unshot_fraction {
                    if self.refreshed || self.deadline_passed() {
                        return Finish::Converged;
                    }
                    self.refreshed = true;
                    if self.refresh_visibility() == 0 {
                        return Finish::Converged;
                    }
                }
                if refined == 0 {
                    target = stop.unshot_fraction;
                }
                last = f64::INFINITY;
                stalled = 0;
                continue;
            }
            // Jacobi shrinks the residual by the scene's reflectance every iteration; when it
            // stops shrinking (rounding), nothing more is to be had.
            if self.residual_fraction >= last {
                stalled += 1;
                if stalled >= 8 {
                    return Finish::Exhausted;
                }
            } else {
                stalled = 0;
            }
            last = self.residual_fraction;
        }
    }
}
