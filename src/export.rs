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

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use arrow::datatypes::DataType;
use serde_json::{Value, json};

use crate::config::{AuthorConfig, PublicationConfig, Study, license_url};
use crate::pipeline::Stage;
use crate::pipeline::code::CodeRecord;
use crate::pipeline::executor::{self, Freshness, tool_version};
use crate::pipeline::key::sha256_hex;
use crate::pipeline::store::{Depth, Store};
use crate::pipeline::table::{is_table_file, read_parquet_footer};
use crate::report::html;

mod readme;

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
    let staging = prepare_target(dir)?;
    let placed =
        write_bundle(study, store, plan, &entries, &staging.dir).and_then(|()| staging.place(dir));
    if let Err(error) = placed {
        let _ = fs::remove_dir_all(&staging.dir);
        return Err(error);
    }
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

/// Where a bundle is written before it appears at its target.
struct BundleStaging {
    /// The staging directory.
    dir: PathBuf,
    /// `true` when it lies inside the (empty) target, which may be a mount
    /// point: its entries are then moved up one by one; otherwise the whole
    /// directory is renamed onto the target.
    inside: bool,
}

impl BundleStaging {
    /// Moves the written bundle to `target`.
    fn place(&self, target: &Path) -> Result<()> {
        let moved = |from: &Path, to: &Path| {
            fs::rename(from, to).with_context(|| format!("moving the bundle into {}", to.display()))
        };
        if !self.inside {
            return moved(&self.dir, target);
        }
        for entry in
            fs::read_dir(&self.dir).with_context(|| format!("reading {}", self.dir.display()))?
        {
            let name = entry?.file_name();
            moved(&self.dir.join(&name), &target.join(&name))?;
        }
        fs::remove_dir(&self.dir).with_context(|| format!("removing {}", self.dir.display()))
    }
}

/// Prefix of a staging directory inside an existing empty target.
const INSIDE_STAGING: &str = ".export-";

/// Checks the target `dir` (missing, or an empty directory, which may be a
/// mount point), removes staging debris of exports that were killed (named
/// for a process that no longer runs), and creates the staging directory:
/// inside an existing target (a mount point cannot be renamed over), beside
/// a missing one. Every error names its path.
fn prepare_target(dir: &Path) -> Result<BundleStaging> {
    let name = dir
        .file_name()
        .with_context(|| format!("{}: the bundle directory has no name", dir.display()))?
        .to_string_lossy()
        .into_owned();
    let parent = dir
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let beside = format!(".{name}.export-");
    remove_dead_staging(parent, &beside)?;
    let pid = std::process::id();
    if dir.exists() {
        if !dir.is_dir() {
            bail!(
                "{} is a file, not a directory: export into a new or empty directory",
                dir.display()
            );
        }
        remove_dead_staging(dir, INSIDE_STAGING)?;
        let listing = fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))?;
        if listing.count() > 0 {
            bail!(
                "{} is not empty: export into a new or empty directory",
                dir.display()
            );
        }
        let staging = dir.join(format!("{INSIDE_STAGING}{pid}"));
        fs::create_dir(&staging).with_context(|| format!("creating {}", staging.display()))?;
        return Ok(BundleStaging {
            dir: staging,
            inside: true,
        });
    }
    fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    let staging = parent.join(format!("{beside}{pid}"));
    if staging.exists() {
        fs::remove_dir_all(&staging).with_context(|| format!("removing {}", staging.display()))?;
    }
    fs::create_dir(&staging).with_context(|| format!("creating {}", staging.display()))?;
    Ok(BundleStaging {
        dir: staging,
        inside: false,
    })
}

/// Removes the directories `<prefix><pid>` in `dir` whose process no longer
/// runs: what an export killed midway left.
fn remove_dead_staging(dir: &Path, prefix: &str) -> Result<()> {
    let Ok(listing) = fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in listing.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = name
            .strip_prefix(prefix)
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        let running = Path::new("/proc").join(pid.to_string()).exists();
        if !running && entry.path().is_dir() {
            fs::remove_dir_all(entry.path())
                .with_context(|| format!("removing {}", entry.path().display()))?;
        }
    }
    Ok(())
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

/// Significant digits of a parameter value in a bundle path.
const NAME_DIGITS: usize = 6;

/// A parameter value, short: the shorter of its shortest round-trip form
/// (when that has at most `NAME_DIGITS` significant digits) and its
/// `NAME_DIGITS`-digit exponent form without trailing zeros: `0`, `-0.25`,
/// `5.38226e-5`, `1e-20`.
fn short_number(value: f64) -> String {
    let exponent = format!("{value:.*e}", NAME_DIGITS - 1);
    let (mantissa, power) = exponent.split_once('e').unwrap_or((&exponent, "0"));
    let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
    let rounded = format!("{mantissa}e{power}");
    let plain = value.to_string();
    let significant = plain
        .trim_start_matches(['-', '0', '.'])
        .chars()
        .filter(char::is_ascii_digit)
        .count();
    if significant <= NAME_DIGITS && plain.len() <= rounded.len() {
        plain
    } else {
        rounded
    }
}

/// An instance name with each `<label><number>` part between underscores
/// (`rho0.00005382255169036728`, `lj-0.1052`) cut by `short_number`.
fn short_instance(instance: &str) -> String {
    let short_part = |part: &str| {
        let at = part
            .find(|c: char| c.is_ascii_digit() || matches!(c, '-' | '.'))
            .unwrap_or(part.len());
        let (label, number) = part.split_at(at);
        match number.parse::<f64>() {
            Ok(value) if value.is_finite() => format!("{label}{}", short_number(value)),
            _ => part.to_string(),
        }
    };
    instance
        .split('_')
        .map(short_part)
        .collect::<Vec<_>>()
        .join("_")
}

/// The bundle name of each of the plan's `instances`: its `short_instance`,
/// or its full name where two instances' short names coincide. It does not
/// depend on the selection, so a name is the same in every bundle of a study.
fn bundle_names<'a>(instances: impl Iterator<Item = &'a str>) -> BTreeMap<&'a str, String> {
    let instances: BTreeSet<&str> = instances.collect();
    let mut sharing: BTreeMap<String, usize> = BTreeMap::new();
    for instance in &instances {
        *sharing.entry(short_instance(instance)).or_default() += 1;
    }
    instances
        .into_iter()
        .map(|instance| {
            let short = short_instance(instance);
            let name = if sharing[&short] == 1 {
                short
            } else {
                instance.to_string()
            };
            (instance, name)
        })
        .collect()
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
        let target = dir.join(&entry.path);
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

/// The bundle's files besides the tables and the two that describe the rest
/// (`datapackage.json`, `SHA256SUMS`): path, format, media type, description.
const DOCUMENTS: [(&str, &str, &str, &str); 4] = [
    (
        "README.md",
        "md",
        "text/markdown",
        "what each table holds and how to read it",
    ),
    (
        "pipeline.toml",
        "toml",
        "application/toml",
        "the study configuration that produced the tables",
    ),
    (
        "CITATION.cff",
        "cff",
        "application/x-yaml",
        "how to cite the dataset (Citation File Format 1.2.0)",
    ),
    (
        ".zenodo.json",
        "json",
        "application/json",
        "deposit metadata for Zenodo",
    ),
];

/// Writes the study's HTML report into `report/` (`ternary report`) and
/// returns the descriptors of its page and figures.
fn report_resources(
    study: &Study,
    store: &Store,
    plan: &[Box<dyn Stage>],
    dir: &Path,
) -> Result<Vec<Value>> {
    let folder = Path::new(REPORT);
    html::write(study, store, plan, &dir.join(folder))?;
    let mut resources = vec![document_resource(
        dir,
        &format!("{REPORT}/{}", html::PAGE),
        "html",
        "text/html",
        "the study report: tables, figures with captions, stages and provenance (open in a browser)",
    )?];
    let figures = folder.join(html::FIGURES);
    for entry in fs::read_dir(dir.join(&figures))? {
        let name = entry?.file_name().to_string_lossy().into_owned();
        resources.push(document_resource(
            dir,
            &format!("{REPORT}/{}/{name}", html::FIGURES),
            "png",
            "image/png",
            "a figure of the study report, as it shows it",
        )?);
    }
    resources.sort_by(|a, b| a["path"].as_str().cmp(&b["path"].as_str()));
    Ok(resources)
}

/// The descriptor of a non-tabular file of the bundle.
fn document_resource(
    dir: &Path,
    path: &str,
    format: &str,
    mediatype: &str,
    description: &str,
) -> Result<Value> {
    let bytes = fs::read(dir.join(path))?;
    let name: String = path
        .trim_start_matches('.')
        .to_lowercase()
        .replace(['.', '/'], "-");
    Ok(json!({
        "name": name,
        "path": path,
        "format": format,
        "mediatype": mediatype,
        "bytes": bytes.len(),
        "hash": format!("sha256:{}", sha256_hex(&bytes)),
        "description": description,
    }))
}

/// A Data Package resource name: lower-case, `[a-z0-9._-]`.
fn resource_name(entry: &Entry) -> String {
    format!("{}.{}.{}", entry.stage, entry.name, entry.table)
        .to_lowercase()
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '-'
            }
        })
        .collect()
}

fn check_unique_names(resources: &[Value]) -> Result<()> {
    let mut seen = std::collections::BTreeSet::new();
    for resource in resources {
        let name = resource["name"].as_str().unwrap_or_default();
        if !seen.insert(name.to_string()) {
            bail!("two tables would share the resource name `{name}`");
        }
    }
    Ok(())
}

/// The descriptor of a figure (or another non-tabular file) of an artifact.
fn figure_resource(entry: &Entry, bytes: u64) -> Value {
    let (format, mediatype) = match entry.path.rsplit_once('.').map(|(_, e)| e) {
        Some("svg") => ("svg", "image/svg+xml"),
        Some("png") => ("png", "image/png"),
        Some(other) => (other, "application/octet-stream"),
        None => ("", "application/octet-stream"),
    };
    json!({
        "name": resource_name(entry),
        "path": entry.path,
        "format": format,
        "mediatype": mediatype,
        "bytes": bytes,
        "hash": format!("sha256:{}", entry.sha256),
        "description": format!("figure `{}` of `{}[{}]`", entry.table, entry.stage, entry.instance),
        "ternary": {
            "stage": entry.stage,
            "code": entry.code,
            "instance": entry.instance,
            "key": entry.key,
        },
    })
}

/// Table Schema type of an Arrow column type.
fn field_type(data_type: &DataType) -> &'static str {
    match data_type {
        DataType::Float32 | DataType::Float64 => "number",
        DataType::Boolean => "boolean",
        DataType::Utf8 | DataType::LargeUtf8 => "string",
        t if t.is_integer() => "integer",
        _ => "any",
    }
}

/// The descriptor of one table: path, Table Schema from the file's column
/// metadata (a nullable column's `null` says what a null means; every other
/// column is `required`; only a null is missing, not an empty string), and
/// the artifact it came from. No `bytes` or `hash`:
/// frictionless reads Parquet through pandas, cannot count its bytes and
/// reports every such table invalid (`byte-count ... actual is None`);
/// `SHA256SUMS` and `verify --bundle` check a table's bytes instead.
fn resource(entry: &Entry, file: &Path) -> Result<Value> {
    let (schema, metadata, rows) = read_parquet_footer(file)?;
    let fields: Vec<Value> = schema
        .fields()
        .iter()
        .map(|field| {
            let meta = field.metadata();
            let mut value = json!({
                "name": field.name(),
                "type": field_type(field.data_type()),
                "description": meta.get("description").cloned().unwrap_or_default(),
            });
            if let Some(unit) = meta.get("unit").filter(|u| !u.is_empty()) {
                value["unit"] = json!(unit);
            }
            // A nullable column says what a null means; any other has none.
            match meta.get("null").filter(|_| field.is_nullable()) {
                Some(meaning) => value["null"] = json!(meaning),
                None => value["constraints"] = json!({ "required": true }),
            }
            value
        })
        .collect();
    let description = metadata
        .get("ternary.description")
        .cloned()
        .unwrap_or_else(|| format!("table `{}` of stage `{}`", entry.table, entry.stage));
    Ok(json!({
        "name": resource_name(entry),
        "path": entry.path,
        "type": "table",
        "format": "parquet",
        "mediatype": PARQUET_MEDIATYPE,
        "description": description,
        // Only a Parquet null is missing: an empty string is a value (the
        // paper table's `table_i_column` of a row outside Table I, a unit of
        // 1), and frictionless's default would read it as missing and fail
        // a `required` column.
        "schema": { "fields": fields, "missingValues": [] },
        "ternary": {
            "stage": entry.stage,
            "code": entry.code,
            "instance": entry.instance,
            "table": entry.table,
            "key": entry.key,
            "rows": rows,
            "params": entry.params,
        },
    }))
}

/// `https://orcid.org/<id>`.
fn orcid_url(orcid: &str) -> String {
    format!("https://orcid.org/{orcid}")
}

fn datapackage(publication: &PublicationConfig, resources: Vec<Value>) -> Value {
    let mut license = json!({ "name": publication.license });
    if let Some(path) = license_url(&publication.license) {
        license["path"] = json!(path);
    }
    let contributors: Vec<Value> = publication
        .authors
        .iter()
        .map(|author| {
            let mut value = json!({ "title": author.display_name(), "roles": ["creator"] });
            if let Some(given) = &author.given_names {
                value["givenName"] = json!(given);
            }
            if let Some(family) = &author.family_names {
                value["familyName"] = json!(family);
            }
            if let Some(orcid) = &author.orcid {
                value["path"] = json!(orcid_url(orcid));
            }
            if let Some(affiliation) = &author.affiliation {
                value["organization"] = json!(affiliation);
            }
            value
        })
        .collect();
    let mut descriptor = json!({
        "$schema": DATAPACKAGE_SCHEMA,
        "name": publication.name,
        "title": publication.title,
        "version": publication.version,
        "description": publication.description,
        "licenses": [license],
        "contributors": contributors,
        "sources": [
            { "title": PAPER_CITATION, "path": format!("https://doi.org/{PAPER_DOI}") },
            { "title": format!("arXiv:{PAPER_ARXIV}"), "path": format!("https://arxiv.org/abs/{PAPER_ARXIV}") },
        ],
        "keywords": publication.keywords,
        "resources": resources,
        "ternary": { "tool": tool_version(), "configuration": "pipeline.toml" },
    });
    if let Some(date) = &publication.date {
        descriptor["created"] = json!(format!("{date}T00:00:00Z"));
    }
    descriptor
}

/// A YAML string (double-quoted, escaped): safe for any text.
fn yaml(text: &str) -> String {
    serde_json::to_string(text).unwrap_or_default()
}

fn citation_cff(publication: &PublicationConfig) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "cff-version: 1.2.0");
    let _ = writeln!(
        out,
        "message: {}",
        yaml(&format!(
            "If you use this dataset, please cite it as below. It reproduces and extends \
             {PAPER_CITATION}, doi:{PAPER_DOI}, arXiv:{PAPER_ARXIV}."
        ))
    );
    let _ = writeln!(out, "type: dataset");
    let _ = writeln!(out, "title: {}", yaml(&publication.title));
    let _ = writeln!(out, "version: {}", yaml(&publication.version));
    if let Some(date) = &publication.date {
        let _ = writeln!(out, "date-released: {}", yaml(date));
    }
    let _ = writeln!(out, "license: {}", yaml(&publication.license));
    let _ = writeln!(out, "abstract: {}", yaml(&publication.description));
    let _ = writeln!(out, "authors:");
    for author in &publication.authors {
        cff_author(&mut out, author);
    }
    if !publication.keywords.is_empty() {
        let _ = writeln!(out, "keywords:");
        for keyword in &publication.keywords {
            let _ = writeln!(out, "  - {}", yaml(keyword));
        }
    }
    out
}

fn cff_author(out: &mut String, author: &AuthorConfig) {
    let mut lines = Vec::new();
    if let Some(family) = &author.family_names {
        lines.push(format!("family-names: {}", yaml(family)));
    }
    if let Some(given) = &author.given_names {
        lines.push(format!("given-names: {}", yaml(given)));
    }
    if let Some(name) = &author.name {
        lines.push(format!("name: {}", yaml(name)));
    }
    if let Some(orcid) = &author.orcid {
        lines.push(format!("orcid: {}", yaml(&orcid_url(orcid))));
    }
    if let Some(affiliation) = &author.affiliation {
        lines.push(format!("affiliation: {}", yaml(affiliation)));
    }
    for (k, line) in lines.iter().enumerate() {
        let _ = writeln!(out, "  {} {line}", if k == 0 { "-" } else { " " });
    }
}

fn zenodo(publication: &PublicationConfig) -> Value {
    let creators: Vec<Value> = publication
        .authors
        .iter()
        .map(|author| {
            let mut value = json!({ "name": author.display_name() });
            if let Some(affiliation) = &author.affiliation {
                value["affiliation"] = json!(affiliation);
            }
            if let Some(orcid) = &author.orcid {
                value["orcid"] = json!(orcid);
            }
            value
        })
        .collect();
    let mut value = json!({
        "upload_type": "dataset",
        "title": publication.title,
        "description": publication.description,
        "version": publication.version,
        "license": publication.license.to_lowercase(),
        "creators": creators,
        "keywords": publication.keywords,
        "related_identifiers": [
            { "identifier": PAPER_DOI, "relation": "references", "scheme": "doi" },
            { "identifier": format!("arXiv:{PAPER_ARXIV}"), "relation": "references", "scheme": "arxiv" },
        ],
    });
    if let Some(date) = &publication.date {
        value["publication_date"] = json!(date);
    }
    value
}

/// Every file of a bundle, relative, sorted.
fn files_of(dir: &Path) -> Result<Vec<String>> {
    let mut found = Vec::new();
    let mut pending = vec![PathBuf::new()];
    while let Some(relative) = pending.pop() {
        for entry in fs::read_dir(dir.join(&relative))? {
            let entry = entry?;
            let path = relative.join(entry.file_name());
            if entry.file_type()?.is_dir() {
                pending.push(path);
            } else {
                found.push(path.to_string_lossy().into_owned());
            }
        }
    }
    found.sort();
    Ok(found)
}

/// `<sha256>  <path>` of every file but `SHA256SUMS`.
fn sha256sums(dir: &Path) -> Result<String> {
    let mut out = String::new();
    for path in files_of(dir)? {
        if path == "SHA256SUMS" {
            continue;
        }
        let bytes = fs::read(dir.join(&path))?;
        let _ = writeln!(out, "{}  {path}", sha256_hex(&bytes));
    }
    Ok(out)
}

/// Checks a bundle: the descriptor's required fields, every resource's size
/// and hash, and `SHA256SUMS` against every file. Returns the report and the
/// number of problems.
pub fn verify_bundle(dir: &Path) -> Result<(String, usize)> {
    let mut problems = Vec::new();
    let descriptor_path = dir.join("datapackage.json");
    let descriptor: Value = match fs::read(&descriptor_path) {
        Err(error) => {
            problems.push(format!("datapackage.json: {error}"));
            Value::Null
        }
        Ok(bytes) => serde_json::from_slice(&bytes).unwrap_or_else(|error| {
            problems.push(format!("datapackage.json: not JSON ({error})"));
            Value::Null
        }),
    };
    if !descriptor.is_null() {
        problems.extend(descriptor_problems(dir, &descriptor));
    }
    problems.extend(sums_problems(dir)?);
    let mut out = String::new();
    for problem in &problems {
        let _ = writeln!(out, "PROBLEM  {problem}");
    }
    let resources = descriptor["resources"].as_array().map_or(0, Vec::len);
    let _ = writeln!(
        out,
        "verify --bundle: {} resources, {} problems in {}",
        resources,
        problems.len(),
        dir.display()
    );
    Ok((out, problems.len()))
}

/// Required fields of the package and of each resource, and each resource's
/// file against its `bytes` and `hash` where it records them (a table
/// records neither: `SHA256SUMS` holds its hash).
fn descriptor_problems(dir: &Path, descriptor: &Value) -> Vec<String> {
    let mut problems = Vec::new();
    for field in [
        "$schema",
        "name",
        "title",
        "version",
        "licenses",
        "resources",
    ] {
        if descriptor.get(field).is_none_or(Value::is_null) {
            problems.push(format!("datapackage.json: missing `{field}`"));
        }
    }
    let resources = descriptor["resources"]
        .as_array()
        .cloned()
        .unwrap_or_default();
    if resources.is_empty() {
        problems.push("datapackage.json: no resource".into());
    }
    for (k, resource) in resources.iter().enumerate() {
        let Some(path) = resource["path"].as_str() else {
            problems.push(format!("datapackage.json: resources[{k}] has no `path`"));
            continue;
        };
        let required: &[&str] = if resource["type"] == "table" {
            &["name", "format", "mediatype", "schema"]
        } else {
            &["name", "format", "mediatype", "bytes", "hash"]
        };
        for field in required {
            if resource.get(field).is_none_or(Value::is_null) {
                problems.push(format!("{path}: the descriptor lacks `{field}`"));
            }
        }
        if path.split('/').any(|part| part == ".." || part.is_empty()) {
            problems.push(format!("{path}: not a path inside the bundle"));
            continue;
        }
        match fs::read(dir.join(path)) {
            Err(error) => problems.push(format!("{path}: {error}")),
            Ok(bytes) => problems.extend(size_and_hash_problems(path, resource, &bytes)),
        }
    }
    problems
}

/// A file's size and SHA-256 against the `bytes` and `hash` its resource
/// records, when it records them.
fn size_and_hash_problems(path: &str, resource: &Value, bytes: &[u8]) -> Vec<String> {
    let mut problems = Vec::new();
    if let Some(recorded) = resource.get("bytes")
        && recorded.as_u64() != Some(bytes.len() as u64)
    {
        problems.push(format!(
            "{path}: {} bytes but the descriptor records {recorded}",
            bytes.len()
        ));
    }
    let hash = format!("sha256:{}", sha256_hex(bytes));
    if let Some(recorded) = resource.get("hash")
        && recorded.as_str() != Some(hash.as_str())
    {
        problems.push(format!(
            "{path}: {hash} but the descriptor records {recorded}"
        ));
    }
    problems
}

/// `SHA256SUMS` against the files: each listed file hashes to its line, and
/// every file of the bundle is listed.
fn sums_problems(dir: &Path) -> Result<Vec<String>> {
    let mut problems = Vec::new();
    let sums = match fs::read_to_string(dir.join("SHA256SUMS")) {
        Ok(text) => text,
        Err(error) => return Ok(vec![format!("SHA256SUMS: {error}")]),
    };
    let mut listed = BTreeMap::new();
    for line in sums.lines() {
        match line.split_once("  ") {
            Some((sha, path)) => {
                listed.insert(path.to_string(), sha.to_string());
            }
            None => problems.push(format!("SHA256SUMS: malformed line `{line}`")),
        }
    }
    for (path, sha) in &listed {
        match fs::read(dir.join(path)) {
            Err(error) => problems.push(format!("{path}: {error}")),
            Ok(bytes) if &sha256_hex(&bytes) != sha => {
                problems.push(format!("{path}: does not match its line in SHA256SUMS"))
            }
            Ok(_) => {}
        }
    }
    for path in files_of(dir)? {
        if path != "SHA256SUMS" && !listed.contains_key(&path) {
            problems.push(format!("{path}: not listed in SHA256SUMS"));
        }
    }
    Ok(problems)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_parameter_value_is_cut_to_six_significant_digits() {
        assert_eq!(
            short_instance("lj-0.1052_u0_rho0.00005382255169036728"),
            "lj-0.1052_u0_rho5.38226e-5"
        );
        assert_eq!(
            short_instance("ipp-6_u-0.25_rho0.0010324090855340624"),
            "ipp-6_u-0.25_rho1.03241e-3"
        );
        assert_eq!(short_instance("ipp-6_u-3_rho0"), "ipp-6_u-3_rho0");
        assert_eq!(short_instance("study"), "study");
        assert_eq!(short_number(1e-20), "1e-20");
        assert_eq!(short_number(2.0e-5), "2e-5");
    }

    #[test]
    fn bundle_names_are_unique_even_where_short_names_coincide() {
        let instances = [
            "ipp-6_u0_rho0.00005382255169036728",
            "ipp-6_u0_rho0.00005382255169036729",
            "ipp-6_u0_rho0.0007300234653397379",
            "ipp-6_u0_rho0",
        ];
        let names = bundle_names(instances.into_iter());
        let distinct: BTreeSet<&String> = names.values().collect();
        assert_eq!(distinct.len(), instances.len(), "{names:?}");
        assert_eq!(names[instances[0]], instances[0], "coinciding: full names");
        assert_eq!(names[instances[1]], instances[1]);
        assert_eq!(names[instances[2]], "ipp-6_u0_rho7.30023e-4");
        assert_eq!(names[instances[3]], "ipp-6_u0_rho0");
    }
}
