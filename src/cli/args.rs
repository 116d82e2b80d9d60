//! The command line's arguments: subcommands, their options and the parsers
//! that check option values.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use ternary::physics::potential::{InversePower, LennardJones};

/// Three-body thermalization of dilute 1D gases: collision kernels, rates and
/// archival Parquet datasets, computed as a content-addressed DAG.
#[derive(Parser)]
#[command(name = "ternary", version, about)]
pub(super) struct Cli {
    /// The study definition.
    #[arg(long, global = true, default_value = "pipeline.toml")]
    pub(super) config: PathBuf,
    #[command(subcommand)]
    pub(super) command: Command,
}

#[derive(Subcommand)]
pub(super) enum Command {
    /// Execute the stale part of the DAG and print a_n, the paper table and
    /// where the figures are (`--details`: every instance and every table).
    Run(RunArgs),
    /// Show each stage instance as fresh, stale, damaged or missing, and why,
    /// after a one-line count of each.
    Status(StatusArgs),
    /// Print the DAG of stage instances (or of stages), as text, Graphviz or Mermaid.
    Dag(DagArgs),
    /// Check every artifact to the bottom (or an exported bundle); exit non-zero on any problem.
    Verify(VerifyArgs),
    /// Write the study's current artifacts as a citable dataset bundle.
    Export(ExportArgs),
    /// Write the study as a static HTML page (tables, figures with captions,
    /// each stage's instances with keys and times, provenance) into DIR.
    Report(ReportArgs),
    /// Remove artifacts that no stage instance of the current study references.
    Gc,
    /// Show a stage's instances and files, or an artifact or Parquet file: metadata and first rows.
    Show(ShowArgs),
    /// Thermalization and recombination rates and times of a Lennard-Jones gas
    /// (a species of the table or given eps, sigma and mass) at a temperature
    /// and density, interpolated in theta = kT/eps from the study's table.
    Rate(RateArgs),
    /// A computed kernel's model G(u' -> u' + du) at given du, each value with
    /// its standard error (the fit stage's kernel_model tables).
    Kernel(KernelArgs),
    /// Bound pairs forming and breaking in equilibrium ring MD, against what
    /// K_b and the dissociation scenes predict (a potential with a well).
    Pairs(PairsArgs),
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
pub(super) enum SlurmCommand {
    /// Submit an array job (one task per missing shard) and a dependent merge job.
    /// Each option overrides its `[slurm]` key.
    Submit(SlurmSubmitArgs),
}

#[derive(Subcommand)]
pub(super) enum BenchCommand {
    /// Work-precision of the integrators on thermally sampled scenes.
    Integrators(BenchIntegratorsArgs),
    /// Precision of a_n and of the kernel per CPU second: what each sampling measure gains.
    Kernel(BenchKernelArgs),
    /// The far kernel (0.01 <= |du| <= 0.05) on the offset quadrature: the launch proposal's slow stratum (shares 0, 1/64, 1/32, 1/16 of each coordinate, speeds below 0.1) at P and 4P pairs.
    FarKernel(BenchFarKernelArgs),
    /// Detailed balance far from u' = 0 (the paper's pair at -3.00, -2.96): its precision per second for the sweep's scene sets.
    Balance(BenchBalanceArgs),
    /// Ring MD: cluster stepping against whole-ring stepping on one run of the published ring.
    Md(BenchMdArgs),
}

/// Arguments of `ternary run`.
#[derive(Args)]
pub(super) struct RunArgs {
    /// Run only instances of this stage (repeatable).
    #[arg(long, value_name = "STAGE")]
    pub(super) only: Vec<String>,
    /// Recompute instances of this stage even when fresh (repeatable).
    #[arg(long, value_name = "STAGE")]
    pub(super) force: Vec<String>,
    /// Worker threads (default: all cores; at most 4 per core). Results do not depend on it.
    #[arg(long, value_name = "N")]
    pub(super) threads: Option<usize>,
    /// Instances computed at once, each with all worker threads: a stage
    /// whose instances cannot fill the cores alone shares them (1: one at a
    /// time, in plan order). Results do not depend on it.
    #[arg(long, value_name = "N", default_value_t = 2,
          value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=64))]
    pub(super) jobs: usize,
    /// Print only errors.
    #[arg(long)]
    pub(super) quiet: bool,
    /// Also print a line for every fresh instance and, after the summary,
    /// the per-stage tables (gases, convergence, evolution, spectra, MD, scans, balance).
    #[arg(long, conflicts_with = "quiet")]
    pub(super) details: bool,
    /// Split shardable stages (collisions) into N shards, computing
    /// missing shards and merging them (same bytes as unsharded).
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub(super) shards: u32,
    /// Compute only shard K of N of every shardable instance, nothing else
    /// (one task of a Slurm array).
    #[arg(long, value_name = "K", requires = "shards")]
    pub(super) shard: Option<u32>,
    /// Start even when the study's estimated CPU time or store size
    /// exceeds `[limits]`.
    #[arg(long)]
    pub(super) i_know: bool,
}

/// Arguments of `ternary status`.
#[derive(Args)]
pub(super) struct StatusArgs {
    /// Also show which of N shards of each shardable instance are done.
    #[arg(long, value_name = "N", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub(super) shards: u32,
    /// List only the instances that are not fresh (what `run` would compute).
    #[arg(long)]
    pub(super) changed: bool,
    /// Exit with status 1 when any instance is not fresh (0 when all are),
    /// as `dvc status` does in scripts.
    #[arg(long)]
    pub(super) check: bool,
    /// Instead of the instances, a line per stage: the estimated CPU time,
    /// and the measured one of its fresh instances against their estimate.
    #[arg(long)]
    pub(super) costs: bool,
}

/// Arguments of `ternary dag`.
#[derive(Args)]
pub(super) struct DagArgs {
    /// Graphviz `digraph` (draw it with `dot -Tsvg`).
    #[arg(long, conflicts_with = "mermaid")]
    pub(super) dot: bool,
    /// Mermaid flowchart (renders in Markdown on GitHub and GitLab).
    #[arg(long)]
    pub(super) mermaid: bool,
    /// One node per stage with its instance count, instead of one per instance.
    #[arg(long)]
    pub(super) stages: bool,
}

/// Arguments of `ternary verify`.
#[derive(Args)]
pub(super) struct VerifyArgs {
    /// Check the exported bundle in this directory instead of the store.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["recompute", "only"])]
    pub(super) bundle: Option<PathBuf>,
    /// Recompute the current artifacts in memory from their stored inputs
    /// and compare their bytes with the stored ones under the same key.
    #[arg(long)]
    pub(super) recompute: bool,
    /// With --recompute: only this stage's instances (repeatable).
    #[arg(long, value_name = "STAGE", requires = "recompute")]
    pub(super) only: Vec<String>,
}

/// Arguments of `ternary export`.
#[derive(Args)]
pub(super) struct ExportArgs {
    /// The bundle directory (new or empty).
    pub(super) dir: PathBuf,
    /// Export only this stage's tables (repeatable).
    #[arg(long, value_name = "STAGE")]
    pub(super) stage: Vec<String>,
    /// Export only this potential's tables, plus the study-wide ones (repeatable).
    #[arg(long, value_name = "ID")]
    pub(super) potential: Vec<String>,
    /// Include the scene tables of the collisions stage (large).
    #[arg(long)]
    pub(super) include_events: bool,
}

/// Arguments of `ternary report`.
#[derive(Args)]
pub(super) struct ReportArgs {
    /// The report's directory: `index.html` and its `figures/` (created
    /// when missing; the store is only read).
    #[arg(default_value = "report")]
    pub(super) dir: PathBuf,
}

/// Arguments of `ternary show`.
#[derive(Args)]
pub(super) struct ShowArgs {
    /// A stage (lists its current instances with keys and files), an
    /// instance `stage[instance]` as `status` names it, an artifact key (or
    /// a unique prefix of at least 6 characters) or a path.
    pub(super) target: String,
    /// Rows to print per table.
    #[arg(long, default_value_t = 10)]
    pub(super) rows: usize,
}

/// Arguments of `ternary rate`.
#[derive(Args)]
pub(super) struct RateArgs {
    /// A species of the Lennard-Jones table: He, Ne, Ar, Kr, Xe, H2, N2, O2, CH4.
    #[arg(long, required_unless_present = "eps_k", conflicts_with_all = ["eps_k", "sigma_angstrom", "mass_amu"])]
    pub(super) species: Option<String>,
    /// The mass of a species' gas: its particle's (the molecule for N2) or
    /// one atom's (of a homonuclear diatomic molecule: the paper's "nitrogen
    /// atom gas").
    #[arg(long, value_enum, default_value_t = MassArg::Particle)]
    pub(super) mass: MassArg,
    /// Well depth eps/k_B of 4 eps ((sigma/d)^12 - (sigma/d)^6), K (with
    /// --sigma-angstrom and --mass-amu, instead of --species).
    #[arg(long, allow_negative_numbers = true, value_parser = positive, requires_all = ["sigma_angstrom", "mass_amu"])]
    pub(super) eps_k: Option<f64>,
    /// sigma, Angstrom.
    #[arg(long, allow_negative_numbers = true, value_parser = positive, requires = "eps_k")]
    pub(super) sigma_angstrom: Option<f64>,
    /// Particle mass, amu.
    #[arg(long, allow_negative_numbers = true, value_parser = positive, requires = "eps_k")]
    pub(super) mass_amu: Option<f64>,
    /// How the well depth eps becomes the eps of U = eps ((l0/d)^12 -
    /// (l0/d)^6): as it is (the paper's N2 example, theta = kT/eps) or 4 eps
    /// (the compilation's own potential, theta = kT/(4 eps)); l0 = sigma.
    #[arg(long, value_enum, default_value_t = ReadingArg::Paper)]
    pub(super) reading: ReadingArg,
    /// Temperature, K.
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub(super) temperature: f64,
    /// Mean spacing of the particles, um (density 1/spacing).
    #[arg(long, allow_negative_numbers = true, value_parser = positive, required_unless_present = "density_per_um", conflicts_with = "density_per_um")]
    pub(super) spacing_um: Option<f64>,
    /// Linear density, particles per um.
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub(super) density_per_um: Option<f64>,
}

/// Arguments of `ternary kernel`.
#[derive(Args)]
pub(super) struct KernelArgs {
    /// The potential by id (e.g. ipp-6, lj-0.8).
    #[arg(long, required_unless_present_any = ["n", "theta"], conflicts_with_all = ["n", "theta"])]
    pub(super) potential: Option<String>,
    /// An inverse power law by its exponent (--n 6 is ipp-6); between the
    /// study's, their models interpolated in 1/n.
    #[arg(long, allow_negative_numbers = true, value_parser = positive, conflicts_with = "theta")]
    pub(super) n: Option<f64>,
    /// Lennard-Jones at theta = kT/eps (--theta 0.8 is lj-0.8); between the
    /// study's, their models interpolated in ln theta.
    #[arg(long, allow_negative_numbers = true, value_parser = positive)]
    pub(super) theta: Option<f64>,
    /// The special particle's velocity u' of a computed kernel, v_th.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub(super) u_prime: f64,
    /// rho l of a computed kernel (0: dilute).
    #[arg(long, default_value_t = 0.0)]
    pub(super) density: f64,
    /// u - u' at which to evaluate, v_th (non-zero; repeat for several).
    #[arg(long, required = true, allow_hyphen_values = true, value_parser = non_zero)]
    pub(super) du: Vec<f64>,
    /// The part of the kernel: the whole, its self part (the special
    /// particle's own velocity) or its bath part (the whole less the self).
    #[arg(long, value_enum, default_value_t = PartArg::Total)]
    pub(super) part: PartArg,
}

/// `--part` of `ternary kernel`.
#[derive(Clone, Copy, ValueEnum)]
pub(super) enum PartArg {
    /// G, self plus bath.
    Total,
    /// G_self.
    #[value(name = "self")]
    SelfPart,
    /// G_bath = G - G_self.
    Bath,
}

/// Arguments of `ternary pairs`.
#[derive(Args)]
pub(super) struct PairsArgs {
    /// A potential of the study whose family has a well, by id (e.g. lj-1).
    #[arg(long)]
    pub(super) potential: String,
    /// Particles on each ring (at least 16).
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(16..=100_000))]
    pub(super) particles: u32,
    /// Linear density, particles per l (l = l0 (eps/kT)^(1/6)).
    #[arg(long, default_value_t = 0.02, allow_negative_numbers = true, value_parser = positive)]
    pub(super) density: f64,
    /// Time each ring is watched, l/v_th (many relaxation times 1/(k_d rho)).
    #[arg(long, default_value_t = 20000.0, allow_negative_numbers = true, value_parser = positive)]
    pub(super) duration: f64,
    /// Time between two counts of the bound pairs, l/v_th.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true, value_parser = positive)]
    pub(super) interval: f64,
    /// The fit of the count's autocorrelation starts at this lag, l/v_th
    /// (past the collisions in progress: a few l/v_th).
    #[arg(long, default_value_t = 20.0, allow_negative_numbers = true, value_parser = positive)]
    pub(super) fit_from: f64,
    /// Integrator tolerance of the rings (1e-6 and 1e-8 gave the same rates
    /// at theta = 1; [md]'s 1e-10 costs 2x more than 1e-8).
    #[arg(long, default_value_t = 1e-8, allow_negative_numbers = true, value_parser = positive)]
    pub(super) tolerance: f64,
    /// Independent rings (at least 2, for the errors).
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(2..=100_000))]
    pub(super) runs: u32,
    /// Seed of the rings' initial states.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
}

/// `--mass` of `ternary rate`.
#[derive(Clone, Copy, ValueEnum)]
pub(super) enum MassArg {
    /// The particle the parameters describe (atom or molecule).
    Particle,
    /// One atom of a homonuclear diatomic molecule.
    Atom,
}

/// `--reading` of `ternary rate`.
#[derive(Clone, Copy, ValueEnum)]
pub(super) enum ReadingArg {
    /// eps = the table's well depth (the paper's N2 example).
    Paper,
    /// eps = 4 x the table's well depth (the 4 eps form itself).
    FourEps,
}

/// Arguments of `ternary slurm submit`.
#[derive(Args)]
pub(super) struct SlurmSubmitArgs {
    /// Shards per shardable instance (array tasks), in [2, 4096] (`[slurm] shards`, 8).
    #[arg(long, value_name = "N")]
    pub(super) shards: Option<u32>,
    /// CPUs of each job, also its run's `--threads`.
    #[arg(long, value_name = "N")]
    pub(super) cpus_per_task: Option<u32>,
    /// Memory of each job (e.g. 4000, 500M, 16G).
    #[arg(long, value_name = "SIZE")]
    pub(super) mem: Option<String>,
    /// Slurm account charged.
    #[arg(long)]
    pub(super) account: Option<String>,
    /// Slurm partition (several separated by commas).
    #[arg(long)]
    pub(super) partition: Option<String>,
    /// Slurm quality of service.
    #[arg(long)]
    pub(super) qos: Option<String>,
    /// Time limit of each shard task (e.g. 2:00:00).
    #[arg(long)]
    pub(super) time: Option<String>,
    /// Time limit of the merge job (default: --time).
    #[arg(long, value_name = "TIME")]
    pub(super) merge_time: Option<String>,
    /// Most array tasks running at once.
    #[arg(long, value_name = "K")]
    pub(super) max_parallel: Option<u32>,
    /// A further sbatch option for both jobs, as `--sbatch-arg=--exclusive`
    /// (repeatable; replaces `[slurm] sbatch_args`).
    #[arg(long, value_name = "OPTION", allow_hyphen_values = true)]
    pub(super) sbatch_arg: Vec<String>,
    /// Print the scripts instead of submitting them (creates nothing).
    #[arg(long)]
    pub(super) dry_run: bool,
    /// Submit even when the study's estimate exceeds `[limits]` (the
    /// jobs' runs get `--i-know` too).
    #[arg(long)]
    pub(super) i_know: bool,
}

/// Arguments of `ternary bench integrators`.
#[derive(Args)]
pub(super) struct BenchIntegratorsArgs {
    /// Potential exponent n of U = x^-n, in (1, 100].
    #[arg(long, default_value_t = 6.0, value_parser = exponent)]
    pub(super) n: f64,
    /// Thermal scenes per measurement, 1 to 1000000.
    #[arg(long, default_value_t = 2000, value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub(super) scenes: u32,
    /// Seed of the scene sample.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
    /// Also draw the work-precision figure (SVG, PNG) into this directory.
    #[arg(long, value_name = "DIR")]
    pub(super) figures: Option<PathBuf>,
}

/// Arguments of `ternary bench kernel`.
#[derive(Args)]
pub(super) struct BenchKernelArgs {
    /// Potential exponent n of U = x^-n, in (1, 100].
    #[arg(long, default_value_t = 6.0, value_parser = exponent)]
    pub(super) n: f64,
    /// Lennard-Jones at theta = kT/eps in [1e-3, 1e3] instead of the inverse power law.
    #[arg(long, conflicts_with = "n", value_parser = theta)]
    pub(super) theta: Option<f64>,
    /// Randomizations (replicates), 2 to 256.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(2..=256))]
    pub(super) randomizations: u32,
    /// Scenes per randomization in the sampler comparison, 16 to 65536; the
    /// work-precision tables draw 1/4 to 16x as many sampled scenes and
    /// 1/64 to 3x as many quadrature launch pairs (at least 16).
    #[arg(long, default_value_t = 4096, value_parser = clap::value_parser!(u32).range(16..=65536))]
    pub(super) points: u32,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
    /// Also draw the work-precision figure (SVG, PNG) into this directory.
    #[arg(long, value_name = "DIR")]
    pub(super) figures: Option<PathBuf>,
}

/// Arguments of `ternary bench far-kernel`.
#[derive(Args)]
pub(super) struct BenchFarKernelArgs {
    /// Potential exponent n of U = x^-n, in (1, 100].
    #[arg(long, default_value_t = 6.0, value_parser = exponent)]
    pub(super) n: f64,
    /// Randomizations (replicates), 2 to 256.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(2..=256))]
    pub(super) randomizations: u32,
    /// Launch pairs per randomization of the smaller runs (the larger take 4x), 16 to 16384.
    #[arg(long, default_value_t = 1024, value_parser = clap::value_parser!(u32).range(16..=16384))]
    pub(super) pairs: u32,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
}

/// Arguments of `ternary bench balance`.
#[derive(Args)]
pub(super) struct BenchBalanceArgs {
    /// Potential exponent n of U = x^-n, in (1, 100].
    #[arg(long, default_value_t = 6.0, value_parser = exponent)]
    pub(super) n: f64,
    /// Randomizations (replicates), 2 to 256.
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(2..=256))]
    pub(super) randomizations: u32,
    /// Velocity a of the pair (v_th), within [-3, 3].
    #[arg(long, default_value_t = -3.0, allow_hyphen_values = true, value_parser = reachable)]
    pub(super) from: f64,
    /// Separation b - a (v_th), in (0, 0.5].
    #[arg(long, default_value_t = 0.04, value_parser = separation)]
    pub(super) separation: f64,
    /// Bin width of the two kernels (v_th), from separation / 5e5 (1e6
    /// bins) to the separation (the pair at least one bin apart).
    #[arg(long, default_value_t = 0.005, allow_negative_numbers = true, value_parser = positive)]
    pub(super) bin_width: f64,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
}

/// Arguments of `ternary bench md`.
#[derive(Args)]
pub(super) struct BenchMdArgs {
    /// Particles N, 3 to 100000.
    #[arg(long, default_value_t = 161, value_parser = clap::value_parser!(u32).range(3..=100_000))]
    pub(super) particles: u32,
    /// Ring radius, um (> 0).
    #[arg(long, default_value_t = 51200.0, allow_negative_numbers = true, value_parser = positive)]
    pub(super) radius_um: f64,
    /// Temperature, eV (> 0).
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true, value_parser = positive)]
    pub(super) kt_ev: f64,
    /// Final time, ns (> 0).
    #[arg(long, default_value_t = 12800.0, allow_negative_numbers = true, value_parser = positive)]
    pub(super) final_time_ns: f64,
    /// Interacting neighbours on each side, 1 to 64.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub(super) neighbours: u32,
    /// Seed of the initial state.
    #[arg(long, default_value_t = 1)]
    pub(super) seed: u64,
}

/// A finite number > 0.
fn non_zero(text: &str) -> Result<f64, String> {
    let value: f64 = text.parse().map_err(|e| format!("{e}"))?;
    if value.is_finite() && value != 0.0 {
        Ok(value)
    } else {
        Err(format!(
            "{value} must be a finite number other than 0 (u' itself has no kernel value: G diverges there)"
        ))
    }
}

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
