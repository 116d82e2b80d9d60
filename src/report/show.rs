//! `ternary show`: a stage's current instances, or one artifact by key
//! prefix: its manifest, and each table's metadata, schema with units and
//! first rows.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, bail};
use arrow_array::cast::AsArray;
use arrow_array::types::{Float32Type, Float64Type, Int32Type, Int64Type, UInt32Type, UInt64Type};
use arrow_array::{ArrayRef, ArrowPrimitiveType};
use arrow_schema::DataType;

use crate::pipeline::executor::{self, Freshness, StatusLine};
use crate::pipeline::store::{Depth, Store};
use crate::pipeline::table::{is_table_file, read_parquet};
use crate::pipeline::{InstanceId, Stage};

use super::read_frame;
use super::status::size;

/// Sum of a numeric column in row order (nulls skipped), `None` for text.
fn column_sum(column: &ArrayRef) -> Option<f64> {
    /// The column's values of Arrow type `T`, widened to `f64`.
    fn widened<T: ArrowPrimitiveType>(column: &ArrayRef, to_f64: fn(T::Native) -> f64) -> f64 {
        column
            .as_primitive::<T>()
            .iter()
            .flatten()
            .map(to_f64)
            .sum()
    }
    Some(match column.data_type() {
        DataType::Float64 => widened::<Float64Type>(column, |v| v),
        DataType::Float32 => widened::<Float32Type>(column, f64::from),
        DataType::UInt32 => widened::<UInt32Type>(column, f64::from),
        DataType::Int32 => widened::<Int32Type>(column, f64::from),
        DataType::UInt64 => widened::<UInt64Type>(column, |v| v as f64),
        DataType::Int64 => widened::<Int64Type>(column, |v| v as f64),
        _ => return None,
    })
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

/// What `ternary show` shows, and the number of problems of an artifact
/// looked up in the store (checked to its file hashes; a damaged one is shown
/// under a warning). `target` is a Parquet file or an artifact directory; a
/// stage of `plan` (its current instances, their keys and files); an
/// instance `stage[instance]` (its current artifact); or an artifact key or
/// unique key prefix of at least 6 characters.
pub fn show(
    store: Option<&Store>,
    plan: &[Box<dyn Stage>],
    target: &str,
    rows: usize,
) -> Result<(String, usize)> {
    let path = Path::new(target);
    if path.is_file() {
        return Ok((show_file(path, rows)?, 0));
    }
    if path.is_dir() {
        return Ok((show_artifact(path, &[], rows)?, 0));
    }
    let Some(store) = store else {
        bail!("`{target}` is neither a file nor a directory, and no store is open to look up keys")
    };
    if plan.iter().any(|stage| stage.id().stage == target) {
        return Ok((show_stage(store, plan, target)?, 0));
    }
    let (stage, key) = match target.strip_suffix(']').and_then(|t| t.split_once('[')) {
        Some((stage, instance)) => {
            current_artifact(store, plan, &InstanceId::new(stage, instance))?
        }
        None => artifact_by_prefix(store, target)?,
    };
    let problems = store
        .inspect(&stage, &key, None, Depth::Hashes)
        .err()
        .unwrap_or_default();
    let text = show_artifact(&store.artifact_dir(&stage, &key), &problems, rows)?;
    Ok((text, problems.len()))
}

/// The current instances of `stage`: freshness and key of each, and the
/// files of those with an artifact under their current key.
fn show_stage(store: &Store, plan: &[Box<dyn Stage>], stage: &str) -> Result<String> {
    let lines: Vec<StatusLine> = executor::status(store, plan, 1)?
        .into_iter()
        .filter(|line| line.id.stage == stage)
        .collect();
    let mut out = String::new();
    writeln!(
        out,
        "{stage}: {} instances (`ternary show '{stage}[<instance>]'` shows one)",
        lines.len()
    )?;
    for line in &lines {
        let key = line.key.as_deref().unwrap_or("(inputs not computed)");
        writeln!(out, "{}  {}  key {key}", line.id, line.freshness.name())?;
        let Some(key) = line
            .key
            .as_deref()
            .filter(|_| matches!(line.freshness, Freshness::Fresh | Freshness::Damaged(_)))
        else {
            continue;
        };
        let dir = store.artifact_dir(stage, key);
        if let Ok(manifest) = store.inspect(stage, key, None, Depth::Sizes) {
            for file in &manifest.files {
                writeln!(
                    out,
                    "    {} ({})",
                    dir.join(&file.name).display(),
                    size(file.bytes as f64)
                )?;
            }
        }
    }
    Ok(out)
}

/// The stage and current key of instance `id` of `plan` when its artifact
/// exists (intact or damaged); otherwise why there is none.
pub(super) fn current_artifact(
    store: &Store,
    plan: &[Box<dyn Stage>],
    id: &InstanceId,
) -> Result<(String, String)> {
    executor::check_stage_names(plan, std::slice::from_ref(&id.stage))
        .map_err(anyhow::Error::msg)?;
    let line = executor::status(store, plan, 1)?
        .into_iter()
        .find(|line| &line.id == id)
        .with_context(|| {
            format!(
                "no instance `{id}` in the study (`ternary show {}` lists them)",
                id.stage
            )
        })?;
    let why = match line.freshness {
        Freshness::Fresh | Freshness::Damaged(_) => {
            let key = line.key.with_context(|| format!("{id} has no key"))?;
            return Ok((id.stage.clone(), key));
        }
        Freshness::Stale(reasons) => format!("stale: {}", reasons.join("; ")),
        Freshness::Missing(reason) => format!("missing: {reason}"),
    };
    bail!("{id} has no artifact under its current key ({why}); `ternary run` computes it")
}

/// The artifact whose key starts with `prefix` (at least 6 characters).
fn artifact_by_prefix(store: &Store, prefix: &str) -> Result<(String, String)> {
    if prefix.len() < 6 {
        bail!(
            "`{prefix}` is not a stage, an instance `stage[instance]` or a path; give at least 6 characters of a key"
        );
    }
    let mut matches: Vec<(String, String)> = store
        .artifacts()?
        .into_iter()
        .filter(|(_, key)| key.starts_with(prefix))
        .collect();
    match matches.len() {
        1 => Ok(matches.remove(0)),
        0 => bail!(
            "no stage, instance or artifact key `{prefix}` in {} (`ternary dag --stages` lists the stages)",
            store.root().display()
        ),
        n => bail!("`{prefix}` is ambiguous: {n} artifacts match"),
    }
}

/// The artifact in `dir`: its manifest, under a warning naming `problems`
/// when it has any, then each table ([`show_file`]) and other file. Of a
/// damaged artifact, what cannot be read is listed as unreadable under the
/// warning instead of failing the command.
fn show_artifact(dir: &Path, problems: &[String], rows: usize) -> Result<String> {
    let damaged = !problems.is_empty();
    let mut out = String::new();
    if damaged {
        writeln!(
            out,
            "DAMAGED {}: {} (not to be trusted; the next run recomputes it)",
            dir.display(),
            problems.join("; ")
        )?;
    }
    let manifest_path = dir.join("manifest.json");
    let value = std::fs::read_to_string(&manifest_path)
        .with_context(|| format!("reading {}", manifest_path.display()))
        .and_then(|manifest| {
            let value: serde_json::Value = serde_json::from_str(&manifest)
                .with_context(|| format!("decoding {}", manifest_path.display()))?;
            Ok((manifest, value))
        });
    let value = match value {
        Ok((manifest, value)) => {
            writeln!(out, "{manifest}")?;
            value
        }
        Err(error) if damaged => {
            writeln!(
                out,
                "== {}: unreadable ({error:#})",
                manifest_path.display()
            )?;
            return Ok(out);
        }
        Err(error) => return Err(error),
    };
    for file in value["files"].as_array().into_iter().flatten() {
        let name = file["name"].as_str().unwrap_or_default();
        if is_table_file(name) {
            match show_file(&dir.join(name), rows) {
                Ok(text) => out.push_str(&text),
                Err(error) if damaged => writeln!(
                    out,
                    "== {}: unreadable ({error:#})",
                    dir.join(name).display()
                )?,
                Err(error) => return Err(error),
            }
        } else {
            writeln!(
                out,
                "== {} ({} bytes)",
                dir.join(name).display(),
                file["bytes"]
            )?;
        }
    }
    Ok(out)
}
