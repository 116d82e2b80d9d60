//! One function per subcommand of the study (`run`, `status`, `dag`,
//! `verify`, `export`, `report`, `gc`, `show`, `rate`, `pairs`, `slurm submit`): each loads
//! what it needs, calls the library and prints its result.

use std::path::Path;
use std::process::ExitCode;

use std::sync::atomic::{AtomicU32, Ordering};

use anyhow::{Context, Result, bail};

use super::args::{
    DagArgs, ExportArgs, KernelArgs, MassArg, PairsArgs, PartArg, RateArgs, ReadingArg, ReportArgs,
    RunArgs, ShowArgs, SlurmSubmitArgs, StatusArgs, VerifyArgs,
};
use super::{Opening, emit, exit_code, load, open, print_event, within_limits};
use ternary::config::{SlurmConfig, Study, compact};
use ternary::contract::instances;
use ternary::export::{self, ExportOptions};
use ternary::kernel::model::{
    Family, POTENTIAL_NODES, Part, U_PRIME_NODES, nearest_nodes, u_prime_nodes,
};
use ternary::physics::dissociation::{dissociation_rate, sobol_dissociation_scenes};
use ternary::physics::md::CLUSTER_STEP_BUDGET;
use ternary::physics::pair_kinetics::{
    KineticsSettings, RelaxationSettings, dense_bound_length, equilibrium_runs, pair_relaxation,
};
use ternary::physics::potential::{LennardJones, Potential};
use ternary::physics::species::{self, MassChoice, Particle, Reading};
use ternary::physics::units::{Mass, PhysicalGas};
use ternary::pipeline::executor::{self, Action, Freshness, RunOptions, Verbosity};
use ternary::pipeline::shards::Sharding;
use ternary::pipeline::{Cost, InstanceId};
use ternary::plan::plan;
use ternary::rates::gas_rates;
use ternary::report::{self, DagFormat};
use ternary::slurm::{self, SubmitOptions};
use ternary::stats::Estimate;

/// Worker threads per core a run may start (`--threads`): enough to cover
/// waits, few enough that thread start-up stays negligible (5000 threads took
/// 13.5 s for a 0.03 s stage; 100000 never started).
const THREADS_PER_CORE: usize = 4;

/// `ternary run`: executes the stale part of the DAG and prints a line per
/// instance as it goes, then the counts and the summary.
pub(super) fn run(config: &Path, args: RunArgs) -> Result<ExitCode> {
    if let Some(task) = args.shard.filter(|&task| task >= args.shards) {
        bail!("--shard {task} is not below --shards {}", args.shards);
    }
    if let Some(threads) = args.threads {
        use_threads(threads)?;
    }
    let study = Study::load(config)?;
    let plan = plan(&study);
    within_limits(&study, &plan, args.i_know)?;
    let store = open(&study, Opening::Write)?;
    let verbosity = if args.quiet {
        Verbosity::Quiet
    } else if args.details {
        Verbosity::Detailed
    } else {
        Verbosity::Normal
    };
    let options = RunOptions {
        only: args.only,
        force: args.force,
        verbosity,
        sharding: Sharding {
            shards: args.shards,
            task: args.shard,
        },
        jobs: args.jobs,
    };
    let reports = executor::run(&store, &plan, &options, &mut print_event)?;
    if !args.quiet {
        let count =
            |wanted: fn(&Action) -> bool| reports.iter().filter(|r| wanted(&r.action)).count();
        let computed = count(|action| matches!(action, Action::Computed { .. }));
        let fresh = count(|action| action == &Action::Fresh);
        let skipped = count(|action| action == &Action::Skipped);
        emit(&format!(
            "run: {computed} computed, {fresh} fresh, {skipped} skipped (store {})\n",
            store.root().display()
        ));
        emit(&report::summary(
            &store,
            &reports,
            study.config.kernel.kick_floor,
            args.details,
        )?);
    }
    Ok(ExitCode::SUCCESS)
}

/// Sizes the global thread pool to `threads` (`--threads`), refusing a count
/// outside [1, [`THREADS_PER_CORE`] per core].
fn use_threads(threads: usize) -> Result<()> {
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
    Ok(())
}

/// `ternary status`: every instance's freshness and the cost estimate;
/// with `--check`, failure when any is not fresh.
pub(super) fn status(config: &Path, args: StatusArgs) -> Result<ExitCode> {
    let (study, store) = load(config, Opening::View)?;
    let plan = plan(&study);
    let lines = executor::status(&store, &plan, args.shards)?;
    let slowness = crate::bench::machine_slowness();
    let costs: Vec<(InstanceId, Cost)> = executor::estimate(&plan)
        .into_iter()
        .map(|(id, cost)| {
            let cpu_seconds = cost.cpu_seconds * slowness;
            (
                id,
                Cost {
                    cpu_seconds,
                    ..cost
                },
            )
        })
        .collect();
    if args.costs {
        emit(&report::costs_by_stage(&costs, &lines));
    } else {
        emit(&report::status(&lines, args.shards, args.changed));
    }
    emit(&report::cost_estimate(&costs, &lines, slowness));
    let all_fresh = lines.iter().all(|line| line.freshness == Freshness::Fresh);
    Ok(exit_code(usize::from(args.check && !all_fresh)))
}

/// `ternary dag`: the plan as text, Graphviz or Mermaid.
pub(super) fn dag(config: &Path, args: DagArgs) -> Result<ExitCode> {
    let study = Study::load(config)?;
    let format = if args.dot {
        DagFormat::Dot
    } else if args.mermaid {
        DagFormat::Mermaid
    } else {
        DagFormat::Text
    };
    emit(&report::dag(&plan(&study), args.stages, format));
    Ok(ExitCode::SUCCESS)
}

/// `ternary verify`: the store (or a bundle) checked, or recomputed with
/// `--recompute` (a line per instance as it is checked).
pub(super) fn verify(config: &Path, args: VerifyArgs) -> Result<ExitCode> {
    let (text, problems) = match args.bundle {
        Some(dir) => export::verify_bundle(&dir)?,
        None if args.recompute => {
            let (study, store) = load(config, Opening::Existing)?;
            report::audit(&store, &plan(&study), &args.only, &mut print_event)?
        }
        None => {
            let (study, store) = load(config, Opening::Existing)?;
            report::verify(&store, &plan(&study))?
        }
    };
    emit(&text);
    Ok(exit_code(problems))
}

/// `ternary export`: the current artifacts as a dataset bundle.
pub(super) fn export(config: &Path, args: ExportArgs) -> Result<ExitCode> {
    let (study, store) = load(config, Opening::Existing)?;
    let options = ExportOptions {
        stages: args.stage,
        potentials: args.potential,
        include_events: args.include_events,
    };
    let plan = plan(&study);
    emit(&export::export(&study, &store, &plan, &args.dir, &options)?);
    Ok(ExitCode::SUCCESS)
}

/// `ternary report`: the study as a static HTML page.
pub(super) fn report(config: &Path, args: ReportArgs) -> Result<ExitCode> {
    let (study, store) = load(config, Opening::View)?;
    let plan = plan(&study);
    emit(&report::html::write(&study, &store, &plan, &args.dir)?);
    Ok(ExitCode::SUCCESS)
}

/// `ternary gc`: removes the artifacts no current instance names.
pub(super) fn gc(config: &Path) -> Result<ExitCode> {
    let (study, store) = load(config, Opening::Existing)?;
    emit(&report::gc(&store, &plan(&study))?);
    Ok(ExitCode::SUCCESS)
}

/// `ternary show`: a stage, instance, artifact or Parquet file.
pub(super) fn show(config: &Path, args: ShowArgs) -> Result<ExitCode> {
    let (store, plan) = if Path::new(&args.target).exists() {
        (None, Vec::new())
    } else {
        let (study, store) = load(config, Opening::Existing)?;
        (Some(store), plan(&study))
    };
    let (text, problems) = report::show(store.as_ref(), &plan, &args.target, args.rows)?;
    emit(&text);
    Ok(exit_code(problems))
}

/// `ternary rate`: a Lennard-Jones gas's rates from the study's theta table.
pub(super) fn rate(config: &Path, args: RateArgs) -> Result<ExitCode> {
    let (gas, description) = rate_gas(&args)?;
    let (study, store) = load(config, Opening::Existing)?;
    let sourced = report::theta_table(&study, &store, &plan(&study))?;
    let rates = gas_rates(&sourced.table, &gas)?;
    emit(&report::rate_text(&description, &rates, &sourced.sources));
    Ok(ExitCode::SUCCESS)
}

/// `ternary kernel`: the model of a kernel the study computed, at given `du`,
/// or between computed ones (`--n`, `--theta`, `--u-prime`) their models
/// interpolated.
pub(super) fn kernel(config: &Path, args: KernelArgs) -> Result<ExitCode> {
    let (study, store) = load(config, Opening::Existing)?;
    let wanted = match (&args.potential, args.n, args.theta) {
        (Some(id), _, _) => id.clone(),
        (None, Some(n), _) => format!("ipp-{n}"),
        (None, None, Some(theta)) => format!("lj-{theta}"),
        (None, None, None) => bail!("give --potential, --n or --theta"),
    };
    let u_primes = u_prime_targets(&study, config, &args)?;
    let potentials = study.potentials();
    let (asked, symbol) = match args.part {
        PartArg::Total => (report::Asked::Modelled(Part::Total), "G"),
        PartArg::SelfPart => (report::Asked::Modelled(Part::SelfPart), "G_self"),
        PartArg::Bath => (report::Asked::Bath, "G_bath"),
    };
    let title = format!(
        "{symbol}(u' -> u' + du) of {wanted}, u' = {} v_th, rho l = {}",
        args.u_prime, args.density
    );
    let plan = plan(&study);
    let computed = potentials.iter().find(|p| p.id() == wanted);
    if let (Some(potential), [(u_prime, false)]) = (computed, u_primes.as_slice()) {
        let fit = instances::fit(&study.kernel_params(*potential, *u_prime, args.density));
        emit(&report::kernel_model_text(
            &store, &plan, &fit, &title, &args.du, asked,
        )?);
        return Ok(ExitCode::SUCCESS);
    }
    let interpolation = interpolation(&study, config, &args, &wanted, &u_primes)?;
    emit(&report::interpolated_kernel_text(
        &store,
        &plan,
        &interpolation,
        &title,
        &args.du,
        asked,
    )?);
    Ok(ExitCode::SUCCESS)
}

/// How `ternary kernel` reaches `wanted` at `--u-prime` when the study did
/// not compute that kernel: the nodes in the potentials' coordinate (the
/// potential itself when computed) and in `u'` (`u_primes`, each with
/// whether it is a mirror image), and the line saying so.
fn interpolation(
    study: &Study,
    config: &Path,
    args: &KernelArgs,
    wanted: &str,
    u_primes: &[(f64, bool)],
) -> Result<report::Interpolation> {
    let potentials = study.potentials();
    let computed = potentials.iter().find(|p| p.id() == wanted);
    let (mut method, around, coordinate) = match computed {
        Some(potential) => (String::new(), vec![(0.0, *potential)], 0.0),
        None => {
            let ids: Vec<String> = potentials.iter().map(|p| p.id()).collect();
            interpolation_nodes(&potentials, args).with_context(|| {
                format!(
                    "{wanted}: no kernel of it in {} (it has {}); --n or --theta interpolates between computed ones with {POTENTIAL_NODES} of them around it (inverse power laws with n > 2, in 1/n; Lennard-Jones, in ln theta)",
                    config.display(),
                    ids.join(", ")
                )
            })?
        }
    };
    if u_primes.len() > 1 || u_primes[0].1 {
        let listed: Vec<String> = u_primes.iter().map(|(u, _)| u.to_string()).collect();
        let separator = if method.is_empty() { "" } else { "; " };
        method = format!(
            "{method}{separator}interpolated in u' through the kernels at u' = {} (those of positive u' the mirror images of the computed ones at -u', G(u' -> u) = G(-u' -> -u); Lagrange, degree {}; held-out kernels: docs/kernel-model.md)",
            listed.join(", "),
            u_primes.len() - 1
        );
    }
    let nodes = around
        .iter()
        .flat_map(|(c, potential)| {
            u_primes.iter().map(|&(u_prime, mirrored)| {
                let stored = if mirrored { -u_prime } else { u_prime };
                report::Node {
                    coordinate: *c,
                    u_prime,
                    fit: instances::fit(&study.kernel_params(*potential, stored, args.density)),
                    mirrored,
                }
            })
        })
        .collect();
    Ok(report::Interpolation {
        nodes,
        at: coordinate,
        u_prime: args.u_prime,
        method,
    })
}

/// The `u'` of the kernels `--u-prime` takes, each with whether it is the
/// mirror image of the computed kernel at `-u'`: the one computed (or
/// mirrored) at `--u-prime`, else the [`U_PRIME_NODES`] nearest around it
/// at `--density`; an error naming what the study computes when there are
/// too few or `--u-prime` is not between them.
fn u_prime_targets(study: &Study, config: &Path, args: &KernelArgs) -> Result<Vec<(f64, bool)>> {
    let targets = study.kernel_targets();
    let computed: Vec<f64> = targets
        .iter()
        .filter(|(_, rho)| *rho == args.density)
        .map(|(u, _)| *u)
        .collect();
    let nodes: Vec<(f64, bool)> = u_prime_nodes(&computed)
        .into_iter()
        .map(|(u, _, mirrored)| (u, mirrored))
        .collect();
    if let Some(node) = nodes.iter().find(|(u, _)| *u == args.u_prime) {
        return Ok(vec![*node]);
    }
    let coordinates: Vec<f64> = nodes.iter().map(|(u, _)| *u).collect();
    if let Some(taken) = nearest_nodes(&coordinates, args.u_prime, U_PRIME_NODES, 0.0) {
        return Ok(taken.iter().map(|&k| nodes[k]).collect());
    }
    let listed: Vec<String> = targets
        .iter()
        .map(|(u, rho)| format!("(u' {u}, density {rho})"))
        .collect();
    bail!(
        "--u-prime {} --density {}: not a kernel of {} (it computes {}), nor between {U_PRIME_NODES} of them at that density and their mirror images (u' -> -u')",
        args.u_prime,
        args.density,
        config.display(),
        listed.join(", ")
    )
}

/// Computed kernels to interpolate through, each as its coordinate (`1/n`,
/// `ln theta`) and its potential.
type Nodes = Vec<(f64, Potential)>;

/// How to interpolate to `--n` (inverse power laws, in `1/n`) or `--theta`
/// (Lennard-Jones, in `ln theta`): the method's line, the
/// [`POTENTIAL_NODES`] nearest computed potentials around the target
/// ([`nearest_nodes`]: coordinate and potential, in the study's order) and
/// the target's coordinate; `None` when there are too few around it.
fn interpolation_nodes(
    potentials: &[Potential],
    args: &KernelArgs,
) -> Option<(String, Nodes, f64)> {
    let wanted = match (args.n, args.theta) {
        (Some(n), _) => Potential::inverse_power(n),
        (None, Some(theta)) => Potential::lennard_jones(theta),
        (None, None) => return None,
    };
    let (family, at) = Family::of(&wanted)?;
    let family_nodes: Nodes = potentials
        .iter()
        .filter_map(|p| {
            Family::of(p)
                .filter(|(f, _)| *f == family)
                .map(|(_, c)| (c, *p))
        })
        .collect();
    let coordinates: Vec<f64> = family_nodes.iter().map(|(c, _)| *c).collect();
    let mut taken = nearest_nodes(&coordinates, at, POTENTIAL_NODES, family.separation())?;
    taken.sort_unstable();
    let nodes: Nodes = taken.iter().map(|&k| family_nodes[k]).collect();
    let ids: Vec<String> = nodes.iter().map(|(_, p)| p.id()).collect();
    let method = format!(
        "interpolated in {} through the models of {} (Lagrange, degree {}; the error jackknifed over the randomizations the models share; held-out kernels: docs/kernel-model.md)",
        family.coordinate(),
        ids.join(", "),
        nodes.len() - 1
    );
    Some((method, nodes, at))
}

/// The fit of the bound-pair autocorrelation ends where it falls below this
/// (a fifth of a relaxation time): later lags carry the one-dimensional
/// gas's slow memory (docs/lennard-jones.md), not the rate equation's decay.
const FIT_DOWN_TO: f64 = 0.8;

/// `ternary pairs`: equilibrium rings of a potential with a well, their bound
/// pairs' number and its relaxation, against the equilibrium constant `K_b`
/// and the dissociation rate of the study's scenes.
pub(super) fn pairs(config: &Path, args: PairsArgs) -> Result<ExitCode> {
    let study = Study::load(config)?;
    let potentials = study.potentials();
    let potential = potentials
        .iter()
        .find(|p| p.id() == args.potential)
        .copied()
        .with_context(|| {
            let ids: Vec<String> = potentials.iter().map(|p| p.id()).collect();
            format!(
                "--potential {}: not a potential of {} (it has {})",
                args.potential,
                config.display(),
                ids.join(", ")
            )
        })?;
    let Some(dissociation) = study.dissociation_params(potential) else {
        bail!(
            "--potential {}: no dissociation to compare with (its family has no well, or [dissociation] is disabled)",
            args.potential
        );
    };
    let mut dissociation_rates = Vec::new();
    for randomization in 0..dissociation.randomizations {
        eprintln!(
            "dissociation scenes: randomization {}/{}",
            randomization + 1,
            dissociation.randomizations
        );
        let net = (dissociation.seed, randomization, dissociation.points);
        let scenes = sobol_dissociation_scenes(&potential, &dissociation.engine, net, || {})
            .context("a potential with a well has bound pairs")?;
        dissociation_rates.push(dissociation_rate(&scenes));
    }
    let particles = args.particles as usize;
    let circumference = f64::from(args.particles) / args.density;
    let md = &study.config.md;
    let settings = KineticsSettings {
        particles,
        duration: args.duration,
        interval: args.interval,
        tolerance: args.tolerance,
        max_steps: CLUSTER_STEP_BUDGET,
    };
    let seeds: Vec<u64> = (0..u64::from(args.runs))
        .map(|r| args.seed.wrapping_shl(32).wrapping_add(r))
        .collect();
    let finished = AtomicU32::new(0);
    let runs = equilibrium_runs(
        &potential,
        circumference,
        md.neighbours as usize,
        &settings,
        &seeds,
        || {
            let done = finished.fetch_add(1, Ordering::Relaxed) + 1;
            eprintln!("rings: {done}/{} watched", args.runs);
        },
    )?;
    let relaxation = RelaxationSettings {
        particles,
        circumference,
        interval: args.interval,
        fit_from: args.fit_from,
        fit_down_to: FIT_DOWN_TO,
    };
    let measured = pair_relaxation(&runs, &relaxation).with_context(|| {
        format!(
            "the bound-pair count's autocorrelation did not fall below {FIT_DOWN_TO} between --fit-from {} and half of --duration {}: watch longer",
            args.fit_from, args.duration
        )
    })?;
    let predicted = report::PairPrediction {
        bound_length: potential.family().bound_pair_length(),
        dense_bound_length: dense_bound_length(&potential, args.density),
        dissociation: Estimate::from_replicates(&dissociation_rates),
    };
    let ring = format!(
        "{}: {} rings of N = {particles}, rho l = {}, watched {} l/v_th each (every {} l/v_th), tolerance {}",
        potential.id(),
        args.runs,
        args.density,
        args.duration,
        args.interval,
        settings.tolerance
    );
    emit(&report::pairs_text(&ring, &measured, &predicted));
    Ok(ExitCode::SUCCESS)
}

/// The gas `ternary rate` is asked about, and a line saying what it is.
fn rate_gas(args: &RateArgs) -> Result<(PhysicalGas, String)> {
    let (eps_over_k, sigma, mass_amu, what) = match (&args.species, args.eps_k) {
        (Some(name), _) => {
            let species = species::species(name).map_err(anyhow::Error::msg)?;
            let choice = match args.mass {
                MassArg::Particle => MassChoice::Particle,
                MassArg::Atom => MassChoice::Atom,
            };
            let mass = species.mass(choice).map_err(anyhow::Error::msg)?;
            let (particle, whose) = match (species.particle, choice) {
                (Particle::Atom, _) => ("atom", "the atom's"),
                (Particle::Molecule, MassChoice::Particle) => ("molecule", "the molecule's"),
                (Particle::Molecule, MassChoice::Atom) => ("molecule", "one atom's"),
            };
            let what = format!(
                "{} ({particle}; mass {mass} amu, {whose}) [{}]",
                species.name,
                species::SOURCE
            );
            (species.eps_over_k, species.sigma_angstrom, mass, what)
        }
        (None, Some(eps)) => match (args.sigma_angstrom, args.mass_amu) {
            (Some(sigma), Some(mass)) => (eps, sigma, mass, format!("mass {mass} amu")),
            _ => bail!("--eps-k needs --sigma-angstrom and --mass-amu"),
        },
        (None, None) => bail!("give --species or --eps-k, --sigma-angstrom and --mass-amu"),
    };
    let reading = match args.reading {
        ReadingArg::Paper => Reading::Paper,
        ReadingArg::FourEps => Reading::FourEps,
    };
    let eps = reading.eps_over_k(eps_over_k);
    let density = match (args.density_per_um, args.spacing_um) {
        (Some(density), _) => density,
        (None, Some(spacing)) => 1.0 / spacing,
        (None, None) => bail!("give --density-per-um or --spacing-um"),
    };
    let gas = PhysicalGas::from_kelvin(
        eps,
        sigma,
        args.temperature,
        Mass::AtomicMassUnits(mass_amu),
        density,
    );
    let description = format!(
        "{what}\nwell depth eps/k_B = {eps_over_k} K, sigma = {sigma} A; U = eps ((l0/d)^12 - (l0/d)^6) with l0 = sigma, eps/k_B = {eps} K ({}); T = {} K, rho = {density} /um",
        match reading {
            Reading::Paper => "the paper's reading: eps = the well depth",
            Reading::FourEps => "the 4 eps form: eps = 4 x the well depth",
        },
        args.temperature
    );
    check_rate_gas(&gas, eps, args.temperature)?;
    Ok((gas, description))
}

/// Refuses a gas whose `theta = kT/eps` the Lennard-Jones family does not
/// take, or whose units (`rho^2 l v_th`) are not a finite positive rate:
/// `rate` prints no `inf`, `undefined` or 310-digit number.
fn check_rate_gas(gas: &PhysicalGas, eps_over_k: f64, temperature: f64) -> Result<()> {
    let theta = temperature / eps_over_k;
    if LennardJones::new(theta).is_err() {
        let [low, high] = LennardJones::THETA_RANGE;
        bail!(
            "--temperature {} K over eps/k_B = {} K gives theta = kT/eps = {}, outside the Lennard-Jones family's [{}, {}]",
            compact(temperature),
            compact(eps_over_k),
            compact(theta),
            compact(low),
            compact(high)
        );
    }
    let unit = gas.rate_per_ns(1.0, None);
    if !(unit.is_finite() && unit > 0.0) {
        bail!(
            "the gas's rate unit rho^2 l v_th is {} /ns: check --mass-amu, the density and the temperature (their product over- or underflows)",
            compact(unit)
        );
    }
    Ok(())
}

/// `ternary slurm submit`: the shardable stages as an array job and a
/// dependent merge job (or their scripts, with `--dry-run`).
pub(super) fn slurm_submit(config: &Path, args: SlurmSubmitArgs) -> Result<ExitCode> {
    let study = Study::load(config)?;
    let plan = plan(&study);
    within_limits(&study, &plan, args.i_know)?;
    // A dry run reads a missing store as empty and creates nothing.
    let store = open(
        &study,
        if args.dry_run {
            Opening::View
        } else {
            Opening::Write
        },
    )?;
    let options = SubmitOptions {
        slurm: slurm_config(study.config.slurm.clone(), &args),
        dry_run: args.dry_run,
        i_know: args.i_know,
    };
    emit(&slurm::submit(config, &store, &plan, &options)?);
    Ok(ExitCode::SUCCESS)
}

/// The `[slurm]` settings with each option given on the command line in
/// place of its key.
fn slurm_config(configured: SlurmConfig, args: &SlurmSubmitArgs) -> SlurmConfig {
    SlurmConfig {
        shards: args.shards.unwrap_or(configured.shards),
        cpus_per_task: args.cpus_per_task.or(configured.cpus_per_task),
        mem: args.mem.clone().or(configured.mem),
        account: args.account.clone().or(configured.account),
        partition: args.partition.clone().or(configured.partition),
        qos: args.qos.clone().or(configured.qos),
        time: args.time.clone().or(configured.time),
        merge_time: args.merge_time.clone().or(configured.merge_time),
        max_parallel: args.max_parallel.or(configured.max_parallel),
        sbatch_args: if args.sbatch_arg.is_empty() {
            configured.sbatch_args
        } else {
            args.sbatch_arg.clone()
        },
    }
}
