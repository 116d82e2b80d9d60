//! Commands: argument parsing and the turning of library results into output
//! and exit codes.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};

use ternary::bench::{self, KernelBenchOptions, MdBenchOptions, WorkPrecisionOptions};
use ternary::config::Study;
use ternary::pipeline::executor::{self, Action, Freshness, RunOptions, Verbosity};
use ternary::pipeline::store::Store;
use ternary::{report, stages};

/// Three-body thermalization of dilute 1D gases: collision kernels, rates and
/// archival Parquet datasets, computed as a content-addressed DAG.
#[derive(Parser)]
#[command(name = "ternary", version, about)]
struct Cli {
    /// The study definition.
    #[arg(long, global = true, default_value = "pipeline.toml")]
    config: PathBuf,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Execute the stale part of the DAG and print the result tables.
    Run {
        /// Run only instances of this stage (repeatable).
        #[arg(long, value_name = "STAGE")]
        only: Vec<String>,
        /// Recompute instances of this stage even when fresh (repeatable).
        #[arg(long, value_name = "STAGE")]
        force: Vec<String>,
        /// Worker threads (default: all cores). Results do not depend on it.
        #[arg(long, value_name = "N")]
        threads: Option<usize>,
        /// Print only errors.
        #[arg(long)]
        quiet: bool,
    },
    /// Show each stage instance as fresh, stale or missing, and why.
    Status,
    /// Print the DAG of stage instances.
    Dag,
    /// Re-hash every artifact; exit non-zero on any mismatch.
    Verify,
    /// Remove artifacts that no stage instance of the current study references.
    Gc,
    /// Show an artifact (key or key prefix) or a Parquet file: metadata and first rows.
    Show {
        /// Artifact key (or a unique prefix of at least 6 characters) or a path.
        target: String,
        /// Rows to print per table.
        #[arg(long, default_value_t = 10)]
        rows: usize,
    },
    /// Benchmarks (not tests); results go to docs/benchmarks.md.
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Work-precision of the integrators on thermally sampled scenes.
    Integrators {
        /// Potential exponent n of U = x^-n.
        #[arg(long, default_value_t = 6.0)]
        n: f64,
        /// Thermal scenes per measurement.
        #[arg(long, default_value_t = 2000)]
        scenes: usize,
        /// Seed of the scene sample.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Precision of a_n and of the kernel per CPU second: what each sampling measure gains.
    Kernel {
        /// Potential exponent n of U = x^-n.
        #[arg(long, default_value_t = 6.0)]
        n: f64,
        /// Randomizations (replicates).
        #[arg(long, default_value_t = 16)]
        randomizations: u32,
        /// Scenes per randomization in the sampler comparison.
        #[arg(long, default_value_t = 4096)]
        points: u32,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Ring MD: cluster stepping against whole-ring stepping on one run of the published ring.
    Md {
        /// Particles N.
        #[arg(long, default_value_t = 161)]
        particles: usize,
        /// Ring radius, um.
        #[arg(long, default_value_t = 51200.0)]
        radius_um: f64,
        /// Temperature, eV.
        #[arg(long, default_value_t = 0.1)]
        kt_ev: f64,
        /// Final time, ns.
        #[arg(long, default_value_t = 12800.0)]
        final_time_ns: f64,
        /// Interacting neighbours on each side.
        #[arg(long, default_value_t = 3)]
        neighbours: usize,
        /// Seed of the initial state.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

/// Runs the command line and maps errors to exit code 1 (2 for usage errors, by clap).
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match dispatch(cli) {
        Ok(code) => code,
        Err(error) => {
            eprintln!("error: {error:#}");
            ExitCode::FAILURE
        }
    }
}

/// Writes command output to stdout; a closed pipe (`ternary show ... | head`)
/// ends the output quietly instead of panicking.
fn emit(text: &str) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if stdout
        .write_all(text.as_bytes())
        .and_then(|()| stdout.flush())
        .is_err()
    {
        std::process::exit(0);
    }
}

/// How a command opens the study's store.
#[derive(Clone, Copy)]
enum Opening {
    /// Create it when missing or empty (`run`).
    Write,
    /// It must exist (`verify`, `gc`, `show`).
    Existing,
    /// A missing store reads as empty (`status`).
    View,
}

fn load(config: &Path, opening: Opening) -> Result<(Study, Store)> {
    let study = Study::load(config)?;
    let root = study.store_path();
    let store = match opening {
        Opening::Write => Store::open(&root),
        Opening::Existing => Store::open_existing(&root),
        Opening::View => Store::view(&root),
    }
    .with_context(|| format!("opening the store {}", root.display()))?;
    Ok((study, store))
}

fn dispatch(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Run {
            only,
            force,
            threads,
            quiet,
        } => {
            if let Some(threads) = threads {
                if threads == 0 {
                    bail!("--threads must be at least 1");
                }
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build_global()?;
            }
            let (study, store) = load(&cli.config, Opening::Write)?;
            let plan = stages::plan(&study);
            let verbosity = if quiet {
                Verbosity::Quiet
            } else {
                Verbosity::Normal
            };
            let options = RunOptions {
                only,
                force,
                verbosity,
            };
            let reports = executor::run(&store, &plan, &options)?;
            let computed = reports
                .iter()
                .filter(|r| matches!(r.action, Action::Computed { .. }))
                .count();
            let fresh = reports.iter().filter(|r| r.action == Action::Fresh).count();
            let skipped = reports
                .iter()
                .filter(|r| r.action == Action::Skipped)
                .count();
            if !quiet {
                emit(&format!(
                    "run: {computed} computed, {fresh} fresh, {skipped} skipped (store {})\n",
                    store.root().display()
                ));
                emit(&report::summary(&store, &reports)?);
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Status => {
            let (study, store) = load(&cli.config, Opening::View)?;
            for line in executor::status(&store, &stages::plan(&study))? {
                let id = line.id;
                let line = match line.freshness {
                    Freshness::Fresh => "fresh".to_string(),
                    Freshness::Stale(reasons) => format!("stale: {}", reasons.join("; ")),
                    Freshness::Damaged(problems) => format!(
                        "damaged: {} (the next run recomputes it)",
                        problems.join("; ")
                    ),
                    Freshness::Missing(reason) => format!("missing: {reason}"),
                };
                emit(&format!("{:<24} {line}\n", id.to_string()));
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Dag => {
            let study = Study::load(&cli.config)?;
            emit(&report::dag(&stages::plan(&study)));
            Ok(ExitCode::SUCCESS)
        }
        Command::Verify => {
            let (study, store) = load(&cli.config, Opening::Existing)?;
            let (text, damaged) = report::verify(&store, &stages::plan(&study))?;
            emit(&text);
            Ok(if damaged == 0 {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            })
        }
        Command::Gc => {
            let (study, store) = load(&cli.config, Opening::Existing)?;
            emit(&report::gc(&store, &stages::plan(&study))?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Show { target, rows } => {
            let store = if Path::new(&target).exists() {
                None
            } else {
                Some(load(&cli.config, Opening::Existing)?.1)
            };
            emit(&report::show(store.as_ref(), &target, rows)?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which: BenchCommand::Integrators { n, scenes, seed },
        } => {
            let options = WorkPrecisionOptions { n, scenes, seed };
            emit(&bench::integrators(&options));
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which:
                BenchCommand::Kernel {
                    n,
                    randomizations,
                    points,
                    seed,
                },
        } => {
            let options = KernelBenchOptions {
                n,
                randomizations,
                points,
                seed,
            };
            emit(&bench::kernel(&options));
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which:
                BenchCommand::Md {
                    particles,
                    radius_um,
                    kt_ev,
                    final_time_ns,
                    neighbours,
                    seed,
                },
        } => {
            let options = MdBenchOptions {
                particles,
                radius_um,
                kt_ev,
                final_time_ns,
                neighbours,
                seed,
            };
            emit(&bench::md(&options));
            Ok(ExitCode::SUCCESS)
        }
    }
}
