//! Commands: argument parsing and the turning of library results into output
//! and exit codes. The library reports what it does as values and events;
//! only this module prints.

mod args;
mod benches;
mod commands;

use std::path::Path;
use std::process::ExitCode;

use anyhow::{Context, Result, bail};
use clap::Parser;

use args::{BenchCommand, Cli, Command, SlurmCommand};
use ternary::config::{Study, compact};
use ternary::pipeline::Stage;
use ternary::pipeline::executor::{self, Event};
use ternary::pipeline::store::{Store, StoreEvent};
use ternary::report;

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

/// Runs one subcommand.
fn dispatch(cli: Cli) -> Result<ExitCode> {
    let config = cli.config.as_path();
    match cli.command {
        Command::Run(args) => commands::run(config, args),
        Command::Status(args) => commands::status(config, args),
        Command::Dag(args) => commands::dag(config, args),
        Command::Verify(args) => commands::verify(config, args),
        Command::Export(args) => commands::export(config, args),
        Command::Report(args) => commands::report(config, args),
        Command::Gc => commands::gc(config),
        Command::Show(args) => commands::show(config, args),
        Command::Rate(args) => commands::rate(config, args),
        Command::Kernel(args) => commands::kernel(config, args),
        Command::Pairs(args) => commands::pairs(config, args),
        Command::Slurm {
            which: SlurmCommand::Submit(args),
        } => commands::slurm_submit(config, args),
        Command::Bench { which } => match which {
            BenchCommand::Integrators(args) => benches::integrators(args),
            BenchCommand::Kernel(args) => benches::kernel(config, args),
            BenchCommand::FarKernel(args) => benches::far_kernel(config, args),
            BenchCommand::Balance(args) => benches::balance(config, args),
            BenchCommand::Md(args) => benches::md(args),
        },
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

/// Prints an executor event's line on stdout as it happens (a closed stdout
/// must not abort a run: the line is only a log).
fn print_event(event: Event<'_>) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout().lock(), "{}", event.line());
}

/// Prints what the store reports (a wait for its lock) on stderr.
fn print_store_event(event: &StoreEvent) {
    eprintln!("{event}");
}

/// `0` when nothing is wrong, otherwise failure.
fn exit_code(problems: usize) -> ExitCode {
    if problems == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
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

/// The study's store, opened as `opening` says, reporting on stderr.
fn open(study: &Study, opening: Opening) -> Result<Store> {
    let root = study.store_path();
    match opening {
        Opening::Write => {
            Store::view(&root).and_then(|store| store.reporting_to(print_store_event).writable())
        }
        Opening::Existing => {
            Store::open_existing(&root).map(|store| store.reporting_to(print_store_event))
        }
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
