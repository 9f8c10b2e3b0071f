//! Workloads for measuring and testing: ray batches for the accelerator (`query`), the synthetic
//! scene of growing size (`synthetic`) and the family of generated test rooms (`room`) that
//! `twopass bench bakes` measures bakes on.

mod query;
mod room;
mod synthetic;

pub use query::{QueryKind, camera_rays, cosine_direction, incoherent_rays, occlusion_pairs, rng};
pub use room::{Room, RoomKind, RoomSettings, room};
pub use synthetic::{synthetic_scene, synthetic_scene_toml};
