//! `asperity`: the command-line front end. All work is done by the library; this file only
//! parses arguments, sets up logging and prints results.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use asperity::case::Case;
use asperity::mesh::msh;
use asperity::pipeline;

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
    match execute(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
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
        Command::MeshInfo { file } => {
            let mesh = msh::read_msh(&file)?;
            println!("{}", msh::describe(&mesh));
        }
    }
    Ok(())
}
