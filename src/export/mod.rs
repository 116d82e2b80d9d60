//! `ternary export`: the study's current artifacts as a citable,
//! self-describing dataset bundle, and `ternary verify --bundle`.
//!
//! A bundle is a directory a data repository and a reader without our code
//! both accept:
//!
//! ```text
//! datapackage.json        Frictionless Data Package v2: one resource per file
//!                         (but itself and SHA256SUMS); for a table its Table
//!                         Schema (types, units, descriptions) and the artifact
//!                         it came from, for any other file its bytes and sha256
//! CITATION.cff            Citation File Format 1.2.0 }  both from `[publication]`
//! .zenodo.json            Zenodo deposit metadata    }  (Zenodo reads only this one)
//! README.md               the headline tables, names, figures and each kind of
//!                         table once; how to read one (Python, R, DuckDB)
//! pipeline.toml           the study configuration, verbatim
//! report/index.html       the study report (`ternary report`): tables, figures
//!                         (in `report/figures/`), stages and provenance
//! SHA256SUMS              every other file, in the format `sha256sum -c` reads
//! <stage>/<instance>.parquet            a stage's only table
//! <stage>/<instance>/<table>.parquet    one of several tables
//! ```
//!
//! `<instance>` is the instance's name with each parameter value cut to six
//! significant digits (`rho5.38226e-5` for `rho0.00005382255169036728`);
//! the full name and parameters stay in the table's resource.
//!
//! Exporting the same store twice gives the same bytes: files are written in
//! sorted order and nothing records the wall-clock time (dates come from
//! `[publication]`). The bundle is written next to its target and renamed
//! into place, so it appears complete or not at all.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde_json::Value;

use crate::config::Study;
use crate::pipeline::Stage;
use crate::pipeline::code::CodeRecord;
use crate::pipeline::executor::{self, Freshness};
use crate::pipeline::key::sha256_hex;
use crate::pipeline::path_names::joined_inside;
use crate::pipeline::store::{Depth, Store};
use crate::pipeline::table::is_table_file;

mod check;
mod citation;
mod datapackage;
mod names;
mod readme;
mod staging;

pub use check::verify_bundle;
use check::{files_of, sha256sums};
use citation::{citation_cff, zenodo};
use datapackage::{
    DOCUMENTS, check_unique_names, datapackage, document_resource, figure_resource,
    report_resources, resource,
};
use names::bundle_names;
use staging::prepare_target;

/// The bundle's folder of the study report.
const REPORT: &str = "report";

/// The stages whose tables hold every launch pair and integrated scene:
/// large, and left out of a bundle unless asked for.
const SCENE_STAGES: [&str; 2] = ["launches", "collisions"];

/// Data Package v2 profile.
const DATAPACKAGE_SCHEMA: &str = "https://datapackage.org/profiles/2.0/datapackage.json";

/// IANA media type of Parquet.
const PARQUET_MEDIATYPE: &str = "application/vnd.apache.parquet";

/// The published study `ternary` reproduces.
const PAPER_DOI: &str = "10.1103/PhysRevE.110.014114";
const PAPER_CITATION: &str = "Phys. Rev. E 110, 014114 (2024)";
const PAPER_ARXIV: &str = "2403.00089";

/// What to export.
#[derive(Clone, Debug, Default)]
pub struct ExportOptions {
    /// Only these stages (all when empty).
    pub stages: Vec<String>,
    /// Only instances of these potentials (by id, e.g. `ipp-6`), plus the
    /// study-wide ones (all when empty).
    pub potentials: Vec<String>,
    /// Include the scene tables of the `launches` and `collisions` stages.
    pub include_events: bool,
}

/// One exported table: where it came from and where it goes.
struct Entry {
    stage: String,
    instance: String,
    /// The instance's short name in the bundle (`bundle_names`).
    name: String,
    key: String,
    code: CodeRecord,
    params: Value,
    table: String,
    source: PathBuf,
    path: String,
    sha256: String,
}

/// Writes the bundle of `study`'s current artifacts into `dir` (missing or
/// empty); refuses while a selected instance is stale, missing or damaged.
/// Returns a one-line summary that counts tables and figure files apart.
pub fn export(
    study: &Study,
    store: &Store,
    plan: &[Box<dyn Stage>],
    dir: &Path,
    options: &ExportOptions,
) -> Result<String> {
    if study.config.publication.authors.is_empty() {
        bail!(
            "{}: `[publication]` lists no author; add a [[publication.authors]] entry (a citation needs one)",
            study.file.display()
        );
    }
    let entries = selected_entries(study, store, plan, options)?;
    let staging = prepare_target(store, dir)?;
    if let Err(error) = write_bundle(study, store, plan, &entries, &staging.dir()) {
        let _ = staging.abandon();
        return Err(error);
    }
    staging.place(dir)?;
    let bytes: u64 = files_of(dir)?
        .iter()
        .map(|path| fs::metadata(dir.join(path)).map(|m| m.len()).unwrap_or(0))
        .sum();
    let tables = entries
        .iter()
        .filter(|entry| is_table_file(&entry.path))
        .count();
    Ok(format!(
        "export: {tables} tables, {} figure files, {bytes} bytes in {}\n",
        entries.len() - tables,
        dir.display()
    ))
}

/// The tables of the selected, fresh instances, in plan order.
fn selected_entries(
    study: &Study,
    store: &Store,
    plan: &[Box<dyn Stage>],
    options: &ExportOptions,
) -> Result<Vec<Entry>> {
    executor::check_stage_names(plan, &options.stages).map_err(anyhow::Error::msg)?;
    let known_potentials: Vec<String> = study.potentials().iter().map(|p| p.id()).collect();
    // The potential an instance is computed for: its name's first part.
    let potential_of = |instance: &str| -> Option<String> {
        let id = instance.split('_').next().unwrap_or(instance);
        known_potentials.iter().find(|known| *known == id).cloned()
    };
    if let Some(unknown) = options
        .potentials
        .iter()
        .find(|p| !known_potentials.contains(p))
    {
        bail!("`{unknown}` names no potential of the study");
    }
    let selected = |stage: &str, instance: &str| {
        (options.stages.is_empty() || options.stages.iter().any(|s| s == stage))
            && (options.include_events || !SCENE_STAGES.contains(&stage))
            && (options.potentials.is_empty()
                || potential_of(instance).is_none_or(|p| options.potentials.contains(&p)))
    };
    let lines = executor::status(store, plan, 1)?;
    let names = bundle_names(lines.iter().map(|line| line.id.instance.as_str()));
    let mut not_fresh = Vec::new();
    let mut entries = Vec::new();
    for line in &lines {
        let (stage, instance) = (&line.id.stage, &line.id.instance);
        let name = &names[instance.as_str()];
        if !selected(stage, instance) {
            continue;
        }
        let key = match (&line.freshness, &line.key) {
            (Freshness::Fresh, Some(key)) => key.clone(),
            (freshness, _) => {
                not_fresh.push(format!(
                    "{}: {}",
                    line.id,
                    crate::report::describe(freshness)
                ));
                continue;
            }
        };
        let manifest = store
            .inspect(stage, &key, None, Depth::Hashes)
            .map_err(|problems| anyhow::anyhow!("{}: {}", line.id, problems.join("; ")))?;
        let single = manifest.files.len() == 1;
        for file in &manifest.files {
            let table = file.name.trim_end_matches(".parquet").to_string();
            let path = if single {
                format!("{stage}/{name}.parquet")
            } else {
                format!("{stage}/{name}/{}", file.name)
            };
            entries.push(Entry {
                stage: stage.clone(),
                instance: instance.clone(),
                name: name.clone(),
                key: key.clone(),
                code: manifest.code.clone(),
                params: manifest.params.clone(),
                table,
                source: store.artifact_dir(stage, &key).join(&file.name),
                path,
                sha256: file.sha256.clone(),
            });
        }
    }
    if !not_fresh.is_empty() {
        bail!(
            "not exported: these instances are not up to date (run `ternary run` first):\n  {}",
            not_fresh.join("\n  ")
        );
    }
    if entries.is_empty() {
        bail!("the selection holds no table");
    }
    Ok(entries)
}

/// Copies the tables (checking each copy's hash), writes the study's report
/// and the descriptors.
fn write_bundle(
    study: &Study,
    store: &Store,
    plan: &[Box<dyn Stage>],
    entries: &[Entry],
    dir: &Path,
) -> Result<()> {
    let mut resources = Vec::new();
    for entry in entries {
        let target = joined_inside(dir, &entry.path).map_err(anyhow::Error::msg)?;
        let folder = target.parent().unwrap_or(dir);
        fs::create_dir_all(folder).with_context(|| format!("creating {}", folder.display()))?;
        let bytes = fs::read(&entry.source)
            .with_context(|| format!("reading {}", entry.source.display()))?;
        if sha256_hex(&bytes) != entry.sha256 {
            bail!(
                "{} changed while it was exported; run `ternary run` to repair it",
                entry.source.display()
            );
        }
        fs::write(&target, &bytes).with_context(|| format!("writing {}", target.display()))?;
        resources.push(if is_table_file(&entry.path) {
            resource(entry, &target)?
        } else {
            figure_resource(entry, bytes.len() as u64)
        });
    }
    let publication = &study.config.publication;
    fs::write(dir.join("CITATION.cff"), citation_cff(publication))?;
    write_json(&dir.join(".zenodo.json"), &zenodo(publication))?;
    fs::copy(&study.file, dir.join("pipeline.toml"))
        .with_context(|| format!("copying {}", study.file.display()))?;
    fs::write(
        dir.join("README.md"),
        readme::bundle_readme(publication, &resources),
    )?;
    for (path, format, mediatype, description) in DOCUMENTS {
        resources.push(document_resource(
            dir,
            path,
            format,
            mediatype,
            description,
        )?);
    }
    resources.extend(report_resources(study, store, plan, dir)?);
    check_unique_names(&resources)?;
    write_json(
        &dir.join("datapackage.json"),
        &datapackage(publication, resources),
    )?;
    let sums = sha256sums(dir)?;
    fs::write(dir.join("SHA256SUMS"), sums)?;
    Ok(())
}

fn write_json(path: &Path, value: &Value) -> Result<()> {
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    fs::write(path, text)?;
    Ok(())
}
