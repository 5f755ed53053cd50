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
        /// Output folder (default: the case's [output] dir, else out/<case name> next to the
        /// case file).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Replace the results of an earlier run in the output folder (only the files a run
        /// writes are removed).
        #[arg(long, conflicts_with = "resume")]
        force: bool,
        /// Continue the run in the output folder from its last converged increment.
        #[arg(long)]
        resume: bool,
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
    /// Describe a gmsh MSH 4.1 file: physical groups, element counts and types, problems.
    MeshInfo {
        /// The mesh file.
        file: PathBuf,
    },
}

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
            // A study that cannot run keeps its documented 2 (README "Exit codes") until its
            // callers move to the shared codes of `Error::exit_code`.
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(2)
            }
        };
    }
    match execute(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        // README "Exit codes": one mapping for every subcommand, in the library.
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
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

fn execute(command: Command) -> asperity::Result<()> {
    match command {
        Command::Run {
            case,
            out,
            force,
            resume,
        } => {
            let parsed = Case::from_file(&case)?;
            let out_dir = out.unwrap_or_else(|| pipeline::default_out_dir(&parsed));
            let options = pipeline::RunOptions {
                progress: std::io::IsTerminal::is_terminal(&std::io::stderr()),
                mode: pipeline::OutputMode::from_flags(force, resume),
                command_line: std::env::args().collect(),
            };
            let summary = pipeline::run_with(&parsed, &out_dir, &options)?;
            println!("{summary}");
        }
        Command::Converge { .. } => unreachable!("handled by converge_command"),
        Command::MeshInfo { file } => {
            let mesh = msh::read_msh(&file)?;
            println!("{}", msh::describe(&mesh));
        }
    }
    Ok(())
}
