//! `dancegen convert`: motion from any supported format to any other.

use std::io::Write;

use anyhow::Result;
use dancegen_formats::dispatch::{
    ConvertOptions, LoadOptions, NpzStyle, convert_motion, load_motion_file_with, save_motion_file,
};

use crate::cli::{ConvertArgs, NpzStyleArg, TargetSkeleton};
use crate::progress::spinner;

pub fn run(args: &ConvertArgs, quiet: bool) -> Result<()> {
    let opts = ConvertOptions {
        fps: args.fps,
        to_smpl24: args.to == Some(TargetSkeleton::Smpl24),
        dancer: args.dancer,
        npz_style: match args.npz_style {
            NpzStyleArg::Amass => NpzStyle::Amass,
            NpzStyleArg::Edge => NpzStyle::Edge,
        },
        rig: args.rig,
        npz_record: None,
    };
    let pb = spinner(&format!("converting {}", args.input.display()), quiet);
    let read = LoadOptions {
        source_fps: args.source_fps,
        ..LoadOptions::default()
    };
    let loaded = load_motion_file_with(&args.input, &read)?;
    let converted = convert_motion(&args.input, loaded, &opts)?;
    save_motion_file(&args.output, &converted, &opts)?;
    pb.finish_and_clear();
    if !quiet {
        writeln!(
            std::io::stdout().lock(),
            "{} ({}, {} fps) -> {}",
            args.input.display(),
            converted.kind(),
            converted.fps(),
            args.output.display()
        )?;
    }
    Ok(())
}
