//! `patchwork` command line: render, stats, check, merge, export, bench, view, implode.
//!
//! Thin: each command lives in `cmd/<name>.rs` (its flags, checks, library calls, printing);
//! shared flag groups and their checks in `args.rs`; errors in `error.rs`; where output goes
//! (`--json`, `-q`) in `out.rs`. Exit codes: 0 done (or passed), 1 a check or benchmark ran
//! and failed (or `render --ref` found the image different), 2 an error (`error: …` on
//! stderr), 130 / 143 interrupted by SIGINT / SIGTERM (temporary output files removed first).

mod args;
mod cmd;
mod error;
mod out;
mod shard;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "patchwork",
    version,
    about = "Crack-free rendering of multi-patch surfaces with fat borders"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Print nothing but errors (and --json output).
    #[arg(short, long, global = true)]
    quiet: bool,
    /// Print the command's results as one JSON object on stdout (render, stats, check,
    /// export, implode, bench --flythrough).
    #[arg(long, global = true)]
    json: bool,
    /// Format of a model read from stdin (`-` as the file): its extension (step, stp, iges,
    /// igs, bpt, glb, obj, ply, stl; step.gz, iges.gz).
    #[arg(long, global = true, value_name = "EXT")]
    format: Option<String>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a model to a PNG (headless; software rasterizers are fine).
    Render(cmd::render::RenderArgs),
    /// Tessellate for a view and print patches, triangles, border vertices, ε range, time.
    Stats(cmd::stats::StatsArgs),
    /// Render random views with fat borders off and on and count crack and growth pixels.
    Check(cmd::check::CheckArgs),
    /// Combine the shards of a sharded run (`check --shard I/N`, `bench --scale --shard I/N`):
    /// the unsharded run's output and exit code, or exit 2 when a shard is missing, given
    /// twice or of another run.
    Merge(cmd::merge::MergeArgs),
    /// Write the tessellation as binary glTF (.glb): one mesh per part, one node per placement.
    Export(cmd::export::ExportArgs),
    /// Benchmarks: `--flythrough` drives a recorded camera path through the LOD frame loop;
    /// `--scale` sweeps teapot grids from 10³ to 10⁶ patches (and the files given).
    Bench(cmd::bench::BenchArgs),
    /// One point of `bench --scale`, measured in this process (run by `bench --scale`).
    #[command(hide = true)]
    ScalePoint(cmd::bench::ScalePointArgs),
    /// Interactive viewer (needs a display; `xvfb-run -a` gives a virtual one).
    #[cfg(feature = "viewer")]
    View(cmd::view::ViewArgs),
    /// Animate parts (or patches) flying together (or apart): numbered PNGs, an animated GIF,
    /// and an MP4 when `ffmpeg` is on the PATH.
    Implode(cmd::implode::ImplodeArgs),
}

/// On SIGINT or SIGTERM: remove the live temporary files and folders of output being written
/// (`patchwork::io::atomic`), then exit with 128 + the signal's number (130, 143) like a
/// shell. Without the handler a signal would leave `.NAME.PID.N.tmp` files behind.
fn remove_temporaries_on_signals() {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM]) else {
        eprintln!("warning: no SIGINT/SIGTERM handler: an interrupted write may leave a .tmp file");
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            // Held until the process ends: no new temporary file appears after the clean-up.
            let removed = patchwork::io::atomic::remove_temporaries();
            eprintln!(
                "interrupted by signal {signal}: {} temporary output file(s) removed",
                removed.removed
            );
            std::process::exit(128 + signal);
        }
    });
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    out::set(out::Mode {
        quiet: cli.quiet,
        json: cli.json,
    });
    cmd::set_stdin_format(cli.format.clone());
    remove_temporaries_on_signals();
    let passed = match &cli.command {
        Command::Render(a) => cmd::render::run(a),
        Command::Stats(a) => cmd::stats::run(a),
        Command::Check(a) => cmd::check::run(a),
        Command::Merge(a) => cmd::merge::run(a),
        Command::Export(a) => cmd::export::run(a).map(|()| true),
        Command::Bench(a) => cmd::bench::run(a),
        Command::ScalePoint(a) => cmd::bench::run_scale_point(a).map(|()| true),
        #[cfg(feature = "viewer")]
        Command::View(a) => cmd::view::run(a).map(|()| true),
        Command::Implode(a) => cmd::implode::run(a),
    };
    match passed {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
