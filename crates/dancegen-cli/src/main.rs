//! `dancegen`: music to 3D dance, from the command line.

mod batch;
mod cli;
mod cmd_beats;
mod cmd_bundle;
mod cmd_convert;
mod cmd_dataset;
mod cmd_eval;
mod cmd_features;
mod cmd_generate;
mod cmd_models;
mod cmd_render;
mod cmd_serve;
mod cmd_train;
mod plot;
mod progress;

use clap::Parser;

/// The analysis allocates and frees many multi-megabyte buffers (resampled signals, spectra,
/// octave signals); mimalloc reuses them instead of returning them to the kernel, which
/// measured ~20% of the CPU time in page faults with the system allocator.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    let cli = cli::Cli::parse();
    init_logging(cli.verbose, cli.quiet);
    let result = match &cli.command {
        cli::Command::Features(args) => cmd_features::run(args, cli.quiet),
        cli::Command::Beats(args) => cmd_beats::run(args, cli.quiet),
        cli::Command::Convert(args) => cmd_convert::run(args, cli.quiet),
        cli::Command::Render(args) => cmd_render::run(args, cli.quiet),
        cli::Command::Eval(args) => cmd_eval::run(args),
        cli::Command::Train(args) => cmd_train::run(args, cli.quiet),
        cli::Command::Dataset(cmd) => cmd_dataset::run(cmd, cli.quiet),
        cli::Command::Generate(args) => cmd_generate::run(args, cli.quiet),
        cli::Command::Batch(args) => batch::run(args, cli.quiet),
        cli::Command::Bundle(args) => cmd_bundle::run(args, cli.quiet),
        cli::Command::Models(args) => cmd_models::run(args, cli.quiet),
        cli::Command::Serve(args) => cmd_serve::run(args, cli.quiet),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        // `dancegen beats | head`: the reader went away, which is not our failure.
        Err(e) if is_broken_pipe(&e) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

fn init_logging(verbose: u8, quiet: bool) {
    // -v levels apply to dancegen's own crates; libraries (decoders) stay at warn unless
    // DANCEGEN_LOG says otherwise.
    let ours = match (quiet, verbose) {
        (true, _) => "error",
        (false, 0) => "warn",
        (false, 1) => "info",
        (false, 2) => "debug",
        _ => "trace",
    };
    // Decoder libraries warn about harmless oddities (e.g. malformed Vorbis comments); show
    // those only when asked for more output.
    let others = if verbose == 0 { "error" } else { "warn" };
    // A server's log is its record of jobs: info unless asked to be quiet.
    let server = if quiet || verbose > 0 { ours } else { "info" };
    let directives = format!(
        "{others},dancegen={ours},dancegen_music={ours},dancegen_io={ours},dancegen_server={server}"
    );
    let filter = tracing_subscriber::EnvFilter::try_from_env("DANCEGEN_LOG")
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(directives));
    // Colours only on a terminal: a program reading stderr (the Blender add-on, a CI log)
    // got `\x1b[31mERROR\x1b[0m` around a decoder's words.
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .with_writer(std::io::stderr)
        .with_target(false)
        .without_time()
        .init();
}
