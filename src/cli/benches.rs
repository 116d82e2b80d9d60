//! `ternary bench ...`: one function per benchmark, each building its
//! options from the arguments and printing the benchmark's report.

use std::path::Path;
use std::process::ExitCode;

use anyhow::{Result, bail};

use super::args::{
    BenchBalanceArgs, BenchFarKernelArgs, BenchIntegratorsArgs, BenchKernelArgs, BenchMdArgs,
};
use super::emit;
use crate::bench::{
    self, BalanceBenchOptions, KernelBenchOptions, MdBenchOptions, StudySettings,
    WorkPrecisionOptions,
};
use ternary::config::{MAX_GAS_DENSITY, MAX_RING_ENCOUNTERS, Study, compact};
use ternary::physics::potential::Potential;
use ternary::physics::units::{Mass, PhysicalGas, ring_density_per_um};

/// `ternary bench integrators`.
pub(super) fn integrators(args: BenchIntegratorsArgs) -> Result<ExitCode> {
    let options = WorkPrecisionOptions {
        n: args.n,
        scenes: args.scenes as usize,
        seed: args.seed,
    };
    let (report, figure) = bench::integrators(&options);
    emit(&report);
    write_bench_figure(&figure, args.figures.as_deref())?;
    Ok(ExitCode::SUCCESS)
}

/// `ternary bench kernel`, with the study's sampler settings from `config`.
pub(super) fn kernel(config: &Path, args: BenchKernelArgs) -> Result<ExitCode> {
    let options = KernelBenchOptions {
        potential: args
            .theta
            .map_or(Potential::inverse_power(args.n), Potential::lennard_jones),
        randomizations: args.randomizations,
        points: args.points,
        seed: args.seed,
        study: bench_study(config)?,
    };
    let (report, figure) = bench::kernel(&options);
    emit(&report);
    write_bench_figure(&figure, args.figures.as_deref())?;
    Ok(ExitCode::SUCCESS)
}

/// `ternary bench far-kernel`, with the study's engine, offset rule and bins from `config`.
pub(super) fn far_kernel(config: &Path, args: BenchFarKernelArgs) -> Result<ExitCode> {
    let options = KernelBenchOptions {
        potential: Potential::inverse_power(args.n),
        randomizations: args.randomizations,
        points: args.pairs,
        seed: args.seed,
        study: bench_study(config)?,
    };
    emit(&bench::far_kernel(&options));
    Ok(ExitCode::SUCCESS)
}

/// `ternary bench balance`, refusing a bin width that would put the pair in
/// one bin or make more than 1e6 bins.
pub(super) fn balance(config: &Path, args: BenchBalanceArgs) -> Result<ExitCode> {
    let narrowest = args.separation / 5e5;
    if !(narrowest..=args.separation).contains(&args.bin_width) {
        bail!(
            "--bin-width {}: must be in [{}, {}] for --separation {} (the pair at least one bin apart, at most 1e6 bins)",
            compact(args.bin_width),
            compact(narrowest),
            compact(args.separation),
            compact(args.separation)
        );
    }
    let options = BalanceBenchOptions {
        potential: Potential::inverse_power(args.n),
        randomizations: args.randomizations,
        from: args.from,
        separation: args.separation,
        bin_width: args.bin_width,
        seed: args.seed,
        study: bench_study(config)?,
    };
    emit(&bench::balance(&options).map_err(anyhow::Error::msg)?);
    Ok(ExitCode::SUCCESS)
}

/// `ternary bench md`.
pub(super) fn md(args: BenchMdArgs) -> Result<ExitCode> {
    let options = MdBenchOptions {
        particles: args.particles as usize,
        radius_um: args.radius_um,
        kt_ev: args.kt_ev,
        final_time_ns: args.final_time_ns,
        neighbours: args.neighbours as usize,
        seed: args.seed,
    };
    check_md_bench(&options)?;
    emit(&bench::md(&options).map_err(anyhow::Error::msg)?);
    Ok(ExitCode::SUCCESS)
}

/// The settings a benchmark takes from the study at `config`, or the
/// defaults when there is no such file.
fn bench_study(config: &Path) -> Result<StudySettings> {
    let study = config.exists().then(|| Study::load(config)).transpose()?;
    Ok(StudySettings::of(study.as_ref()))
}

/// Writes a benchmark's figure into `dir` when one was asked for, naming the files.
fn write_bench_figure(figure: &bench::BenchFigure, dir: Option<&Path>) -> Result<()> {
    if let Some(dir) = dir {
        for path in figure.write(dir).map_err(anyhow::Error::msg)? {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
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
