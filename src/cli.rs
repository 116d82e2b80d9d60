//! Commands: argument parsing and the turning of library results into output
//! and exit codes.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};

use crate::bench::{
    self, BalanceBenchOptions, KernelBenchOptions, MdBenchOptions, StudySettings,
    WorkPrecisionOptions,
};
use ternary::config::{MAX_GAS_DENSITY, MAX_RING_ENCOUNTERS, SlurmConfig, Study, compact};
use ternary::export::{self, ExportOptions};
use ternary::physics::potential::{InversePower, LennardJones, Potential};
use ternary::physics::units::{Mass, PhysicalGas, ring_density_per_um};
use ternary::pipeline::Stage;
use ternary::pipeline::executor::{self, Action, Freshness, RunOptions, Verbosity};
use ternary::pipeline::shards::Sharding;
use ternary::pipeline::store::Store;
use ternary::report::DagFormat;
use ternary::slurm::{self, SubmitOptions};
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
    /// Execute the stale part of the DAG and print a_n, the paper table and
    /// where the figures are (`--details`: every instance and every table).
    Run {
        /// Run only instances of this stage (repeatable).
        #[arg(long, value_name = "STAGE")]
        only: Vec<String>,
        /// Recompute instances of this stage even when fresh (repeatable).
        #[arg(long, value_name = "STAGE")]
        force: Vec<String>,
        /// Worker threads (default: all cores; at most 4 per core). Results do not depend on it.
        #[arg(long, value_name = "N")]
        threads: Option<usize>,
        /// Print only errors.
        #[arg(long)]
        quiet: bool,
        /// Also print a line for every fresh instance and, after the summary,
        /// the per-stage tables (gases, convergence, evolution, MD, scans, balance).
        #[arg(long, conflicts_with = "quiet")]
        details: bool,
        /// Split shardable stages (collisions) into N shards, computing
        /// missing shards and merging them (same bytes as unsharded).
        #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
        shards: u32,
        /// Compute only shard K of N of every shardable instance, nothing else
        /// (one task of a Slurm array).
        #[arg(long, value_name = "K", requires = "shards")]
        shard: Option<u32>,
        /// Start even when the study's estimated CPU time or store size
        /// exceeds `[limits]`.
        #[arg(long)]
        i_know: bool,
    },
    /// Show each stage instance as fresh, stale, damaged or missing, and why,
    /// after a one-line count of each.
    Status {
        /// Also show which of N shards of each shardable instance are done.
        #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
        shards: u32,
        /// List only the instances that are not fresh (what `run` would compute).
        #[arg(long)]
        changed: bool,
        /// Exit with status 1 when any instance is not fresh (0 when all are),
        /// as `dvc status` does in scripts.
        #[arg(long)]
        check: bool,
    },
    /// Print the DAG of stage instances (or of stages), as text, Graphviz or Mermaid.
    Dag {
        /// Graphviz `digraph` (draw it with `dot -Tsvg`).
        #[arg(long, conflicts_with = "mermaid")]
        dot: bool,
        /// Mermaid flowchart (renders in Markdown on GitHub and GitLab).
        #[arg(long)]
        mermaid: bool,
        /// One node per stage with its instance count, instead of one per instance.
        #[arg(long)]
        stages: bool,
    },
    /// Check every artifact to the bottom (or an exported bundle); exit non-zero on any problem.
    Verify {
        /// Check the exported bundle in this directory instead of the store.
        #[arg(long, value_name = "DIR", conflicts_with_all = ["recompute", "only"])]
        bundle: Option<PathBuf>,
        /// Recompute the current artifacts in memory from their stored inputs
        /// and compare their bytes with the stored ones under the same key.
        #[arg(long)]
        recompute: bool,
        /// With --recompute: only this stage's instances (repeatable).
        #[arg(long, value_name = "STAGE", requires = "recompute")]
        only: Vec<String>,
    },
    /// Write the study's current artifacts as a citable dataset bundle.
    Export {
        /// The bundle directory (new or empty).
        dir: PathBuf,
        /// Export only this stage's tables (repeatable).
        #[arg(long, value_name = "STAGE")]
        stage: Vec<String>,
        /// Export only this potential's tables, plus the study-wide ones (repeatable).
        #[arg(long, value_name = "ID")]
        potential: Vec<String>,
        /// Include the scene tables of the collisions stage (large).
        #[arg(long)]
        include_events: bool,
    },
    /// Write the study as a static HTML page (tables, figures with captions,
    /// each stage's instances with keys and times, provenance) into DIR.
    Report {
        /// The report's directory: `index.html` and its `figures/` (created
        /// when missing; the store is only read).
        #[arg(default_value = "report")]
        dir: PathBuf,
    },
    /// Remove artifacts that no stage instance of the current study references.
    Gc,
    /// Show a stage's instances and files, or an artifact or Parquet file: metadata and first rows.
    Show {
        /// A stage (lists its current instances with keys and files), an
        /// instance `stage[instance]` as `status` names it, an artifact key (or
        /// a unique prefix of at least 6 characters) or a path.
        target: String,
        /// Rows to print per table.
        #[arg(long, default_value_t = 10)]
        rows: usize,
    },
    /// Run the shardable stages as a Slurm array job, then merge and run the rest.
    Slurm {
        #[command(subcommand)]
        which: SlurmCommand,
    },
    /// Benchmarks (not tests); results go to docs/benchmarks.md.
    Bench {
        #[command(subcommand)]
        which: BenchCommand,
    },
}

#[derive(Subcommand)]
enum SlurmCommand {
    /// Submit an array job (one task per missing shard) and a dependent merge job.
    /// Each option overrides its `[slurm]` key.
    Submit {
        /// Shards per shardable instance (array tasks), in [2, 4096] (`[slurm] shards`, 8).
        #[arg(long, value_name = "N")]
        shards: Option<u32>,
        /// CPUs of each job, also its run's `--threads`.
        #[arg(long, value_name = "N")]
        cpus_per_task: Option<u32>,
        /// Memory of each job (e.g. 4000, 500M, 16G).
        #[arg(long, value_name = "SIZE")]
        mem: Option<String>,
        /// Slurm account charged.
        #[arg(long)]
        account: Option<String>,
        /// Slurm partition (several separated by commas).
        #[arg(long)]
        partition: Option<String>,
        /// Slurm quality of service.
        #[arg(long)]
        qos: Option<String>,
        /// Time limit of each shard task (e.g. 2:00:00).
        #[arg(long)]
        time: Option<String>,
        /// Time limit of the merge job (default: --time).
        #[arg(long, value_name = "TIME")]
        merge_time: Option<String>,
        /// Most array tasks running at once.
        #[arg(long, value_name = "K")]
        max_parallel: Option<u32>,
        /// A further sbatch option for both jobs, as `--sbatch-arg=--exclusive`
        /// (repeatable; replaces `[slurm] sbatch_args`).
        #[arg(long, value_name = "OPTION", allow_hyphen_values = true)]
        sbatch_arg: Vec<String>,
        /// Print the scripts instead of submitting them (creates nothing).
        #[arg(long)]
        dry_run: bool,
        /// Submit even when the study's estimate exceeds `[limits]` (the
        /// jobs' runs get `--i-know` too).
        #[arg(long)]
        i_know: bool,
    },
}

#[derive(Subcommand)]
enum BenchCommand {
    /// Work-precision of the integrators on thermally sampled scenes.
    Integrators {
        /// Potential exponent n of U = x^-n, in (1, 100].
        #[arg(long, default_value_t = 6.0, value_parser = exponent)]
        n: f64,
        /// Thermal scenes per measurement, 1 to 1000000.
        #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
        scenes: u32,
        /// Seed of the scene sample.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Also draw the work-precision figure (SVG, PNG) into this directory.
        #[arg(long, value_name = "DIR")]
        figures: Option<PathBuf>,
    },
    /// Precision of a_n and of the kernel per CPU second: what each sampling measure gains.
    Kernel {
        /// Potential exponent n of U = x^-n, in (1, 100].
        #[arg(long, default_value_t = 6.0, value_parser = exponent)]
        n: f64,
        /// Lennard-Jones at theta = kT/eps in [1e-3, 1e3] instead of the inverse power law.
        #[arg(long, conflicts_with = "n", value_parser = theta)]
        theta: Option<f64>,
        /// Randomizations (replicates), 2 to 256.
        #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(2..=256))]
        randomizations: u32,
        /// Scenes per randomization in the sampler comparison, 16 to 65536; the
        /// work-precision tables draw 1/4 to 16x as many sampled scenes and
        /// 1/64 to 3x as many quadrature launch pairs (at least 16).
        #[arg(long, default_value_t = 4096, value_parser = clap::value_parser!(u32).range(16..=65536))]
        points: u32,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Also draw the work-precision figure (SVG, PNG) into this directory.
        #[arg(long, value_name = "DIR")]
        figures: Option<PathBuf>,
    },
    /// Detailed balance far from u' = 0 (the paper's pair at -3.00, -2.96): its precision per second for the sweep's scene sets.
    Balance {
        /// Potential exponent n of U = x^-n, in (1, 100].
        #[arg(long, default_value_t = 6.0, value_parser = exponent)]
        n: f64,
        /// Randomizations (replicates), 2 to 256.
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..=256))]
        randomizations: u32,
        /// Velocity a of the pair (v_th), within [-3, 3].
        #[arg(long, default_value_t = -3.0, allow_hyphen_values = true, value_parser = reachable)]
        from: f64,
        /// Separation b - a (v_th), in (0, 0.5].
        #[arg(long, default_value_t = 0.04, value_parser = separation)]
        separation: f64,
        /// Bin width of the two kernels (v_th), from separation / 5e5 (1e6
        /// bins) to the separation (the pair at least one bin apart).
        #[arg(long, default_value_t = 0.005, value_parser = positive)]
        bin_width: f64,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Ring MD: cluster stepping against whole-ring stepping on one run of the published ring.
    Md {
        /// Particles N, 3 to 100000.
        #[arg(long, default_value_t = 161, value_parser = clap::value_parser!(u32).range(3..=100_000))]
        particles: u32,
        /// Ring radius, um (> 0).
        #[arg(long, default_value_t = 51200.0, value_parser = positive)]
        radius_um: f64,
        /// Temperature, eV (> 0).
        #[arg(long, default_value_t = 0.1, value_parser = positive)]
        kt_ev: f64,
        /// Final time, ns (> 0).
        #[arg(long, default_value_t = 12800.0, value_parser = positive)]
        final_time_ns: f64,
        /// Interacting neighbours on each side, 1 to 64.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=64))]
        neighbours: u32,
        /// Seed of the initial state.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

/// A finite number > 0.
fn positive(text: &str) -> Result<f64, String> {
    let value: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(format!("{value} must be a finite number > 0"))
    }
}

/// A detailed-balance separation `b - a` in (0, 0.5] (v_th).
fn separation(text: &str) -> Result<f64, String> {
    let value: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if value > 0.0 && value <= 0.5 {
        Ok(value)
    } else {
        Err(format!("{value} is outside (0, 0.5]"))
    }
}

/// A velocity `u'` within [-3, 3] (the reach of the sweep's launch proposals).
fn reachable(text: &str) -> Result<f64, String> {
    let value: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if (-3.0..=3.0).contains(&value) {
        Ok(value)
    } else {
        Err(format!("{value} is outside [-3, 3]"))
    }
}

/// The settings a benchmark takes from the study at `config`, or the
/// defaults when there is no such file.
fn bench_study(config: &Path) -> Result<StudySettings> {
    let study = config.exists().then(|| Study::load(config)).transpose()?;
    Ok(StudySettings::of(study.as_ref()))
}

/// A Lennard-Jones `theta = kT/eps` the family accepts.
fn theta(text: &str) -> Result<f64, String> {
    let value: f64 = text.parse().map_err(|e| format!("{e}"))?;
    Ok(LennardJones::new(value)?.theta)
}

/// An inverse-power exponent the family accepts.
fn exponent(text: &str) -> Result<f64, String> {
    let value: f64 = text.parse().map_err(|e| format!("{e}"))?;
    Ok(InversePower::new(value)?.n)
}

/// Refuses a bench ring that is not dilute or would take absurdly long, by the
/// bounds the study's `[md]` section has.
fn check_md_bench(options: &MdBenchOptions) -> Result<()> {
    let gas = PhysicalGas {
        l0_um: 1.0,
        eps_ev: 1.0,
        kt_ev: options.kt_ev,
        mass: Mass::ElectronMasses(1.0),
        density_per_um: ring_density_per_um(options.particles as u32, options.radius_um),
    };
    let density = gas.scaled_density(Some(6.0));
    if density > MAX_GAS_DENSITY {
        bail!(
            "--radius-um {} with --particles {} and --kt-ev {} gives rho*l = {density:.3e}, above {MAX_GAS_DENSITY}: the ring is not dilute",
            options.radius_um,
            options.particles,
            options.kt_ev
        );
    }
    let encounters = options.particles as f64
        * gas.density_per_um
        * gas.thermal_speed_um_per_ns()
        * options.final_time_ns;
    if encounters > MAX_RING_ENCOUNTERS {
        bail!(
            "--final-time-ns {:e} gives ~{encounters:.1e} neighbour encounters, more than {MAX_RING_ENCOUNTERS:.0e}",
            options.final_time_ns
        );
    }
    Ok(())
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
/// Writes a benchmark's figure into `dir` when one was asked for, naming the files.
fn write_bench_figure(figure: &bench::BenchFigure, dir: Option<&Path>) -> Result<()> {
    if let Some(dir) = dir {
        for path in figure.write(dir).map_err(anyhow::Error::msg)? {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}

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
    let store = open(&study, opening)?;
    Ok((study, store))
}

/// The study's store, opened as `opening` says.
fn open(study: &Study, opening: Opening) -> Result<Store> {
    let root = study.store_path();
    match opening {
        Opening::Write => Store::open(&root),
        Opening::Existing => Store::open_existing(&root),
        Opening::View => Store::view(&root),
    }
    .with_context(|| format!("opening the store {}", root.display()))
}

/// Refuses a study whose estimated CPU time or store size exceeds `[limits]`
/// (unless `i_know`), before anything is created.
fn within_limits(study: &Study, plan: &[Box<dyn Stage>], i_know: bool) -> Result<()> {
    let costs = executor::estimate(plan);
    let total = report::total_cost(costs.iter().map(|(_, cost)| cost));
    let limits = &study.config.limits;
    let mut beyond = Vec::new();
    if total.cpu_seconds / 3600.0 > limits.cpu_hours {
        beyond.push(format!(
            "~{} CPU-hours > limits.cpu_hours = {}",
            report::hours(total.cpu_seconds),
            compact(limits.cpu_hours)
        ));
    }
    if total.bytes / 1e9 > limits.store_gb {
        beyond.push(format!(
            "~{} of store > limits.store_gb = {}",
            report::size(total.bytes),
            compact(limits.store_gb)
        ));
    }
    if !i_know && !beyond.is_empty() {
        bail!(
            "{}: the study is estimated beyond [limits]: {}; check the counts, or raise [limits] (or run with --i-know)",
            study.file.display(),
            beyond.join(", ")
        );
    }
    Ok(())
}

/// Worker threads per core a run may start (`--threads`): enough to cover
/// waits, few enough that thread start-up stays negligible (5000 threads took
/// 13.5 s for a 0.03 s stage; 100000 never started).
const THREADS_PER_CORE: usize = 4;

fn dispatch(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Run {
            only,
            force,
            threads,
            quiet,
            details,
            shards,
            shard,
            i_know,
        } => {
            if let Some(task) = shard.filter(|&task| task >= shards) {
                bail!("--shard {task} is not below --shards {shards}");
            }
            if let Some(threads) = threads {
                let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
                let limit = THREADS_PER_CORE * cores;
                if threads == 0 || threads > limit {
                    bail!(
                        "--threads {threads}: must be in [1, {limit}] ({THREADS_PER_CORE} per core of the {cores} this process may use; more only cost memory and start-up)"
                    );
                }
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build_global()?;
            }
            let study = Study::load(&cli.config)?;
            let plan = stages::plan(&study);
            within_limits(&study, &plan, i_know)?;
            let store = open(&study, Opening::Write)?;
            let verbosity = if quiet {
                Verbosity::Quiet
            } else if details {
                Verbosity::Detailed
            } else {
                Verbosity::Normal
            };
            let options = RunOptions {
                only,
                force,
                verbosity,
                sharding: Sharding {
                    shards,
                    task: shard,
                },
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
                emit(&report::summary(
                    &store,
                    &reports,
                    study.config.kernel.kick_floor,
                    details,
                )?);
            }
            Ok(ExitCode::SUCCESS)
        }
        Command::Status {
            shards,
            changed,
            check,
        } => {
            let (study, store) = load(&cli.config, Opening::View)?;
            let plan = stages::plan(&study);
            let lines = executor::status(&store, &plan, shards)?;
            emit(&report::status(&lines, shards, changed));
            emit(&report::cost_estimate(&executor::estimate(&plan), &lines));
            let all_fresh = lines.iter().all(|line| line.freshness == Freshness::Fresh);
            Ok(if check && !all_fresh {
                ExitCode::FAILURE
            } else {
                ExitCode::SUCCESS
            })
        }
        Command::Dag {
            dot,
            mermaid,
            stages: by_stage,
        } => {
            let study = Study::load(&cli.config)?;
            let format = if dot {
                DagFormat::Dot
            } else if mermaid {
                DagFormat::Mermaid
            } else {
                DagFormat::Text
            };
            emit(&report::dag(&stages::plan(&study), by_stage, format));
            Ok(ExitCode::SUCCESS)
        }
        Command::Verify {
            bundle,
            recompute,
            only,
        } => {
            let (text, problems) = match bundle {
                Some(dir) => export::verify_bundle(&dir)?,
                None if recompute => {
                    let (study, store) = load(&cli.config, Opening::Existing)?;
                    report::audit(&store, &stages::plan(&study), &only)?
                }
                None => {
                    let (study, store) = load(&cli.config, Opening::Existing)?;
                    report::verify(&store, &stages::plan(&study))?
                }
            };
            emit(&text);
            Ok(if problems == 0 {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            })
        }
        Command::Export {
            dir,
            stage,
            potential,
            include_events,
        } => {
            let (study, store) = load(&cli.config, Opening::Existing)?;
            let options = ExportOptions {
                stages: stage,
                potentials: potential,
                include_events,
            };
            emit(&export::export(
                &study,
                &store,
                &stages::plan(&study),
                &dir,
                &options,
            )?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Report { dir } => {
            let (study, store) = load(&cli.config, Opening::View)?;
            emit(&report::html::write(
                &study,
                &store,
                &stages::plan(&study),
                &dir,
            )?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Gc => {
            let (study, store) = load(&cli.config, Opening::Existing)?;
            emit(&report::gc(&store, &stages::plan(&study))?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Show { target, rows } => {
            let (store, plan) = if Path::new(&target).exists() {
                (None, Vec::new())
            } else {
                let (study, store) = load(&cli.config, Opening::Existing)?;
                (Some(store), stages::plan(&study))
            };
            let (text, problems) = report::show(store.as_ref(), &plan, &target, rows)?;
            emit(&text);
            Ok(if problems == 0 {
                ExitCode::SUCCESS
            } else {
                ExitCode::FAILURE
            })
        }
        Command::Slurm {
            which:
                SlurmCommand::Submit {
                    shards,
                    cpus_per_task,
                    mem,
                    account,
                    partition,
                    qos,
                    time,
                    merge_time,
                    max_parallel,
                    sbatch_arg,
                    dry_run,
                    i_know,
                },
        } => {
            let study = Study::load(&cli.config)?;
            within_limits(&study, &stages::plan(&study), i_know)?;
            // A dry run reads a missing store as empty and creates nothing.
            let store = open(
                &study,
                if dry_run {
                    Opening::View
                } else {
                    Opening::Write
                },
            )?;
            let configured = study.config.slurm.clone();
            let options = SubmitOptions {
                slurm: SlurmConfig {
                    shards: shards.unwrap_or(configured.shards),
                    cpus_per_task: cpus_per_task.or(configured.cpus_per_task),
                    mem: mem.or(configured.mem),
                    account: account.or(configured.account),
                    partition: partition.or(configured.partition),
                    qos: qos.or(configured.qos),
                    time: time.or(configured.time),
                    merge_time: merge_time.or(configured.merge_time),
                    max_parallel: max_parallel.or(configured.max_parallel),
                    sbatch_args: if sbatch_arg.is_empty() {
                        configured.sbatch_args
                    } else {
                        sbatch_arg
                    },
                },
                dry_run,
                i_know,
            };
            emit(&slurm::submit(
                &cli.config,
                &store,
                &stages::plan(&study),
                &options,
            )?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which:
                BenchCommand::Integrators {
                    n,
                    scenes,
                    seed,
                    figures,
                },
        } => {
            let options = WorkPrecisionOptions {
                n,
                scenes: scenes as usize,
                seed,
            };
            let (report, figure) = bench::integrators(&options);
            emit(&report);
            write_bench_figure(&figure, figures.as_deref())?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which:
                BenchCommand::Kernel {
                    n,
                    theta,
                    randomizations,
                    points,
                    seed,
                    figures,
                },
        } => {
            let study = bench_study(&cli.config)?;
            let options = KernelBenchOptions {
                potential: theta.map_or(Potential::inverse_power(n), Potential::lennard_jones),
                randomizations,
                points,
                seed,
                study,
            };
            let (report, figure) = bench::kernel(&options);
            emit(&report);
            write_bench_figure(&figure, figures.as_deref())?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench {
            which:
                BenchCommand::Balance {
                    n,
                    randomizations,
                    from,
                    separation,
                    bin_width,
                    seed,
                },
        } => {
            let narrowest = separation / 5e5;
            if !(narrowest..=separation).contains(&bin_width) {
                bail!(
                    "--bin-width {}: must be in [{}, {}] for --separation {} (the pair at least one bin apart, at most 1e6 bins)",
                    compact(bin_width),
                    compact(narrowest),
                    compact(separation),
                    compact(separation)
                );
            }
            let study = bench_study(&cli.config)?;
            let options = BalanceBenchOptions {
                potential: Potential::inverse_power(n),
                randomizations,
                from,
                separation,
                bin_width,
                seed,
                study,
            };
            emit(&bench::balance(&options));
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
                particles: particles as usize,
                radius_um,
                kt_ev,
                final_time_ns,
                neighbours: neighbours as usize,
                seed,
            };
            check_md_bench(&options)?;
            emit(&bench::md(&options).map_err(anyhow::Error::msg)?);
            Ok(ExitCode::SUCCESS)
        }
    }
}
