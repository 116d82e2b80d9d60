//! What the command line prints: the run summary, the DAG, verification and
//! garbage-collection reports, and artifact listings. Reads artifacts with
//! polars, as any user would.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::fs::File;
use std::path::Path;

use anyhow::{Context, Result, bail};
use polars::prelude::{DataFrame, ParquetReader, SerReader};

use crate::pipeline::Stage;
use crate::pipeline::executor::{self, Action, InstanceReport};
use crate::pipeline::shards;
use crate::pipeline::store::{Depth, Store, table_files};
use crate::pipeline::table::read_parquet;

/// `value ± error` with as many decimals as the error's leading two digits need.
pub fn with_error(value: f64, error: f64) -> String {
    if !error.is_finite() || !value.is_finite() {
        return format!("{value} ± {error}");
    }
    let decimals = if error > 0.0 {
        (1.0 - error.log10().floor()).clamp(0.0, 16.0) as usize
    } else {
        16
    };
    format!("{value:.decimals$} ± {error:.1e}")
}

/// Cell `name` of `row` as a number (NaN when null).
fn number(frame: &DataFrame, row: usize, name: &str) -> Result<f64> {
    Ok(frame.column(name)?.f64()?.get(row).unwrap_or(f64::NAN))
}

/// Cell `name` of `row` as a count (0 when null).
fn count(frame: &DataFrame, row: usize, name: &str) -> Result<u32> {
    Ok(frame.column(name)?.u32()?.get(row).unwrap_or(0))
}

/// Cell `name` of `row` as text (empty when null).
fn text(frame: &DataFrame, row: usize, name: &str) -> Result<String> {
    Ok(frame
        .column(name)?
        .str()?
        .get(row)
        .unwrap_or_default()
        .to_string())
}

fn read_frame(path: &Path) -> Result<DataFrame> {
    let file = File::open(path).with_context(|| format!("opening {}", path.display()))?;
    ParquetReader::new(file)
        .finish()
        .with_context(|| format!("reading {}", path.display()))
}

/// The study table (when computed), the convergence study and the scan peaks
/// of a run, readable.
pub fn summary(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    let mut out = study_table(store, reports)?;
    out.push_str(&gases_table(store, reports)?);
    out.push_str(&convergence_table(store, reports)?);
    out.push_str(&evolve_table(store, reports)?);
    out.push_str(&md_table(store, reports)?);
    out.push_str(&compare_table(store, reports)?);
    let scans = reports.iter().filter(|r| r.id.stage == "scan");
    for (k, report) in scans.enumerate() {
        let Some(key) = report
            .key
            .as_ref()
            .filter(|_| report.action != Action::Skipped)
        else {
            continue;
        };
        if k == 0 {
            writeln!(
                out,
                "\nmono-energetic scans: largest |u1f| (error bound) and its arrival offset"
            )?;
            writeln!(
                out,
                "{:<10} {:<12} {:<34} {:<30} {:>6} {:>12}",
                "potential",
                "launch",
                "|u1f,max| [v_th]",
                "offset [l/v_th]",
                "failed",
                "max |dE/E|"
            )?;
        }
        let frame = read_frame(&store.artifact_dir("scan", key).join("peak.parquet"))?;
        for row in 0..frame.height() {
            let failed = count(&frame, row, "failed_scenes")?;
            writeln!(
                out,
                "{:<10} {:<12} {:<34} {:<30} {:>6} {:>12.1e}",
                report.id.instance,
                text(&frame, row, "launch")?,
                with_error(
                    number(&frame, row, "u1_final_max_abs")?,
                    number(&frame, row, "u1_final_max_abs_error")?
                ),
                with_error(
                    number(&frame, row, "arrival_offset_at_max")?,
                    number(&frame, row, "arrival_offset_at_max_error")?
                ),
                failed,
                number(&frame, row, "worst_energy_error")?,
            )?;
        }
    }
    Ok(out)
}

/// The table `<stage>.parquet` of every intact artifact of `stage` in a run.
fn stage_frames(
    store: &Store,
    reports: &[InstanceReport],
    stage: &str,
) -> Result<Vec<(String, DataFrame)>> {
    table_frames(store, reports, stage, stage)
}

/// The table `<table>.parquet` of every intact artifact of `stage` in a run.
fn table_frames(
    store: &Store,
    reports: &[InstanceReport],
    stage: &str,
    table: &str,
) -> Result<Vec<(String, DataFrame)>> {
    reports
        .iter()
        .filter(|r| r.id.stage == stage)
        .filter(|r| r.action != Action::Skipped)
        .filter_map(|r| r.key.as_ref().map(|key| (r, key)))
        .map(|(report, key)| {
            let frame = read_frame(
                &store
                    .artifact_dir(stage, key)
                    .join(format!("{table}.parquet")),
            )?;
            Ok((report.id.instance.clone(), frame))
        })
        .collect()
}

/// The `table` stage's output: `a_n` with standard errors per potential.
fn study_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    let mut out = String::new();
    let Some((_, frame)) = stage_frames(store, reports, "table")?.into_iter().next() else {
        return Ok(out);
    };
    writeln!(
        out,
        "\nthermalization constants a_n = self variance rate at u' = 0, dilute limit [rho^2 l v_th]; kernel shape near u' (+- standard errors)"
    )?;
    writeln!(
        out,
        "{:<10} {:<26} {:>8} {:<26} {:<20} {:<22} {:>13}",
        "potential",
        "a_n (|u-u'| <= window/2)",
        "rel.err",
        "a_n untruncated",
        "beta",
        "sigma [v_th]",
        "failed"
    )?;
    for row in 0..frame.height() {
        let potential = text(&frame, row, "potential")?;
        let (a, a_err) = (
            number(&frame, row, "a_n")?,
            number(&frame, row, "a_n_stderr")?,
        );
        let relative = if a == 0.0 {
            "-".to_string()
        } else {
            format!("{:.3}%", 100.0 * a_err / a.abs())
        };
        writeln!(
            out,
            "{:<10} {:<26} {:>8} {:<26} {:<20} {:<22} {:>13}",
            potential,
            with_error(a, a_err),
            relative,
            with_error(
                number(&frame, row, "a_n_untruncated")?,
                number(&frame, row, "a_n_untruncated_stderr")?
            ),
            with_error(
                number(&frame, row, "beta")?,
                number(&frame, row, "beta_stderr")?
            ),
            with_error(
                number(&frame, row, "sigma")?,
                number(&frame, row, "sigma_stderr")?
            ),
            format!(
                "{}/{}",
                count(&frame, row, "failed_events")?,
                count(&frame, row, "events")?
            ),
        )?;
    }
    Ok(out)
}

/// The `gases` stage's output: rates in physical units.
fn gases_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    let mut out = String::new();
    let Some((_, frame)) = stage_frames(store, reports, "gases")?.into_iter().next() else {
        return Ok(out);
    };
    writeln!(
        out,
        "\nthermalization rates in physical units (Gamma = a_n rho^2 l v_th, +- standard error)"
    )?;
    writeln!(
        out,
        "{:<22} {:<8} {:>9} {:>11} {:<26} {:<26} {:<24}",
        "gas",
        "potential",
        "kT [eV]",
        "rho l",
        "Gamma [1/ns] (dilute)",
        "Gamma at rho l [1/ns]",
        "1/Gamma [ns]"
    )?;
    for row in 0..frame.height() {
        writeln!(
            out,
            "{:<22} {:<8} {:>9.3} {:>11.3e} {:<26} {:<26} {:<24}",
            text(&frame, row, "gas")?,
            text(&frame, row, "potential")?,
            number(&frame, row, "kt")?,
            number(&frame, row, "rho_l")?,
            format!(
                "{:.5e} ± {:.1e}",
                number(&frame, row, "gamma")?,
                number(&frame, row, "gamma_stderr")?
            ),
            format!(
                "{:.5e} ± {:.1e}",
                number(&frame, row, "gamma_at_density")?,
                number(&frame, row, "gamma_at_density_stderr")?
            ),
            format!(
                "{:.5e} ± {:.1e}",
                number(&frame, row, "relaxation_time")?,
                number(&frame, row, "relaxation_time_stderr")?
            ),
        )?;
    }
    Ok(out)
}

/// The `convergence` stage's output: shifts of `a_n` against the defaults.
fn convergence_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    let mut out = String::new();
    for (instance, frame) in stage_frames(store, reports, "convergence")? {
        writeln!(
            out,
            "\nconvergence of a_n for {} (shift = a_n - default, paired over randomizations)",
            instance
        )?;
        writeln!(
            out,
            "{:<14} {:>10} {:<30} {:<28} {:>16}",
            "parameter", "value", "a_n", "shift", "shift / a_n error"
        )?;
        for row in 0..frame.height() {
            let parameter = text(&frame, row, "parameter")?;
            writeln!(
                out,
                "{:<14} {:>10.3e} {:<30} {:<28} {:>16.3}",
                parameter,
                number(&frame, row, "value")?,
                with_error(
                    number(&frame, row, "a_n")?,
                    number(&frame, row, "a_n_stderr")?
                ),
                with_error(
                    number(&frame, row, "shift")?,
                    number(&frame, row, "shift_stderr")?
                ),
                number(&frame, row, "shift_over_error")?,
            )?;
        }
    }
    Ok(out)
}

/// The `evolve` stage's summary: spread and approach to equilibrium of `h`.
fn evolve_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    let mut out = String::new();
    for (instance, frame) in table_frames(store, reports, "evolve", "evolution_summary")? {
        writeln!(
            out,
            "\nevolution of h from delta(u - u') for {instance}: full = linearized operator, tagged = special particle, fokker_planck (+- jackknife errors)"
        )?;
        writeln!(
            out,
            "{:<14} {:>10} {:>9} {:<28} {:<26} {:<26}",
            "process",
            "t Gamma",
            "t [ns]",
            "<(u-u')^2>, |u-u'|<=X",
            "<(u-u')^2>",
            "L1 distance to equilibrium"
        )?;
        for row in 0..frame.height() {
            writeln!(
                out,
                "{:<14} {:>10.3e} {:>9.0} {:<28} {:<26} {:<26}",
                text(&frame, row, "process")?,
                number(&frame, row, "time_gamma")?,
                number(&frame, row, "time_ns")?,
                with_error(
                    number(&frame, row, "window_variance")?,
                    number(&frame, row, "window_variance_stderr")?
                ),
                with_error(
                    number(&frame, row, "variance")?,
                    number(&frame, row, "variance_stderr")?
                ),
                with_error(
                    number(&frame, row, "distance_to_equilibrium")?,
                    number(&frame, row, "distance_to_equilibrium_stderr")?
                ),
            )?;
        }
    }
    Ok(out)
}

/// The `md` stage's summaries: moments of `h(u, t_f)` by both estimators.
fn md_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    let mut out = String::new();
    let frames = table_frames(store, reports, "md", "summary")?;
    if frames.is_empty() {
        return Ok(out);
    }
    writeln!(
        out,
        "\nring molecular dynamics: h(u, t_f) within the window (+- standard errors over runs)"
    )?;
    writeln!(
        out,
        "{:<22} {:<10} {:<24} {:<28}",
        "ring", "estimator", "sum h du", "<(u-u')^2>_window [v_th^2]"
    )?;
    for (instance, frame) in frames {
        for row in 0..frame.height() {
            writeln!(
                out,
                "{:<22} {:<10} {:<24} {:<28}",
                instance,
                text(&frame, row, "estimator")?,
                with_error(
                    number(&frame, row, "number")?,
                    number(&frame, row, "number_stderr")?
                ),
                with_error(
                    number(&frame, row, "window_variance")?,
                    number(&frame, row, "window_variance_stderr")?
                ),
            )?;
        }
    }
    out.push_str(&bound_pairs_table(store, reports)?);
    Ok(out)
}

/// The `compare` stage: goodness of fit of MD against Boltzmann and of the
/// scaling collapse, and the finite-size and density study.
fn compare_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    let mut out = String::new();
    for (_, frame) in table_frames(store, reports, "compare", "goodness")? {
        writeln!(
            out,
            "\nMD against Boltzmann and the scaling collapse (chi2 per degree of freedom)"
        )?;
        writeln!(
            out,
            "{:<22} {:<22} {:<10} {:>8} {:>5}",
            "ring", "reference", "estimator", "chi2/dof", "dof"
        )?;
        for row in 0..frame.height() {
            writeln!(
                out,
                "{:<22} {:<22} {:<10} {:>8.2} {:>5}",
                text(&frame, row, "ring")?,
                text(&frame, row, "reference")?,
                text(&frame, row, "estimator")?,
                number(&frame, row, "chi2_per_dof")?,
                count(&frame, row, "dof")?,
            )?;
        }
    }
    for (_, frame) in table_frames(store, reports, "compare", "finite_size")? {
        writeln!(
            out,
            "\nfinite size and density: window variance at t_f, MD / Boltzmann (+- standard errors); tagged: starts near u', thermal: every start"
        )?;
        writeln!(
            out,
            "{:<22} {:>5} {:>10} {:>16} {:<24} {:<24}",
            "ring", "N", "rho l", "rho^2 l v_th t_f", "tagged", "thermal"
        )?;
        for row in 0..frame.height() {
            let ratio = |name: &str| -> Result<String> {
                Ok(with_error(
                    number(&frame, row, name)?,
                    number(&frame, row, &format!("{name}_stderr"))?,
                ))
            };
            writeln!(
                out,
                "{:<22} {:>5} {:>10.3e} {:>16.4e} {:<24} {:<24}",
                text(&frame, row, "ring")?,
                count(&frame, row, "particles")?,
                number(&frame, row, "density")?,
                number(&frame, row, "scaled_time")?,
                ratio("ratio")?,
                ratio("thermal_ratio")?,
            )?;
        }
    }
    Ok(out)
}

/// Bound neighbour pairs of the rings with a well: sampled, after the
/// dynamics, and the dilute limit.
fn bound_pairs_table(store: &Store, reports: &[InstanceReport]) -> Result<String> {
    let mut out = String::new();
    let frames = table_frames(store, reports, "md", "pairs")?;
    let bound = |frame: &DataFrame, row: usize| -> Result<String> {
        Ok(with_error(
            number(frame, row, "bound_fraction")?,
            number(frame, row, "bound_fraction_stderr")?,
        ))
    };
    for (instance, frame) in frames {
        let dilute = number(&frame, 2, "bound_fraction")?;
        if dilute > 0.0 {
            writeln!(
                out,
                "{instance}: bound neighbour pairs per gap {} initial, {} final, {dilute:.5} dilute limit rho K_b",
                bound(&frame, 0)?,
                bound(&frame, 1)?,
            )?;
        }
    }
    Ok(out)
}

/// The DAG as text: one line per instance with its inputs.
pub fn dag(stages: &[Box<dyn Stage>]) -> String {
    let mut out = String::new();
    for stage in stages {
        let inputs: Vec<String> = stage.inputs().iter().map(ToString::to_string).collect();
        let from = if inputs.is_empty() {
            "(source)".to_string()
        } else {
            format!("<- {}", inputs.join(", "))
        };
        let _ = writeln!(out, "{:<24} {from}", stage.id().to_string());
    }
    out
}

/// Checks every artifact down to its tables' content hashes (and, for stages
/// of the study, that it holds exactly the tables the stage writes): the
/// report and the number of damaged artifacts.
pub fn verify(store: &Store, stages: &[Box<dyn Stage>]) -> Result<(String, usize)> {
    let outputs: BTreeMap<String, Vec<String>> = stages
        .iter()
        .map(|stage| (stage.id().stage, table_files(stage.tables())))
        .collect();
    let mut out = String::new();
    let mut damaged = 0;
    let artifacts = store.artifacts()?;
    for (stage, key) in &artifacts {
        let expected = outputs.get(stage).map(Vec::as_slice);
        match store.inspect(stage, key, expected, Depth::Contents) {
            Ok(_) => writeln!(out, "ok       {stage}/{key}")?,
            Err(problems) => {
                damaged += 1;
                writeln!(out, "DAMAGED  {stage}/{key}: {}", problems.join("; "))?;
            }
        }
    }
    for path in store.foreign_entries()? {
        writeln!(
            out,
            "foreign  {} (not written by ternary: left alone)",
            path.display()
        )?;
    }
    let debris = store.staging_debris()?.len();
    if debris > 0 {
        writeln!(
            out,
            "{debris} staging entries from interrupted runs are ignored (the next run or gc removes them)"
        )?;
    }
    writeln!(
        out,
        "verify: {} artifacts, {} intact, {} damaged",
        artifacts.len(),
        artifacts.len() - damaged,
        damaged
    )?;
    Ok((out, damaged))
}

/// Removes artifacts that neither the current key nor the last computed key of
/// a current instance names (shards are kept while their current artifact
/// waits to be merged), and staging debris. Only names ternary gives are
/// removed; foreign entries are reported and kept.
pub fn gc(store: &Store, stages: &[Box<dyn Stage>]) -> Result<String> {
    let lock = store.lock()?;
    let mut keep: BTreeSet<(String, String)> = BTreeSet::new();
    for line in executor::status(store, stages, 1)? {
        if let Some(key) = line.key {
            keep.insert((line.id.stage.clone(), key));
        }
        if let Some(entry) = store.read_ref(&line.id.stage, &line.id.instance) {
            keep.insert((line.id.stage, entry.key));
        }
    }
    let mut removed = 0;
    let mut bytes = 0;
    let awaiting_merge = |stage: &str, key: &str| {
        let whole = store
            .inspect(stage, key, None, Depth::Sizes)
            .ok()
            .as_ref()
            .and_then(shards::whole_of);
        whole.is_some_and(|(stage, key)| {
            !store.artifact_dir(&stage, &key).is_dir() && keep.contains(&(stage, key))
        })
    };
    for (stage, key) in store.artifacts()? {
        if !keep.contains(&(stage.clone(), key.clone())) && !awaiting_merge(&stage, &key) {
            bytes += store.remove_artifact(&lock, &stage, &key)?;
            removed += 1;
        }
    }
    let debris = store.clean_staging(&lock)?;
    let mut out =
        format!("gc: removed {removed} artifacts ({bytes} bytes) and {debris} staging entries\n");
    for path in store.foreign_entries()? {
        writeln!(out, "gc: kept {} (not written by ternary)", path.display())?;
    }
    Ok(out)
}

/// Sum of a numeric column in row order (nulls skipped), `None` for text.
fn column_sum(column: &arrow::array::ArrayRef) -> Option<f64> {
    let as_f64 = arrow::compute::cast(column, &arrow::datatypes::DataType::Float64).ok()?;
    if !column.data_type().is_numeric() {
        return None;
    }
    let values = as_f64
        .as_any()
        .downcast_ref::<arrow::array::Float64Array>()?;
    Some(values.iter().flatten().sum())
}

/// Metadata, schema with units, and the first rows of a Parquet file.
fn show_file(path: &Path, rows: usize) -> Result<String> {
    let mut out = String::new();
    let (batch, metadata) = read_parquet(path)?;
    writeln!(out, "== {} ({} rows)", path.display(), batch.num_rows())?;
    for (key, value) in metadata.iter().filter(|(k, _)| k.starts_with("ternary.")) {
        writeln!(out, "  {key}: {value}")?;
    }
    writeln!(out, "  columns (sum of the numbers, in row order):")?;
    for (field, column) in batch.schema().fields().iter().zip(batch.columns()) {
        let meta = field.metadata();
        let unit = meta.get("unit").map(String::as_str).unwrap_or("");
        let description = meta.get("description").map(String::as_str).unwrap_or("");
        let sum = column_sum(column).map_or(String::new(), |sum| format!("{sum:e}"));
        writeln!(
            out,
            "    {:<28} {:<8} {sum:<24} [{unit}] {description}",
            field.name(),
            field.data_type().to_string()
        )?;
    }
    writeln!(out, "{}", read_frame(path)?.head(Some(rows)))?;
    Ok(out)
}

/// An artifact (by key or unique key prefix, or its directory) or a Parquet file.
pub fn show(store: Option<&Store>, target: &str, rows: usize) -> Result<String> {
    let path = Path::new(target);
    if path.is_file() {
        return show_file(path, rows);
    }
    let dir = if path.is_dir() {
        path.to_path_buf()
    } else {
        let Some(store) = store else {
            bail!(
                "`{target}` is neither a file nor a directory, and no store is open to look up keys"
            )
        };
        if target.len() < 6 {
            bail!("`{target}`: give at least 6 characters of a key, or a path");
        }
        let matches: Vec<(String, String)> = store
            .artifacts()?
            .into_iter()
            .filter(|(_, key)| key.starts_with(target))
            .collect();
        match matches.as_slice() {
            [(stage, key)] => store.artifact_dir(stage, key),
            [] => bail!(
                "no artifact key starts with `{target}` in {}",
                store.root().display()
            ),
            _ => bail!("`{target}` is ambiguous: {} artifacts match", matches.len()),
        }
    };
    let manifest_path = dir.join("manifest.json");
    let manifest = std::fs::read_to_string(&manifest_path)
        .with_context(|| format!("reading {}", manifest_path.display()))?;
    let mut out = format!("{manifest}\n");
    let value: serde_json::Value = serde_json::from_str(&manifest)?;
    for file in value["files"].as_array().into_iter().flatten() {
        let name = file["name"].as_str().unwrap_or_default();
        out.push_str(&show_file(&dir.join(name), rows)?);
    }
    Ok(out)
}
