//! `asperity`: the command-line front end. All work is done by the library; this file only
//! parses arguments, sets up logging and prints results.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use asperity::config::{Case, QuantitySpec};
use asperity::mesh::msh;
use asperity::pipeline;
use asperity::study;

/// Finite-element analysis of 2D plane and axisymmetric contact with interface compliance
/// and friction (Buczkowski & Kleiber 1994). Units: mm, N, MPa.
#[derive(Parser)]
#[command(version, about)]
struct Cli {
    /// More log output (-v info, -vv debug).
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a case file: mesh, solve all load steps, write VTU/PVD and CSV results.
    Run {
        /// The case file (TOML).
        case: PathBuf,
        /// Output folder (default: the case's [output] dir, else out/<case name>).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Mesh-convergence study: mesh the case's .geo at several sizes, solve each, and check
    /// the convergence of quantities of interest. Exit status: 0 when every quantity passes,
    /// 1 when one fails (one line each on stderr), 2 when the study cannot be run.
    Converge {
        /// The case file (TOML); it must mesh a .geo script.
        case: PathBuf,
        /// Number of mesh levels (at least 3).
        #[arg(long, default_value_t = 3)]
        levels: usize,
        /// Refinement ratio: each level's mesh size factor is the previous one's / RATIO.
        #[arg(long, default_value_t = 2.0)]
        ratio: f64,
        /// A quantity of interest in addition to the case's [[quantity]] sections (replacing
        /// one of the same name): name:kind:key=value,key=value, e.g.
        /// 'u:displacement:point=bore_point,component=x'. Repeatable.
        #[arg(long = "quantity", value_parser = asperity::config::parse_quantity)]
        quantities: Vec<QuantitySpec>,
        /// Output folder (default: out/converge/<case name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Levels solved at once (default: the number of cores; memory permitting).
        #[arg(long)]
        jobs: Option<usize>,
        /// Do not make convergence.png.
        #[arg(long)]
        no_plot: bool,
    },
    /// Fit interface-law parameters to measured joint curves (Levenberg–Marquardt): values,
    /// standard errors, 95 % intervals, correlations, plots, fit.json and a `law = {...}` line.
    /// Exit status 1 when a parameter is not identifiable from the data.
    Fit {
        /// The fit file (TOML).
        file: PathBuf,
        /// Output folder (default: out/fit/<fit file name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Do not make the PNG plots.
        #[arg(long)]
        no_plot: bool,
    },
    /// Parameter sweeps: plan case files, run them (locally, GNU parallel or Slurm), collect.
    Sweep {
        #[command(subcommand)]
        action: SweepAction,
    },
    /// Describe a gmsh MSH 4.1 file: physical groups, element counts and types, problems.
    MeshInfo {
        /// The mesh file.
        file: PathBuf,
    },
}

#[derive(Subcommand)]
enum SweepAction {
    /// Write one case file per run, manifest.json, jobs.txt (GNU parallel) and array.sbatch
    /// (Slurm job array) into the study folder.
    Plan {
        /// The sweep file (TOML).
        file: PathBuf,
        /// Study folder (default: out/sweep/<sweep file name>).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Run the study's runs that are not done: all of them on a local pool (--jobs), or the
    /// one of --task (what jobs.txt and array.sbatch call).
    Run {
        /// The study folder.
        study: PathBuf,
        /// Run only this task (0-based run id).
        #[arg(long)]
        task: Option<usize>,
        /// Runs at once (default: the number of cores; memory permitting).
        #[arg(long)]
        jobs: Option<usize>,
        /// Run failed runs again (by default every run with a summary.json is done).
        #[arg(long)]
        retry_failed: bool,
    },
    /// Gather every run's status and quantities into sweep.csv, with plots. Exit status 1
    /// when a run failed or has not run.
    Collect {
        /// The study folder.
        study: PathBuf,
        /// Do not make the PNG plots.
        #[arg(long)]
        no_plot: bool,
    },
}

/// Exit status of `asperity run` when the structure collapses (README "Exit codes"): 0 is
/// success, 1 any other failure, 2 a convergence study that cannot run.
const COLLAPSE_EXIT_CODE: u8 = 3;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let level = match cli.verbose {
        0 => tracing::Level::WARN,
        1 => tracing::Level::INFO,
        _ => tracing::Level::DEBUG,
    };
    tracing_subscriber::fmt()
        .with_max_level(level)
        .with_writer(std::io::stderr)
        .with_target(false)
        .init();
    if let Command::Converge { .. } = cli.command {
        return match converge_command(cli.command) {
            Ok(code) => code,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        };
    }
    if let Command::Fit { .. } | Command::Sweep { .. } = cli.command {
        return match fit_or_sweep(cli.command) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => ExitCode::FAILURE,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        };
    }
    match execute(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        // Plastic collapse (the load exceeds what the structure carries): its own code, so
        // scripts can tell it from other failures; the converged steps are on disk.
        Err(e @ asperity::Error::Collapse { .. }) => {
            eprintln!("error: {e}");
            ExitCode::from(COLLAPSE_EXIT_CODE)
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn converge_command(command: Command) -> asperity::Result<ExitCode> {
    let Command::Converge {
        case,
        levels,
        ratio,
        quantities,
        out,
        jobs,
        no_plot,
    } = command
    else {
        unreachable!("called for converge only")
    };
    let parsed = Case::from_file(&case)?;
    let out = out.unwrap_or_else(|| {
        PathBuf::from("out/converge").join(case.file_stem().unwrap_or_default())
    });
    let options = study::Options {
        levels,
        ratio,
        out,
        quantities,
        jobs,
        plot: !no_plot,
    };
    let report = study::run(&parsed, &options)?;
    println!("{report}");
    let failures = report.failures();
    for line in &failures {
        eprintln!("FAILED {line}");
    }
    Ok(if failures.is_empty() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// `asperity fit` and `asperity sweep`; `Ok(false)`: finished, but with a result that needs
/// attention (a non-identifiable parameter, a failed run).
fn fit_or_sweep(command: Command) -> asperity::Result<bool> {
    let default_out = |kind: &str, file: &std::path::Path| {
        PathBuf::from("out")
            .join(kind)
            .join(file.file_stem().unwrap_or_default())
    };
    match command {
        Command::Fit { file, out, no_plot } => {
            let result = asperity::fit::Fit::from_file(&file)?.run()?;
            let out = out.unwrap_or_else(|| default_out("fit", &file));
            let plots = asperity::fit::write(&result, &out, !no_plot)?;
            println!("{result}");
            println!(
                "results: {} (fit.json, curves.csv, law.toml); plots: {plots}",
                out.display()
            );
            Ok(result.identifiable)
        }
        Command::Sweep { action } => sweep_command(action),
        _ => unreachable!("called for fit and sweep only"),
    }
}

fn sweep_command(action: SweepAction) -> asperity::Result<bool> {
    use asperity::sweep;
    let exe = std::env::current_exe().map_err(|e| asperity::Error::io("asperity", e))?;
    match action {
        SweepAction::Plan { file, out } => {
            let study = out.unwrap_or_else(|| {
                PathBuf::from("out/sweep").join(file.file_stem().unwrap_or_default())
            });
            let manifest = sweep::plan(&file, &study, &exe)?;
            println!(
                "planned {} runs of {} in {} (manifest.json, jobs.txt, array.sbatch)",
                manifest.runs.len(),
                manifest.base.display(),
                study.display()
            );
            Ok(true)
        }
        SweepAction::Run {
            study,
            task: Some(k),
            retry_failed,
            ..
        } => {
            if !sweep::run_task(&study, k, retry_failed)? {
                println!("run {k}: done before, skipped");
            }
            Ok(true)
        }
        SweepAction::Run {
            study,
            task: None,
            jobs,
            retry_failed,
        } => {
            let jobs =
                jobs.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            let (ran, failed) = sweep::run_local(&study, jobs, &exe, retry_failed)?;
            println!(
                "ran {} runs ({} failed: {failed:?}); `asperity sweep collect {}` gathers them",
                ran.len(),
                failed.len(),
                study.display()
            );
            Ok(failed.is_empty())
        }
        SweepAction::Collect { study, no_plot } => {
            let c = sweep::collect(&study, !no_plot)?;
            for (id, status, error) in &c.failures {
                eprintln!("run {id}: {status}: {error}");
            }
            println!(
                "collected {} runs ({} not converged) into {}; plots: {}",
                c.runs,
                c.failures.len(),
                c.csv.display(),
                c.plots
            );
            Ok(c.failures.is_empty())
        }
    }
}

fn execute(command: Command) -> asperity::Result<()> {
    match command {
        Command::Run { case, out } => {
            let parsed = Case::from_file(&case)?;
            let out_dir = out
                .or_else(|| parsed.output.dir.as_ref().map(|d| parsed.resolve(d)))
                .unwrap_or_else(|| PathBuf::from("out").join(case.file_stem().unwrap_or_default()));
            let progress = std::io::IsTerminal::is_terminal(&std::io::stderr());
            let summary = pipeline::run(&parsed, &out_dir, progress)?;
            println!("{summary}");
        }
        Command::Converge { .. } => unreachable!("handled by converge_command"),
        Command::Fit { .. } | Command::Sweep { .. } => unreachable!("handled by fit_or_sweep"),
        Command::MeshInfo { file } => {
            let mesh = msh::read_msh(&file)?;
            println!("{}", msh::describe(&mesh));
        }
    }
    Ok(())
}
