//! `dancegen dataset build`: motion + music training sets (see the `dancegen-dataset` crate).

use std::io::Write;
use std::time::Duration;

use anyhow::{Context, Result};
use dancegen_dataset::warp::WarpParams;
use dancegen_dataset::{BuildOptions, Pairing, Progress, build, summary_table};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::cli::{DatasetBuildArgs, DatasetCommand, PairingArg};

pub fn run(cmd: &DatasetCommand, quiet: bool) -> Result<()> {
    match cmd {
        DatasetCommand::Build(args) => run_build(args, quiet),
    }
}

/// One bar per stage (songs, then motions), hidden with `--quiet`.
struct Bar(ProgressBar);

impl Progress for Bar {
    fn stage(&self, name: &str, total: usize) {
        self.0.set_length(total as u64);
        self.0.set_position(0);
        self.0.set_message(name.to_string());
    }

    fn step(&self, _item: &str) {
        self.0.inc(1);
    }
}

fn run_build(args: &DatasetBuildArgs, quiet: bool) -> Result<()> {
    let opts = BuildOptions {
        out: args.output.clone(),
        pairing: match args.pairing {
            PairingArg::Pseudo => Pairing::Pseudo,
            PairingArg::Duet => Pairing::Duet,
            PairingArg::Dd100 => Pairing::Dd100,
            PairingArg::Aistpp => Pairing::Aistpp,
            PairingArg::Finedance => Pairing::FineDance,
            PairingArg::Group => Pairing::Group,
        },
        motions: args.motion.clone(),
        music: args.music.clone(),
        root: args.root.clone(),
        genre: args.genre.clone(),
        hold_out: args.hold_out.clone(),
        seed: args.seed,
        warp: WarpParams::default(),
        mirror: args.mirror,
        holistic: args.holistic,
        songs_per_motion: args.songs_per_motion,
        merge_genres: args.merge_genre.clone(),
        group: dancegen_dataset::group::GroupOptions {
            samples: args.samples,
            held_out_samples: args.held_out_samples,
            clip_seconds: args.clip_seconds,
            hold_out_shapes: args.hold_out_shape.clone(),
        },
        source_fps: dancegen_dataset::takes::SourceRates::new(args.source_fps.clone()),
    };
    let pb = ProgressBar::new(0);
    if quiet {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    pb.set_style(
        ProgressStyle::with_template("{spinner} {msg} [{bar:30}] {pos}/{len} [{elapsed}]")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    pb.enable_steady_tick(Duration::from_millis(120));
    let started = std::time::Instant::now();
    let bar = Bar(pb);
    let report = build(&opts, &bar)
        .with_context(|| format!("building the data set in {}", args.output.display()))?;
    bar.0.finish_and_clear();
    if !quiet {
        let m = &report.manifest;
        let mut out = std::io::stdout().lock();
        if !m.takes.is_empty() {
            write!(out, "{}", dancegen_dataset::takes::table(&m.takes))?;
        }
        write!(out, "{}", summary_table(m))?;
        writeln!(
            out,
            "{} clips ({} held out), {} frames, genres [{}] in {:.1} s -> {}",
            m.clips.len(),
            m.held_out.len(),
            m.clips.iter().map(|c| c.frames).sum::<usize>(),
            m.genres.join(", "),
            started.elapsed().as_secs_f64(),
            report.manifest_path.display()
        )?;
    }
    Ok(())
}
