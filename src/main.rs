//! `asperity`: the command-line front end. All work is done by the library; this file only
//! parses arguments, sets up logging and prints results.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use tracing_subscriber::filter::LevelFilter;
use tracing_subscriber::prelude::*;

use asperity::config::{Case, QuantitySpec};
use asperity::mesh::msh;
use asperity::model::{Model, ModelSpec};
use asperity::output::summary::ModelReport;
use asperity::run;
use asperity::run::folder::{OutputFolder, OutputMode};
use asperity::run::progress::{LogFile, LogToStderr};
use asperity::study;

/// Limits glibc's malloc to two arenas, the main thread's and one that all other threads
/// share, unless `MALLOC_ARENA_MAX` says otherwise. With glibc's default of an arena per
/// thread (up to 8 per core), memory that the output writer or a rayon worker allocated and
/// freed stays in that thread's arena, out of the others' reach, and the peak grows:
/// measured on the tapered press fit, 45 MB more at 1M unknowns and 180–230 MB more at 3.8M
/// (BENCHMARKS.md, "First touches"); run times the same. One arena saved 95 MB at 1M but
/// cost 0.3 s there. Called before any thread starts.
fn two_malloc_arenas() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_ARENA_MAX").is_none() {
        // SAFETY: mallopt only changes a malloc parameter; no other thread runs yet.
        unsafe {
            libc::mallopt(libc::M_ARENA_MAX, 2);
        }
    }
}

/// The exit codes, for `--help` and the man page (docs/guide/troubleshooting.md explains each).
const EXIT_STATUS: &str = "Exit status: 0 success; 1 did not converge (or a fit parameter not \
    identified, a converge quantity that fails its check); 2 usage or an output folder holding \
    an earlier run; 3 bad input (case, mesh, model); 4 a file that cannot be read or written; \
    5 limit load (plastic collapse, friction capacity exceeded, loss of support); 130 \
    interrupted (continue with --resume). The guide: docs/guide/ in the repository.";

/// Finite-element analysis of 2D plane and axisymmetric contact with interface compliance
/// and friction (Buczkowski & Kleiber 1994). Units: mm, N, MPa.
#[derive(Parser)]
#[command(version, about, after_long_help = EXIT_STATUS)]
struct Cli {
    /// More log output on stderr: -v adds debug lines (Newton iterations, timings), -vv
    /// trace lines. Without it: one INFO line per increment and warnings.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    /// Only warnings and errors on stderr (log.txt keeps the INFO lines).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
    /// Worker threads of the assembly and the sparse solvers (rayon's pool, which faer uses
    /// too; default: one per core; at most 4 per core this process may use).
    #[arg(long, global = true, value_name = "N", value_parser = thread_count)]
    threads: Option<u16>,
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
        /// Number of mesh levels (3 to 20).
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
    /// Fit interface-law parameters to measured joint curves (Levenberg–Marquardt from several
    /// starts): values, verdicts and profile 95 % intervals, standard errors, correlations,
    /// plots, fit.json and a `law = {...}` line. Exit status 1 when a free parameter is not
    /// identified (the data bound it on one side only, or not at all).
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
    /// Check a case without solving: read and validate it, mesh its .geo (in a temporary
    /// folder) or read its .msh, build the model and print what it contains.
    Check {
        /// The case file (TOML).
        case: PathBuf,
    },
    /// Write a commented template case and its gmsh script (a block pressed onto a
    /// foundation, with friction) into DIR; they run as they are. Existing files are never
    /// overwritten.
    Init {
        /// Target folder (created if missing).
        #[arg(default_value = ".")]
        dir: PathBuf,
    },
    /// Print the JSON schema of the case file (for editors: completion and validation of
    /// case files, e.g. with Taplo or Even Better TOML).
    Schema {
        /// Print the case-file reference as Markdown instead (docs/guide/case-file.md is
        /// this page).
        #[arg(long)]
        markdown: bool,
    },
    /// Print the shell completion script for SHELL (e.g. `asperity completions bash >
    /// ~/.local/share/bash-completion/completions/asperity`).
    Completions {
        /// The shell: bash, zsh, fish, elvish or powershell.
        shell: clap_complete::Shell,
    },
    /// Print the man page (roff) on standard output, or with --out write asperity.1 and one
    /// page per subcommand (asperity-run.1, ...) into DIR.
    Man {
        /// Folder for the pages (created if missing), e.g. /usr/local/share/man/man1. Earlier
        /// pages of asperity's are replaced; a file of another origin (or a symbolic link)
        /// under a page's name is refused before any page is written.
        #[arg(long)]
        out: Option<PathBuf>,
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

/// Sets up logging: stderr at the level of `-q`/`-v` (ANSI colours only on a terminal, so
/// piped and redirected logs stay plain text) and the returned `log.txt` sink at INFO or
/// more. Both print the spans an event is in (e.g. `step{step=3}:`), so Newton iteration
/// lines carry their step.
fn init_logging(cli: &Cli) -> LogFile {
    let level = match (cli.quiet, cli.verbose) {
        (true, _) => LevelFilter::WARN,
        (false, 0) => LevelFilter::INFO,
        (false, 1) => LevelFilter::DEBUG,
        (false, _) => LevelFilter::TRACE,
    };
    let log_file = LogFile::default();
    let stderr = tracing_subscriber::fmt::layer()
        .with_writer(|| LogToStderr)
        .with_ansi(std::io::stderr().is_terminal())
        .with_target(false)
        .with_filter(level);
    let file = tracing_subscriber::fmt::layer()
        .with_writer(log_file.clone())
        .with_ansi(false)
        .with_target(false)
        .with_filter(level.max(LevelFilter::INFO));
    tracing_subscriber::registry()
        .with(stderr)
        .with(file)
        .init();
    log_file
}

/// The first Ctrl-C (or SIGTERM, SIGHUP: a cluster's time limit, a closed terminal) asks the
/// run to stop after its current increment, keeping its converged steps and writing its
/// summary; a second one ends the process at once.
fn stop_cleanly_on_signals() {
    let handler = || {
        if run::progress::request_stop() {
            std::process::exit(130);
        }
        tracing::warn!(
            "stopping after the current increment (its files complete); press Ctrl-C again to \
             stop at once"
        );
    };
    if let Err(e) = ctrlc::set_handler(handler) {
        tracing::warn!("cannot catch Ctrl-C ({e}): it will stop the run at once");
    }
}

/// The most `--threads` per core the process may use.
const THREADS_PER_CORE: usize = 4;

/// `--threads N`: from 1 to [`THREADS_PER_CORE`] per core this process may use (more
/// threads than cores only wait for each other: 2000 made a 0.4 s run take 9 s).
fn thread_count(text: &str) -> Result<u16, String> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let most = (THREADS_PER_CORE * cores).min(usize::from(u16::MAX));
    match text.parse::<usize>() {
        Ok(n) if (1..=most).contains(&n) => Ok(n as u16),
        _ => Err(format!(
            "give 1 to {most} threads ({THREADS_PER_CORE} per core, {cores} cores)"
        )),
    }
}

/// Sizes rayon's global pool, which the assembly, the study's levels and faer's solvers
/// (`Par::rayon(0)`: as many threads as the pool has) all run on.
fn init_threads(threads: Option<u16>) -> asperity::Result<()> {
    let Some(n) = threads else { return Ok(()) };
    rayon::ThreadPoolBuilder::new()
        .num_threads(n.into())
        .build_global()
        .map_err(|e| asperity::Error::Case {
            path: PathBuf::from("--threads"),
            message: format!("cannot start {n} threads: {e}"),
        })
}

/// The man page of `command` and of each of its subcommands (not hidden), as
/// `clap_mangen::generate_to` names them (`asperity.1`, `asperity-run.1`, ...), in memory.
fn man_pages(command: clap::Command) -> std::io::Result<Vec<(String, Vec<u8>)>> {
    let mut pages = Vec::new();
    for sub in command.get_subcommands().filter(|s| !s.is_hide_set()) {
        pages.extend(man_pages(sub.clone())?);
    }
    let man = clap_mangen::Man::new(command);
    let mut page = Vec::new();
    man.render(&mut page)?;
    pages.push((man.get_filename(), page));
    Ok(pages)
}

/// `println!` for the command's results on standard output: when the reader has gone (a
/// closed pipe, as in `asperity mesh-info m.msh | head -1`), the command ends quietly, as
/// Unix tools do, instead of panicking.
macro_rules! say {
    ($($arg:tt)*) => {
        write_stdout(format_args!($($arg)*))
    };
}

fn write_stdout(text: std::fmt::Arguments) {
    if let Err(e) = writeln!(std::io::stdout().lock(), "{text}") {
        if e.kind() == std::io::ErrorKind::BrokenPipe {
            std::process::exit(0);
        }
        eprintln!("error: cannot write to standard output: {e}");
        std::process::exit(4);
    }
}

fn main() -> ExitCode {
    two_malloc_arenas();
    let cli = Cli::parse();
    let log_file = init_logging(&cli);
    if let Err(e) = init_threads(cli.threads) {
        eprintln!("error: {}", e.readable());
        return ExitCode::from(e.exit_code());
    }
    if let Command::Converge { .. } = cli.command {
        return match converge_command(cli.command) {
            Ok(code) => code,
            // A study that cannot run keeps its documented 2 (docs/guide/troubleshooting.md) until its
            // callers move to the shared codes of `Error::exit_code`.
            Err(e) => {
                eprintln!("error: {}", e.readable());
                ExitCode::from(2)
            }
        };
    }
    if let Command::Fit { .. } | Command::Sweep { .. } = cli.command {
        return match fit_or_sweep(cli.command) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => ExitCode::FAILURE,
            Err(e) => {
                eprintln!("error: {}", e.readable());
                ExitCode::from(e.exit_code())
            }
        };
    }
    match execute(cli.command, &log_file) {
        Ok(()) => ExitCode::SUCCESS,
        // Exit codes (docs/guide/troubleshooting.md): one mapping for every subcommand, in the library.
        Err(e) => {
            eprintln!("error: {}", e.readable());
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
    say!("{report}");
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
            let out = out.unwrap_or_else(|| default_out("fit", &file));
            let fit = asperity::fit::Fit::from_file(&file)?;
            asperity::fit::check_folder(&out)?;
            let result = fit.run()?;
            let plots = asperity::fit::write(&result, &out, !no_plot)?;
            say!("{result}");
            say!(
                "results: {} (fit.json, curves.csv, law.toml); plots: {plots}",
                out.display()
            );
            // Warnings are diagnostics: standard error, so that the results can be piped.
            for w in &result.warnings {
                eprintln!("warning: {w}");
            }
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
            say!(
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
            stop_cleanly_on_signals();
            if !sweep::run_task(&study, k, retry_failed)? {
                say!("run {k}: done before, skipped");
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
            say!(
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
            say!(
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

/// `asperity check`: everything a run does before its first step (the case, the mesh, the
/// model), and the model's description. A `.geo` script is meshed into a temporary folder.
fn check(case: &Path) -> asperity::Result<String> {
    let parsed = Case::from_file(case)?;
    let spec = ModelSpec::new(&parsed)?;
    let scratch = tempfile::tempdir().map_err(|e| asperity::Error::io(std::env::temp_dir(), e))?;
    let mesh = run::load_mesh(&parsed, &OutputFolder::scratch(scratch.path())?)?.0;
    let model = Model::build(mesh, spec)?;
    run::check_history_of(&parsed, &model)?;
    Ok(format!(
        "{}\ncase {}: ok",
        ModelReport(&model),
        case.display()
    ))
}

fn execute(command: Command, log_file: &LogFile) -> asperity::Result<()> {
    match command {
        Command::Run {
            case,
            out,
            force,
            resume,
        } => {
            let parsed = Case::from_file(&case)?;
            let out_dir = out.unwrap_or_else(|| run::default_out_dir(&parsed));
            let options = run::RunOptions {
                progress: std::io::IsTerminal::is_terminal(&std::io::stderr()),
                mode: OutputMode::from_flags(force, resume),
                command_line: std::env::args().collect(),
            };
            // log.txt belongs to the run: opened once the folder is the run's (after the
            // refusal of an earlier run's results, or their removal by --force).
            stop_cleanly_on_signals();
            let summary = run::run_with(&parsed, &out_dir, &options, |folder| {
                log_file.open(folder, folder.resumable())
            })?;
            say!("{summary}");
        }
        Command::Converge { .. } => unreachable!("handled by converge_command"),
        Command::Fit { .. } | Command::Sweep { .. } => unreachable!("handled by fit_or_sweep"),
        Command::MeshInfo { file } => {
            let mesh = msh::read_msh(&file)?;
            let distorted = asperity::element::kinematics::distorted_cells(&mesh);
            say!("{}", msh::describe(&mesh, &distorted));
        }
        Command::Check { case } => say!("{}", check(&case)?),
        Command::Init { dir } => {
            for path in asperity::init::write_templates(&dir)? {
                say!("wrote {}", path.display());
            }
            say!(
                "run it with: asperity run {}",
                dir.join(asperity::init::TEMPLATES[0].0).display()
            );
        }
        Command::Schema { markdown: false } => {
            let schema = asperity::reference::case_schema();
            let text = serde_json::to_string_pretty(&schema).expect("a schema is valid JSON");
            say!("{text}");
        }
        Command::Schema { markdown: true } => {
            say!("{}", asperity::reference::case_file_markdown().trim_end());
        }
        Command::Completions { shell } => {
            let mut command = <Cli as clap::CommandFactory>::command();
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut command, "asperity", &mut script);
            say!("{}", String::from_utf8_lossy(&script).trim_end());
        }
        Command::Man { out: None } => {
            let mut page = Vec::new();
            clap_mangen::Man::new(<Cli as clap::CommandFactory>::command())
                .render(&mut page)
                .map_err(|e| asperity::Error::io("man page", e))?;
            say!("{}", String::from_utf8_lossy(&page).trim_end());
        }
        Command::Man { out: Some(dir) } => {
            let mut command = <Cli as clap::CommandFactory>::command()
                .name("asperity")
                .disable_help_subcommand(true);
            command.build();
            let pages = man_pages(command).map_err(|e| asperity::Error::io("man page", e))?;
            // An earlier version of a page (its title line names asperity) is replaced.
            let ours = |head: &[u8]| String::from_utf8_lossy(head).contains("\n.TH asperity");
            asperity::output::generated::write_generated(&dir, &pages, ours)?;
            say!("man pages written to {}", dir.display());
        }
    }
    Ok(())
}
