//! Work split by a stable key (`--part I/N`) and merged bit for bit (`twopass merge`).
//!
//! A render splits by tiles, a bake's final gather by point keys (a texel's index in the
//! atlas, a vertex's in its output): every random sequence depends on its key alone, so a part
//! computes exactly what the single process computes for its keys, and the merge assembles
//! the same bits for any number of parts. Files, one job each: `file` (the part file format),
//! `set` (a set of parts checked as one job), `render` (render parts), `assemble` (a set of render parts into the images),
//! `bake` (gather shards and their merge), `merge` (the command).

pub mod assemble;
pub mod bake;
pub mod file;
pub mod merge;
pub mod render;
pub mod set;

pub use file::{PartIndex, parse_part};
