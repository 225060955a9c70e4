//! File input/output shared by every dancegen crate and command.
//!
//! Outputs are written to a temporary file next to the destination and renamed into place, so
//! an interrupted run or a failing encoder never leaves a half-written file where a previous
//! good one was.

pub mod atomic;
pub mod npy;
pub mod npz;

pub use atomic::write_atomic;
pub use npy::{NpyArray, NpyData, parse_npy, read_npy, write_npy_f32};
pub use npz::{read_npz, read_npz_members, write_npz};
