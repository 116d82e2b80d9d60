//! The bundle's `README.md`: what a stranger needs to use the dataset in five
//! minutes, built from the resources of `datapackage.json`.
//!
//! Order: overview, the headline tables (the study's summaries), a naming
//! guide, how to read a table, the figures, then every other kind of table.
//! A table kind (one stage's table of one name, `kernel/<instance>/kernel.parquet`)
//! has one schema, written once with the list of files that share it, so
//! the README grows with the number of kinds, not of instances. Per-file
//! provenance (code version, key, parameters) stays in `datapackage.json`.

use std::fmt::Write as _;

use serde_json::Value;

use super::{PAPER_ARXIV, PAPER_CITATION, PAPER_DOI};
use crate::config::{AuthorConfig, PublicationConfig};
use crate::contract::{UNIT_PER_PANEL, UNIT_PER_ROW};
use crate::physics::potential::FAMILIES;
use crate::pipeline::executor::tool_version;

/// Stages whose (study-wide) tables summarise the study: shown first.
const HEADLINE_STAGES: [&str; 3] = ["table", "paper", "gases"];

/// Tables that share one schema: one stage's table of one name across
/// instances.
struct TableKind<'a> {
    /// Stage that writes them.
    stage: &'a str,
    /// Table name (the file stem, or the stage's only table).
    table: &'a str,
    /// The schema's `fields`.
    fields: &'a Value,
    /// Their resources, in bundle order.
    files: Vec<&'a Value>,
}

impl TableKind<'_> {
    fn is_headline(&self) -> bool {
        HEADLINE_STAGES.contains(&self.stage)
    }
}

/// A string field of a resource (empty when absent).
fn text<'a>(value: &'a Value, field: &str) -> &'a str {
    value[field].as_str().unwrap_or_default()
}

/// The table resources grouped by kind (stage, table name and schema), in
/// order of first appearance.
fn table_kinds<'a>(tables: &[&'a Value]) -> Vec<TableKind<'a>> {
    let mut kinds: Vec<TableKind> = Vec::new();
    for resource in tables {
        let meta = &resource["ternary"];
        let (stage, table, fields) = (
            text(meta, "stage"),
            text(meta, "table"),
            &resource["schema"]["fields"],
        );
        match kinds
            .iter_mut()
            .find(|k| k.stage == stage && k.table == table && k.fields == fields)
        {
            Some(kind) => kind.files.push(resource),
            None => kinds.push(TableKind {
                stage,
                table,
                fields,
                files: vec![resource],
            }),
        }
    }
    kinds
}

/// The bundle's README from its table and figure resources (in bundle order).
pub(super) fn bundle_readme(publication: &PublicationConfig, resources: &[Value]) -> String {
    let tables: Vec<&Value> = resources.iter().filter(|r| r["type"] == "table").collect();
    let figures: Vec<&Value> = resources.iter().filter(|r| r["type"] != "table").collect();
    let kinds = table_kinds(&tables);
    let mut out = String::new();
    overview(&mut out, publication, &kinds, &figures);
    let (headline, other): (Vec<&TableKind>, Vec<&TableKind>) =
        kinds.iter().partition(|k| k.is_headline());
    if !headline.is_empty() {
        let _ = writeln!(out, "## Headline tables\n");
        for kind in headline {
            schema(&mut out, kind, variant(&kinds, kind));
        }
    }
    naming_guide(&mut out);
    reading(&mut out, &tables);
    figure_list(&mut out, &figures);
    if !other.is_empty() {
        let _ = writeln!(
            out,
            "## Other tables\n\nOne section per kind of table, with the files that share its columns.\n"
        );
        for kind in other {
            schema(&mut out, kind, variant(&kinds, kind));
        }
    }
    out
}

/// `kind`'s variant number among the kinds of its stage and table name when
/// several schemas share them (`None` when it is the only one), so every
/// schema heading is unique.
fn variant(kinds: &[TableKind], kind: &TableKind) -> Option<usize> {
    let same: Vec<&TableKind> = kinds
        .iter()
        .filter(|k| k.stage == kind.stage && k.table == kind.table)
        .collect();
    (same.len() > 1).then(|| {
        1 + same
            .iter()
            .position(|k| k.fields == kind.fields)
            .unwrap_or_default()
    })
}

/// Title, description, authors, units and what the bundle holds.
fn overview(
    out: &mut String,
    publication: &PublicationConfig,
    kinds: &[TableKind],
    figures: &[&Value],
) {
    let _ = writeln!(out, "# {}\n", publication.title);
    let _ = writeln!(out, "{}\n", publication.description);
    let authors: Vec<String> = publication
        .authors
        .iter()
        .map(AuthorConfig::display_name)
        .collect();
    if !authors.is_empty() {
        let _ = writeln!(out, "Authors: {}.\n", authors.join("; "));
    }
    let _ = writeln!(
        out,
        "Version {}, licence {}. Written by {} from the study configuration `pipeline.toml` \
         (included). The model and its units follow {PAPER_CITATION} (doi:{PAPER_DOI}, \
         arXiv:{PAPER_ARXIV}): velocities in v_th = sqrt(kT/m), lengths in l = l0 (eps/kT)^(1/n) \
         (n = 6 for Lennard-Jones), times in l/v_th, rates in rho^2 l v_th.\n",
        publication.version,
        publication.license,
        tool_version()
    );
    let tables: usize = kinds.iter().map(|k| k.files.len()).sum();
    let _ = writeln!(
        out,
        "The bundle holds {tables} tables (Parquet) of {} kinds and {} figure files \
         (SVG and PNG). `datapackage.json` (Frictionless Data Package v2) describes every \
         file: a table's columns with types, units and descriptions, and the stage, code \
         version, key and full parameters that produced it (`frictionless validate \
         datapackage.json` checks it against the tables). `SHA256SUMS` lists every file with \
         its SHA-256 (`sha256sum -c SHA256SUMS`); `ternary verify --bundle .` checks both. \
         `report/index.html` is the study at a glance (open it in a browser): the summary \
         tables, every figure with its caption, what each stage computed and the provenance.\n",
        kinds.len(),
        figures.len()
    );
}

/// How paths, instance names and units are spelled; the potentials' ids
/// as every family of [`FAMILIES`] spells them.
fn naming_guide(out: &mut String) {
    let families: Vec<String> = FAMILIES
        .iter()
        .map(|family| format!("`{}` {}", family.id_pattern(), family.id_meaning))
        .collect();
    let _ = writeln!(
        out,
        "## Naming guide\n\n\
         * `<stage>/<instance>.parquet` is a stage's only table, \
         `<stage>/<instance>/<table>.parquet` one of its several tables.\n\
         * `<instance>` names what the stage was run for: {}, \
         `_u<u'>` the velocity u' the kernel is taken at (v_th), `_rho<density>` the density \
         (0: the dilute limit), `study` the whole study; an MD ring (`md`, `compare`) is \
         named as in `pipeline.toml`, a figure by its name. Values are cut to six significant digits (`rho5.38226e-5`); the full \
         instance name and parameters of each file are in its `ternary` entry in \
         `datapackage.json`.\n\
         * Units: `1` is dimensionless; a label column has none; `{UNIT_PER_ROW}` means \
         the column's unit differs by row and each row's unit is in its text column `unit`; \
         `{UNIT_PER_PANEL}` (figure data) means the unit of the panel's axis.\n",
        families.join(", ")
    );
}

/// Reading one table with Python, R and DuckDB; the example is the first
/// headline table with rows (else the first table with rows).
fn reading(out: &mut String, tables: &[&Value]) {
    let rows = |r: &&&Value| r["ternary"]["rows"].as_u64().unwrap_or(0) > 0;
    let example = tables
        .iter()
        .filter(rows)
        .find(|r| HEADLINE_STAGES.contains(&text(&r["ternary"], "stage")))
        .or_else(|| tables.iter().find(rows))
        .map_or("table.parquet", |r| text(r, "path"));
    let _ = writeln!(out, "## Reading a table\n");
    let _ = writeln!(
        out,
        "A value that is missing or undefined is a null; a column holds nulls only where its schema says what a null means (`null` in `datapackage.json`, the `null` column metadata in the Parquet file), and every other column is `required`. No table holds NaN or infinity.\n"
    );
    let _ = writeln!(
        out,
        "Python (polars):\n\n    import polars as pl\n    frame = pl.read_parquet(\"{example}\")\n"
    );
    let _ = writeln!(
        out,
        "Python (pyarrow), with units from the column metadata:\n\n    import pyarrow.parquet as pq\n    table = pq.read_table(\"{example}\")\n    print(table.schema.field(0).metadata)   # {{b'unit': ..., b'description': ...}}\n"
    );
    let _ = writeln!(
        out,
        "R (arrow):\n\n    library(arrow)\n    frame <- read_parquet(\"{example}\")\n"
    );
    let _ = writeln!(
        out,
        "DuckDB:\n\n    SELECT * FROM '{example}';\n    SELECT * FROM parquet_kv_metadata('{example}');\n"
    );
}

/// One line per figure: its files (print and `_screen` sizes).
fn figure_list(out: &mut String, figures: &[&Value]) {
    if figures.is_empty() {
        return;
    }
    let _ = writeln!(
        out,
        "## Figures\n\nEach figure as SVG and PNG (600 ppi) for print and as `_screen` \
         versions; the plotted points are the figure's `points.parquet` (see its table \
         kind below).\n"
    );
    let mut names: Vec<&str> = Vec::new();
    for figure in figures {
        let name = text(&figure["ternary"], "instance");
        if !names.contains(&name) {
            names.push(name);
        }
    }
    for name in names {
        let files: Vec<String> = figures
            .iter()
            .filter(|f| text(&f["ternary"], "instance") == name)
            .map(|f| format!("`{}`", text(f, "path")))
            .collect();
        let _ = writeln!(out, "* `{name}`: {}", files.join(", "));
    }
    let _ = writeln!(out);
}

/// A table's path as a pattern with `<instance>` for its instance part, and
/// that part: `kernel/<instance>/kernel.parquet` and `ipp-6_u0_rho0`.
fn path_pattern(path: &str) -> (String, &str) {
    let parts: Vec<&str> = path.split('/').collect();
    let Some(part) = parts.get(1) else {
        return (path.to_string(), path);
    };
    let instance = part.strip_suffix(".parquet").unwrap_or(part);
    let pattern = path.replacen(&format!("/{instance}"), "/<instance>", 1);
    (pattern, instance)
}

/// The files of a table kind with their rows: as one path pattern and the
/// instances when they share it, else path by path.
fn files(out: &mut String, files: &[&Value]) {
    let rows = |f: &Value| f["ternary"]["rows"].clone();
    let patterns: Vec<(String, &str)> = files
        .iter()
        .map(|f| path_pattern(text(f, "path")))
        .collect();
    if patterns
        .iter()
        .all(|(pattern, _)| *pattern == patterns[0].0)
    {
        let instances: Vec<String> = patterns
            .iter()
            .zip(files)
            .map(|((_, instance), f)| format!("`{instance}` ({})", rows(f)))
            .collect();
        let _ = writeln!(
            out,
            "Files `{}`, instances (rows): {}.\n",
            patterns[0].0,
            instances.join(", ")
        );
    } else {
        let paths: Vec<String> = files
            .iter()
            .map(|f| format!("`{}` ({} rows)", text(f, "path"), rows(f)))
            .collect();
        let _ = writeln!(out, "Files: {}.\n", paths.join(", "));
    }
}

/// A table kind's heading, description, files and columns.
fn schema(out: &mut String, kind: &TableKind, variant: Option<usize>) {
    let suffix = variant.map_or(String::new(), |v| format!(" (columns variant {v})"));
    let _ = writeln!(
        out,
        "### `{}` table `{}`{suffix}\n\n{}\n",
        kind.stage,
        kind.table,
        text(kind.files[0], "description")
    );
    files(out, &kind.files);
    let _ = writeln!(out, "| column | type | unit | description | null means |");
    let _ = writeln!(out, "|---|---|---|---|---|");
    for field in kind.fields.as_array().into_iter().flatten() {
        let null = if field["constraints"]["required"] == true {
            "never null"
        } else {
            text(field, "null")
        };
        let _ = writeln!(
            out,
            "| `{}` | {} | {} | {} | {} |",
            text(field, "name"),
            text(field, "type"),
            text(field, "unit").replace('|', "\\|"),
            text(field, "description").replace('|', "\\|"),
            null.replace('|', "\\|"),
        );
    }
    let _ = writeln!(out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// The guide spells the potentials' ids from `FAMILIES`, as it did when
    /// written by hand.
    #[test]
    fn the_naming_guide_spells_every_family_id() {
        let mut out = String::new();
        naming_guide(&mut out);
        assert!(
            out.contains(
                "`ipp-<n>` an inverse power law potential of exponent n, \
                 `lj-<theta>` Lennard-Jones at theta = kT/eps, \
                 `morse-<theta>-<x0>` Morse at theta = kT/eps with its well at x0 = a d0, \
                 `_u<u'>`"
            ),
            "{out}"
        );
    }

    /// Resources in the default study's shape: 253 tables of 27 kinds
    /// (the kernels' three per instance, 33 instances; 38 moments, ...),
    /// with 10 columns of 60-character descriptions each (its kinds' columns
    /// average 900 bytes of names and descriptions), and 13 figures in 4
    /// files each.
    fn default_shape() -> Vec<Value> {
        let kinds: [(&str, &str, usize); 10] = [
            ("kernel", "kernel", 33),
            ("kernel", "kernel_log", 33),
            ("kernel", "kernel_replicates", 33),
            ("moments", "moments", 38),
            ("fit", "fit", 30),
            ("figures", "points", 13),
            ("md", "h", 11),
            ("sweep", "rates", 10),
            ("table", "table", 1),
            ("paper", "paper", 1),
        ];
        let fields: Vec<Value> = (0..10)
            .map(|k| {
                json!({"name": format!("column_{k}"), "type": "number", "unit": "rho^2 l v_th",
                       "description": "x".repeat(60)})
            })
            .collect();
        let mut resources = Vec::new();
        for k in 0..27 {
            let (stage, table, count) = kinds.get(k).copied().unwrap_or(("other", "t", 6));
            let table = if k >= kinds.len() {
                format!("{table}{k}")
            } else {
                table.into()
            };
            for i in 0..count {
                resources.push(json!({
                    "path": format!("{stage}/lj-0.1052_u-0.25_rho5.38226e-{i}/{table}.parquet"),
                    "type": "table",
                    "description": "y".repeat(100),
                    "schema": {"fields": fields},
                    "ternary": {"stage": stage, "table": table, "instance": "i", "rows": 1000},
                }));
            }
        }
        for figure in 0..13 {
            for file in ["a.svg", "a.png", "a_screen.svg", "a_screen.png"] {
                resources.push(json!({
                    "path": format!("figures/figure_{figure}/{file}"),
                    "ternary": {"stage": "figures", "instance": format!("figure_{figure}")},
                }));
            }
        }
        resources
    }

    #[test]
    fn the_readme_of_the_default_shape_is_short_with_each_schema_once() {
        let resources = default_shape();
        assert!(resources.len() >= 253 + 52);
        let readme = bundle_readme(&PublicationConfig::default(), &resources);
        assert!(readme.len() < 60_000, "{} bytes", readme.len());
        let headings: Vec<&str> = readme.lines().filter(|l| l.starts_with("### ")).collect();
        assert_eq!(headings.len(), 27, "{headings:?}");
        let headline = readme.find("### `table` table `table`").unwrap();
        let other = readme.find("### `kernel` table `kernel`").unwrap();
        assert!(
            headline < other && headline < 3_000,
            "headline tables first"
        );
    }

    #[test]
    fn a_path_pattern_names_the_instance() {
        assert_eq!(
            path_pattern("kernel/ipp-6_u0_rho0/kernel.parquet"),
            (
                "kernel/<instance>/kernel.parquet".to_string(),
                "ipp-6_u0_rho0"
            )
        );
        assert_eq!(
            path_pattern("fit/ipp-6_u0_rho0.parquet"),
            ("fit/<instance>.parquet".to_string(), "ipp-6_u0_rho0")
        );
    }
}
