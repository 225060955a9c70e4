//! `dancegen convert`: motion from one file format to another.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use dancegen_formats::rig::Rig;

use dancegen_generate::flags::values::{parse_rig, parse_source_fps};

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum NpzStyleArg {
    /// AMASS-style SMPL: poses, trans, betas, mocap_framerate.
    Amass,
    /// EDGE's keys: smpl_poses, smpl_trans.
    Edge,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum TargetSkeleton {
    /// The 24-joint SMPL body (retargets a BVH by joint names).
    Smpl24,
}

#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// Input motion: AIST++ / AIOZ-GDance .pkl, .bvh, SMPL or EDGE .npz, FineDance .npy (T, 315),
    /// joints .npy (T, J, 3) or a group's (N, T, J, 3), or a .glb / .fbx dancegen wrote.
    pub input: PathBuf,
    /// Output; the format follows the extension: .npy (world joints (T, J, 3), float32, Y-up),
    /// .bvh, .glb, .fbx, .npz, .json.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output frame rate (default: the input's).
    #[arg(long)]
    pub fps: Option<f32>,
    /// Read the input as sampled at this rate, whatever its header says: the frames stay the
    /// same, their times change (--fps still resamples the output). E.g. 60 for the CMU salsa
    /// BVHs, whose headers say 120. Needed for a file whose header has no rate.
    #[arg(long, value_name = "FPS", value_parser = parse_source_fps)]
    pub source_fps: Option<f64>,
    /// Retarget to this skeleton first.
    #[arg(long, value_enum)]
    pub to: Option<TargetSkeleton>,
    /// Dancer of a group file to export (single-person formats need one; .glb, .npy and .json keep every dancer unless this is given) (0-based).
    #[arg(long)]
    pub dancer: Option<usize>,
    /// Keys of an .npz output.
    #[arg(long, value_enum, default_value_t = NpzStyleArg::Amass)]
    pub npz_style: NpzStyleArg,
    /// Bone names of .bvh, .fbx and .glb output: smpl, mixamo (mixamorig:Hips, ...), ue5
    /// (pelvis, thigh_l, ...) or vrm (hips, leftUpperLeg, ...); joint positions are the same
    /// in every rig. Needs SMPL 24 motion (add --to smpl24 for a BVH).
    #[arg(long, default_value = "smpl", value_parser = parse_rig)]
    pub rig: Rig,
}
