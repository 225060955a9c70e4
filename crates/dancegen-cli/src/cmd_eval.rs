//! `dancegen eval`: the flags become [`dancegen_eval::EvalOptions`]; the report is printed as a
//! table and, with `--json`, written as one object.

use anyhow::Result;
use dancegen_eval::report::{print_table, write_json};
use dancegen_eval::{EvalOptions, Input};
use dancegen_metrics::bas::Variant;

use crate::cli::{BasVariantArg, EvalArgs, ProtocolArg};

pub fn run(args: &EvalArgs) -> Result<()> {
    let report = dancegen_eval::evaluate(&options(args))?;
    print_table(&report);
    if let Some(out) = &args.json {
        write_json(out, &report)?;
    }
    Ok(())
}

fn options(args: &EvalArgs) -> EvalOptions {
    EvalOptions {
        pred: paths(&args.pred),
        gt: paths(&args.gt),
        leader: paths(&args.leader),
        gt_leader: paths(&args.gt_leader),
        protocol: match args.protocol {
            ProtocolArg::AistppBailando => dancegen_metrics::protocol::AISTPP_BAILANDO,
            ProtocolArg::FinedanceLodge => dancegen_metrics::protocol::FINEDANCE_LODGE,
            ProtocolArg::Edge5s => dancegen_metrics::protocol::EDGE_5S,
            ProtocolArg::None => dancegen_metrics::protocol::NONE,
        },
        fps: args.fps,
        source_fps: args.source_fps,
        metrics: args.metrics.clone(),
        gt_genres: args.gt_genres.clone(),
        want_genre: args.want_genre.clone(),
        genre_min_clips: args.genre_min_clips,
        bas_variant: match args.bas_variant {
            BasVariantArg::Bailando => Variant::Bailando,
            BasVariantArg::Lodge => Variant::Lodge,
            BasVariantArg::Fact => Variant::Fact,
            BasVariantArg::Gcd => Variant::Gcd,
        },
        beats: args.beats.clone(),
        beat_frames: None,
        music: args.music.clone(),
        window: args.window,
    }
}

fn paths(p: &[std::path::PathBuf]) -> Vec<Input> {
    p.iter().cloned().map(Input::Path).collect()
}
