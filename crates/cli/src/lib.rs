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
use nurbspring_scene::Error;

/// Derive mass-spring models that behave like Dynamic NURBS surfaces.
#[derive(Parser, Debug)]
#[command(name = "nurbspring", version, about, long_about = None)]
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
}

impl Context {
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
        // A second Ctrl-C while the first is being honoured ends the process at once.
        let _ = ctrlc::set_handler(move || {
            if cancel.swap(true, std::sync::atomic::Ordering::SeqCst) {
                std::process::exit(i32::from(exit::CANCELLED));
            }
        });
    }
    let ctx = Context {
        global: cli.global.clone(),
        cancel,
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

/// Resolves an output folder: creates it, refusing a path that exists and is not a folder.
pub fn prepare_out_dir(dir: &Path) -> Result<PathBuf, Error> {
    if dir.exists() && !dir.is_dir() {
        return Err(Error::option(
            "--out",
            dir.display(),
            "exists and is not a folder",
        ));
    }
    std::fs::create_dir_all(dir).map_err(|e| {
        Error::Output(nurbspring_io::OutputError::Io {
            path: dir.to_path_buf(),
            source: e,
        })
    })?;
    Ok(dir.to_path_buf())
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
