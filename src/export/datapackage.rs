//! `datapackage.json`: the Frictionless Data Package v2 descriptor, one
//! resource per file (a table's Table Schema with types, units and
//! descriptions; any other file's bytes and sha256).

use std::fs;
use std::path::Path;

use anyhow::{Result, bail};
use arrow_schema::DataType;
use serde_json::{Value, json};

use super::citation::orcid_url;
use super::{
    DATAPACKAGE_SCHEMA, Entry, PAPER_ARXIV, PAPER_CITATION, PAPER_DOI, PARQUET_MEDIATYPE, REPORT,
};
use crate::config::{PublicationConfig, Study, license_url};
use crate::pipeline::Stage;
use crate::pipeline::executor::tool_version;
use crate::pipeline::key::sha256_hex;
use crate::pipeline::store::Store;
use crate::pipeline::table::read_parquet_footer;
use crate::report::html;

/// The bundle's files besides the tables and the two that describe the rest
/// (`datapackage.json`, `SHA256SUMS`): path, format, media type, description.
pub(super) const DOCUMENTS: [(&str, &str, &str, &str); 4] = [
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
pub(super) fn report_resources(
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
pub(super) fn document_resource(
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

pub(super) fn check_unique_names(resources: &[Value]) -> Result<()> {
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
pub(super) fn figure_resource(entry: &Entry, bytes: u64) -> Value {
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
pub(super) fn resource(entry: &Entry, file: &Path) -> Result<Value> {
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

pub(super) fn datapackage(publication: &PublicationConfig, resources: Vec<Value>) -> Value {
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
