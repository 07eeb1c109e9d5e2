//! # nurbspring (the command-line tool)
//!
//! Thin layer over `nurbspring-scene`: parse flags, call, print, map errors to exit codes
//! ([`exit`]). The binary's `main` is [`main_with_args`].

pub mod commands;
pub mod exit;
mod progress;

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use clap::{Args, Parser, Subcommand};
use nurbspring_io::folder::StagedDir;
use nurbspring_scene::msm_file::{MsmSetup, load_msm_within};
use nurbspring_scene::resources::{Estimate, Job, Limits, Timing, parse_size};
use nurbspring_scene::{Error, Scene};

/// What `nurbspring --help` says after the one-line summary.
const LONG_ABOUT: &str = "\
Derive mass-spring models (MSMs) that behave like Dynamic NURBS surfaces and curves.

A scene file (TOML, docs/scenes.md) gives a NURBS surface or curve with its material,
constraints, loads and initial velocity. nurbspring simulates its D-NURBS, derives the spring
constants and node mass of a lattice on it, validates the MSM against the D-NURBS and writes
both models out (msm.json, Matrix Market, ParaView, SOFA, NumPy).

Output: eval, modes, stability and steady print JSON on stdout; the other commands print a
result line on stdout (JSON with --json); progress, notes and warnings go to stderr; -q hides
progress and notes. Exit codes: 0 success, 2 bad input, 1 a failed run, 130 interrupted.";

/// Examples shown at the end of `nurbspring --help`.
const EXAMPLES: &str = "\
Examples:
  nurbspring check examples/paper.toml
  nurbspring derive examples/paper.toml --out out/paper
  nurbspring simulate out/paper/msm.json --model msm --out out/msm-run
  nurbspring simulate examples/paper.toml --model dnurbs --out out/dnurbs-run --json
  nurbspring import part.igs --out part.toml";

/// Derive mass-spring models that behave like Dynamic NURBS surfaces.
#[derive(Parser, Debug)]
#[command(name = "nurbspring", version, about, long_about = LONG_ABOUT, after_help = EXAMPLES)]
pub struct Cli {
    #[command(flatten)]
    global: GlobalArgs,
    #[command(subcommand)]
    command: Command,
}

/// Flags shared by every command.
#[derive(Args, Debug, Clone)]
pub struct GlobalArgs {
    /// Hide progress bars and informational messages.
    #[arg(long, short, global = true)]
    quiet: bool,
    /// More log output (repeat for more); RUST_LOG also works.
    #[arg(long, short, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
    /// Worker threads (default: all cores).
    #[arg(long, global = true, value_name = "N")]
    threads: Option<usize>,
    /// Refuse, before allocating anything, a job estimated to need more memory than this
    /// (bytes, or with a unit: 512M, 4G; default: 80 % of the memory available).
    #[arg(long, global = true, value_name = "SIZE", value_parser = parse_size)]
    max_memory: Option<u64>,
    /// Refuse a run estimated to write more than this (default: 16G, and never more than the
    /// free space of the output's disk).
    #[arg(long, global = true, value_name = "SIZE", value_parser = parse_size)]
    max_output: Option<u64>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run the paper's experiment (built-in scene) and print the reproduction table.
    Paper(commands::paper::PaperArgs),
    /// Derive the MSM of a scene and validate it against the D-NURBS.
    Derive(commands::derive::DeriveArgs),
    /// Evaluate the scene's surface or curve.
    Eval(commands::eval::EvalArgs),
    /// Write the D-NURBS matrices M, D, K and the load f.
    Matrices(commands::matrices::MatricesArgs),
    /// Simulate the D-NURBS or the MSM of a scene.
    Simulate(commands::simulate::SimulateArgs),
    /// D-NURBS natural frequencies of the constrained system.
    Modes(commands::modes::ModesArgs),
    /// Explicit stability limit of the scene's MSM.
    Stability(commands::stability::StabilityArgs),
    /// D-NURBS steady state under the scene's loads (eq. 8).
    Steady(commands::steady::SteadyArgs),
    /// Validate a scene and describe it without running anything.
    Check(commands::check::CheckArgs),
    /// Write a scene for the surface or curve of a geomdl JSON, IGES or OBJ file.
    Import(commands::import::ImportArgs),
    /// Write a scene's geometry (geomdl JSON, IGES, OBJ) or a mass-spring model (SOFA, NumPy).
    Export(commands::export::ExportArgs),
    /// Refine a scene's geometry exactly: degree elevation and knot insertion.
    Refine(commands::refine::RefineArgs),
}

/// Result of a command.
pub type CmdResult = Result<(), Error>;

/// State every command can reach.
pub struct Context {
    /// Global flags.
    pub global: GlobalArgs,
    /// Set by Ctrl-C.
    pub cancel: Arc<AtomicBool>,
    /// Memory and output limits (`--max-memory`, `--max-output`).
    pub limits: Limits,
}

impl Context {
    /// Refuses `job` on `scene` when its estimate exceeds the limits (before anything is
    /// allocated); `out` is the output folder, whose disk's free space also bounds the output.
    pub fn check_resources(
        &self,
        scene: &Scene,
        job: Job,
        out: Option<&Path>,
    ) -> Result<Estimate, Error> {
        scene.check_resources(job, &self.limits, out)
    }

    /// The MSM of an msm.json file or of a scene, checked against the limits first (see
    /// [`load_msm_within`]; `run`: the output folder and the flags' timing of a simulation).
    pub fn load_msm(
        &self,
        path: &Path,
        overrides: &nurbspring_scene::MsmOverrides,
        flag: &dyn Fn(&str) -> String,
        run: Option<(&Path, Timing)>,
    ) -> Result<MsmSetup, Error> {
        load_msm_within(path, overrides, flag, &self.limits, run)
    }

    /// True unless `--quiet`.
    pub fn verbose(&self) -> bool {
        !self.global.quiet
    }
}

/// Runs the command line `std::env::args()` and returns the process exit code.
pub fn main_with_args() -> ExitCode {
    let cli = Cli::parse();
    init_logging(&cli.global);
    if let Some(n) = cli.global.threads {
        if n == 0 {
            eprintln!("error: --threads 0: must be at least 1");
            return ExitCode::from(exit::INPUT);
        }
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
        {
            eprintln!("error: cannot start {n} worker threads: {e}");
            return ExitCode::from(exit::RUN);
        }
    }
    let cancel = Arc::new(AtomicBool::new(false));
    {
        let cancel = cancel.clone();
        // SIGINT, SIGTERM and SIGHUP ask a cancellable command (derive, paper, simulate) to
        // stop at its next step, and end it after CANCEL_GRACE if it has not (a long
        // factorization does not look at the flag); any other command, and a second signal,
        // end the process at once. Never during an output folder's swap (microseconds): a
        // staged run is then complete in place, or left aside for the next run to remove.
        let cancellable = matches!(
            cli.command,
            Command::Derive(_) | Command::Paper(_) | Command::Simulate(_)
        );
        let _ = ctrlc::set_handler(move || {
            let first = !cancel.swap(true, std::sync::atomic::Ordering::SeqCst);
            if !first || !cancellable {
                exit_cancelled();
            }
            std::thread::spawn(|| {
                std::thread::sleep(CANCEL_GRACE);
                exit_cancelled();
            });
        });
    }
    let mut limits = Limits::from_system();
    if let Some(m) = cli.global.max_memory {
        limits = limits.with_memory(m);
    }
    if let Some(o) = cli.global.max_output {
        limits.output = o;
    }
    let ctx = Context {
        global: cli.global.clone(),
        cancel,
        limits,
    };
    let result = match cli.command {
        Command::Paper(a) => commands::paper::run(&ctx, a),
        Command::Derive(a) => commands::derive::run(&ctx, a),
        Command::Eval(a) => commands::eval::run(&ctx, a),
        Command::Matrices(a) => commands::matrices::run(&ctx, a),
        Command::Simulate(a) => commands::simulate::run(&ctx, a),
        Command::Modes(a) => commands::modes::run(&ctx, a),
        Command::Stability(a) => commands::stability::run(&ctx, a),
        Command::Steady(a) => commands::steady::run(&ctx, a),
        Command::Check(a) => commands::check::run(&ctx, a),
        Command::Import(a) => commands::import::run(&ctx, a),
        Command::Export(a) => commands::export::run(&ctx, a),
        Command::Refine(a) => commands::refine::run(&ctx, a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(exit::code(&e))
        }
    }
}

/// How long a cancellable command may take to stop after a signal before it is ended.
const CANCEL_GRACE: std::time::Duration = std::time::Duration::from_secs(5);

/// Ends the process with the cancellation exit code, once no output folder is being swapped.
fn exit_cancelled() -> ! {
    while nurbspring_io::folder::committing() {
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    nurbspring_io::atomic::remove_pending();
    nurbspring_io::folder::remove_pending();
    std::process::exit(i32::from(exit::CANCELLED))
}

fn init_logging(global: &GlobalArgs) {
    use tracing_subscriber::EnvFilter;
    let default = match (global.quiet, global.verbose) {
        (true, _) => "error",
        (false, 0) => "warn",
        (false, 1) => "info",
        (false, 2) => "debug",
        _ => "trace",
    };
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .without_time()
        .try_init();
}

/// Stages a run's output folder (see [`nurbspring_io::folder`]): the command writes into
/// [`StagedDir::path`] and calls [`commit_out_dir`] when every file is written, so `dir` holds
/// exactly one complete run; a failed or interrupted run leaves the previous one as it was.
pub fn stage_out_dir(dir: &Path) -> Result<StagedDir, Error> {
    StagedDir::create(dir).map_err(|e| match e {
        nurbspring_io::OutputError::InvalidData { message, .. } => {
            Error::option("--out", dir.display(), message)
        }
        e => Error::Output(e),
    })
}

/// Swaps a complete run in (see [`stage_out_dir`]) and returns the folder's path.
pub fn commit_out_dir(staged: StagedDir) -> Result<PathBuf, Error> {
    staged.commit().map_err(Error::Output)
}

/// Prints the `report.json` of the output folder `out` (as written) on stdout: `derive --json`
/// and `paper --json`.
pub fn print_report(out: &Path) -> CmdResult {
    let path = out.join("report.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Error::Output(nurbspring_io::OutputError::Io {
            path: path.clone(),
            source: e,
        })
    })?;
    println!("{}", text.trim_end());
    Ok(())
}

/// Pretty JSON of a value, for commands that print JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> CmdResult {
    let text = serde_json::to_string_pretty(value).map_err(|e| {
        Error::Output(nurbspring_io::OutputError::Json {
            path: PathBuf::from("<stdout>"),
            source: e,
        })
    })?;
    println!("{text}");
    Ok(())
}
