//! Refining and staging a generated dance: what the samplers do to a dance after the network,
//! shared by every system.
//!
//! - [`foot_lock`] and [`foot_ik`]: planted feet that stay planted;
//! - [`beat_warp`]: motion beats moved onto the music's beats;
//! - [`couple_separation`]: a duet's follower moved out of the leader's body;
//! - [`formation`]: where a group's dancers stand, and how they move between formations.
//!
//! It builds on `dancegen-motion` alone: no file formats, no networks.
pub mod beat_warp;
pub mod couple_separation;
pub mod foot_ik;
pub mod foot_lock;
pub mod formation;
