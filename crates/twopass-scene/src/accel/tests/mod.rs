//! Tests of the accelerator that reach into its tree and walks, and build scenes with
//! `crate::workload` (kept here, apart from the files they test, so that those files need not
//! know the workload generator).

mod coherence;
mod collapse;
mod queries;
mod stack;
