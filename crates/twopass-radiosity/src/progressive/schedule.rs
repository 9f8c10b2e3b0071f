//! The schedule of a progressive solve: shoot, refine adaptively at the rounds' unshot
//! fractions, shoot to the stop criteria.

use std::ops::ControlFlow;

use super::state::ProgressiveSolver;
use crate::report::Finish;

impl ProgressiveSolver<'_> {
    /// Runs the whole schedule: shooting, adaptive rounds (if enabled), shooting to the stop
    /// criteria. `observer` sees the solver after every shot: it can read
    /// [`ProgressiveSolver::progress`], take an intermediate [`ProgressiveSolver::solution`] (with
    /// the ambient term) or stop the solve early by returning `Break`; the solution is usable
    /// whenever this returns.
    pub fn run(&mut self, mut observer: impl FnMut(&Self) -> ControlFlow<()>) -> Finish {
        let stop = self.options.stop;
        let adaptive = self.options.adaptive;
        let mut rounds_left = adaptive.map_or(0, |a| a.rounds);
        loop {
            let target = match adaptive {
                Some(a) if rounds_left > 0 => a.at_unshot_fraction.max(stop.unshot_fraction),
                _ => stop.unshot_fraction,
            };
            // An adaptive round computes the new vertices' rows to every patch, which can take
            // as long as the shots so far: none is started past half the time budget.
            if stop
                .time_budget
                .is_some_and(|b| self.bookkeeping.started.elapsed() * 2 >= b)
            {
                rounds_left = 0;
            }
            if self.unshot_fraction() <= target {
                if let (Some(a), true) = (adaptive, rounds_left > 0) {
                    rounds_left -= 1;
                    if self.refine(&a) == 0 {
                        rounds_left = 0;
                    }
                    continue;
                }
                return Finish::Converged;
            }
            if stop.max_shots.is_some_and(|m| self.shots >= m) {
                return Finish::MaxShots;
            }
            if stop
                .time_budget
                .is_some_and(|b| self.bookkeeping.started.elapsed() >= b)
            {
                return Finish::TimeBudget;
            }
            if !self.shoot() {
                return Finish::Exhausted;
            }
            if observer(self).is_break() {
                return Finish::Cancelled;
            }
        }
    }
}
