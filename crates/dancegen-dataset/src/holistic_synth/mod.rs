//! Synthetic fingers and faces for the holistic (SoulNet) data set (issue 19).
//!
//! No real finger or face dance data can be had here (`../shared/reference/holistic.md` §4: the
//! CMU finger channels are zero, the face captures are non-commercial or unlicensed). So the
//! holistic data set pairs **real** body motion with **synthetic** hands and face, built by the
//! stated rules of [`hands`] and [`face`] from the body and the music. Every model trained on it
//! says so. The point is that hands and face depend on the body and the music in a learnable
//! way, so the body → hands → face hierarchy has something to learn.
pub mod attach;
pub mod face;
pub mod hand_poses;
pub mod hands;
pub mod signal;

pub use face::{FaceInputs, SyntheticFace, synthesize_face};
pub use hands::{SynthInputs, SyntheticHands, synthesize_hands};
