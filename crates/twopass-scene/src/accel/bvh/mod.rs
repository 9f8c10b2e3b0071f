//! The 8-wide BVH: its node and the node test ([`node`]), its layout in the arena
//! ([`layout`]), the walks' stack ([`stack`]), and the walks: one ray at a time ([`walk`]),
//! several rays interleaved ([`interleaved`]) and coherent rays as packets of eight
//! ([`packet`]). The tree is built by `collapse.rs` from obvhs's binary tree; the queries in
//! `accel/mod.rs` walk it.

mod interleaved;
mod layout;
mod node;
mod packet;
pub(crate) mod stack;
mod walk;

pub(crate) use layout::{Bvh8, HOT_BYTES};
pub(crate) use node::{Node8, NodeRay};
pub(crate) use packet::RayPacket;
