//! `ternary rate`: the study's Lennard-Jones theta table read from the
//! store (the current `table[study]` artifact and the `u' = 0` moments it
//! was computed from), and a gas's rates written with their errors and the
//! artifacts they come from.

use std::fmt::Write as _;

use anyhow::{Context, Result, anyhow};
use arrow_array::RecordBatch;

use super::numbers::with_error;
use super::show::current_artifact;
use crate::config::{PAPER_TRUNCATION, Study};
use crate::contract::readers::self_variance_at;
use crate::contract::{self, instances};
use crate::physics::potential::Potential;
use crate::pipeline::Stage;
use crate::pipeline::store::{Depth, Manifest, Store};
use crate::pipeline::table::read_parquet;
use crate::rates::{GasRates, Interpolated, ThetaTable, time_of};
use crate::stats::Estimate;

/// A theta table and the artifacts it was read from (`stage[instance] key`).
pub struct SourcedTable {
    /// The table.
    pub table: ThetaTable,
    /// Its artifacts, the `table` artifact first.
    pub sources: Vec<String>,
}

/// The Lennard-Jones rows of the study's current `table[study]` artifact
/// (refused when stale, missing or damaged: `ternary run` computes it), each
/// with the paper's `|u - u'| <= 0.04` rate read from the moments artifact
/// that table row was computed from.
pub fn theta_table(study: &Study, store: &Store, plan: &[Box<dyn Stage>]) -> Result<SourcedTable> {
    let id = instances::table();
    let (stage, key) = current_artifact(store, plan, &id)?;
    let manifest = intact(store, &stage, &key)?;
    let batch = table_of(store, &manifest, contract::table::TABLE.name)?;
    let mut rows = lennard_jones_rows(&batch)?;
    rows.sort_by(|a, b| a.theta.total_cmp(&b.theta));
    let mut table = ThetaTable {
        thetas: Vec::new(),
        thermalization: Vec::new(),
        paper_thermalization: Vec::new(),
        recombination: Vec::new(),
        dissociation: Vec::new(),
    };
    let mut sources = vec![format!("{id} {key}")];
    for LennardJonesRow {
        theta,
        thermalization,
        recombination,
        dissociation,
    } in rows
    {
        let dilute = study.kernel_params(Potential::lennard_jones(theta), 0.0, 0.0);
        let moments = instances::moments(&dilute);
        let input = manifest
            .inputs
            .iter()
            .find(|input| input.stage == moments.stage && input.instance == moments.instance)
            .with_context(|| format!("{id} {key} was not computed from {moments}"))?;
        let moments_manifest = intact(store, &input.stage, &input.key)?;
        let batch = table_of(store, &moments_manifest, contract::moments::TABLE.name)?;
        table.thetas.push(theta);
        table.thermalization.push(thermalization);
        table
            .paper_thermalization
            .push(self_variance_at(&batch, PAPER_TRUNCATION)?);
        table.recombination.push(recombination);
        table.dissociation.push(dissociation);
        sources.push(format!("{moments} {}", input.key));
    }
    Ok(SourcedTable { table, sources })
}

/// One Lennard-Jones row of a `table`.
struct LennardJonesRow {
    theta: f64,
    /// `a_n`, `rho^2 l v_th`.
    thermalization: Estimate,
    /// Thermal recombination rate per atom, `rho^2 l v_th`.
    recombination: Estimate,
    /// Dissociation rate per pair, `rho v_th`.
    dissociation: Estimate,
}

/// Every Lennard-Jones row of a `table`.
fn lennard_jones_rows(batch: &RecordBatch) -> Result<Vec<LennardJonesRow>> {
    use contract::dissociation::study::{DISSOCIATION_RATE, THERMAL_RECOMBINATION};
    use contract::table::{A_N, THETA};
    let (thetas, rates) = (THETA.optional(batch)?, A_N.read(batch)?);
    let recombination = THERMAL_RECOMBINATION.read(batch)?;
    let dissociation = DISSOCIATION_RATE.read(batch)?;
    Ok(thetas
        .into_iter()
        .enumerate()
        .filter_map(|(row, theta)| {
            Some(LennardJonesRow {
                theta: theta?,
                thermalization: rates[row],
                recombination: recombination[row],
                dissociation: dissociation[row],
            })
        })
        .collect())
}

/// The manifest of artifact `key` of `stage`, its files checked to their hashes.
pub(super) fn intact(store: &Store, stage: &str, key: &str) -> Result<Manifest> {
    store
        .inspect(stage, key, None, Depth::Hashes)
        .map_err(|problems| anyhow!("{stage} artifact {key} is damaged: {}", problems.join("; ")))
}

/// Table `name` of the artifact `manifest` describes.
pub(super) fn table_of(store: &Store, manifest: &Manifest, name: &str) -> Result<RecordBatch> {
    let path = store
        .artifact_dir(&manifest.stage, &manifest.key)
        .join(format!("{name}.parquet"));
    Ok(read_parquet(&path)?.0)
}

/// The text of `ternary rate`: the gas (`description`), its `theta` and
/// `rho l`, each rate constant with its rate and time in seconds, how the
/// errors are made, and the artifacts the numbers come from.
pub fn rate_text(description: &str, rates: &GasRates, sources: &[String]) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "{description}");
    let _ = writeln!(
        out,
        "theta = kT/eps = {:.6}, rho l = {:.4e} (l = l0 (eps/kT)^(1/6)), rho^2 l v_th = {:.4e} /s",
        rates.theta, rates.scaled_density, rates.rate_unit_per_s
    );
    let gas = |constant| rates.per_second(constant);
    let pair = |constant| rates.per_pair_per_second(constant);
    let sections: [Section; 4] = [
        Section {
            title: "thermalization, the table's a_n (free atoms, untruncated: converged)",
            names: ["a", "Gamma", "1/Gamma"],
            unit: "rho^2 l v_th",
            constant: rates.thermalization,
            rate: gas(rates.thermalization),
        },
        Section {
            title: "thermalization as the paper counts it (|u - u'| <= 0.04)",
            names: ["a", "Gamma", "1/Gamma"],
            unit: "rho^2 l v_th",
            constant: rates.paper_thermalization,
            rate: gas(rates.paper_thermalization),
        },
        Section {
            title: "recombination, per atom averaged over thermal atoms (three atoms meet, a bound pair and a free atom leave; from detailed balance with dissociation, 3 K_b k_d)",
            names: ["rate", "rate", "time"],
            unit: "rho^2 l v_th",
            constant: rates.recombination,
            rate: gas(rates.recombination),
        },
        Section {
            title: "dissociation of a bound pair by the gas's atoms (three free atoms leave), per pair",
            names: ["k_d", "rate", "life"],
            unit: "rho v_th",
            constant: rates.dissociation,
            rate: pair(rates.dissociation),
        },
    ];
    for section in sections {
        section.write(&mut out);
    }
    let _ = writeln!(
        out,
        "errors: the table's standard errors and the interpolation's (log-log between the neighbouring thetas, against the quadratic through a third row) in quadrature; 0 interpolation at a row"
    );
    let _ = writeln!(out, "from: {}", sources.join(", "));
    out
}

/// One rate constant of `ternary rate`: its scaled value and its rate in 1/s.
struct Section {
    title: &'static str,
    /// Names of the constant, its rate and its time.
    names: [&'static str; 3],
    /// Unit of the scaled constant.
    unit: &'static str,
    constant: Interpolated,
    /// The constant in 1/s.
    rate: Interpolated,
}

impl Section {
    /// The title, the constant, its rate and its time.
    fn write(&self, out: &mut String) {
        let _ = writeln!(out, "{}:", self.title);
        let _ = writeln!(
            out,
            "  {:<7} = {}",
            self.names[0],
            constant_text(self.constant, self.unit)
        );
        write_rate(out, (self.names[1], self.names[2]), self.rate);
    }
}

/// A scaled constant in `unit` with its combined error and both parts.
fn constant_text(constant: Interpolated, unit: &str) -> String {
    let estimate = constant.estimate();
    format!(
        "{} [{unit}] (statistical {:.2e}, interpolation {:.2e})",
        with_error(estimate.mean, estimate.stderr, "undefined"),
        constant.statistical,
        constant.interpolation
    )
}

/// A rate in 1/s and its time `1 / rate` in s, as `names`.
fn write_rate(out: &mut String, names: (&str, &str), rate: Interpolated) {
    let rate = rate.estimate();
    let time = time_of(rate);
    let _ = writeln!(
        out,
        "  {:<7} = {} /s",
        names.0,
        with_error(rate.mean, rate.stderr, "undefined")
    );
    let _ = writeln!(
        out,
        "  {:<7} = {} s",
        names.1,
        with_error(time.mean, time.stderr, "never (zero rate)")
    );
}
