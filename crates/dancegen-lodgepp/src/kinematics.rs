//! Differentiable de-normalisation and forward kinematics of EDGE-151 windows, shared by the
//! Foot Refine Block, the auxiliary losses and the penetration guidance. The code lives once in
//! `dancegen_nn::edge151` (TCDiff++ uses it too); this module names it for Lodge++.

pub use dancegen_nn::edge151::{
    Denormalize, displacement, feet, host_skeleton, joints, joints_host,
};
