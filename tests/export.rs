//! `ternary export` and `ternary verify --bundle`, checked by tools that are
//! not ours: the `frictionless` validator, DuckDB and polars (Python) and
//! `sha256sum -c`.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::{
    files_under, flip_byte, run_counts, small_study, stderr, stdout, strace_works, ternary,
    workspace, write_config,
};

const PUBLICATION: &str = r#"
[publication]
name = "ternary-test"
title = "A test bundle"
description = "A small study for checking exports."
version = "0.1.0"
date = "2026-11-23"
keywords = ["test"]

[[publication.authors]]
given_names = "Ada"
family_names = "Lovelace"
orcid = "0000-0002-1825-0097"
affiliation = "Analytical Engines Ltd"

[[publication.authors]]
name = "The ternary developers"
"#;

/// A computed small study with a `[publication]` section.
fn computed(name: &str) -> (PathBuf, PathBuf) {
    let dir = workspace(name);
    let config = write_config(&dir, &format!("{}{PUBLICATION}", small_study("data")));
    run_counts(&config, &[]);
    (config, dir)
}

fn export(config: &Path, bundle: &Path, extra: &[&str]) -> std::process::Output {
    let bundle = bundle.to_string_lossy().into_owned();
    let args: Vec<&str> = [&["export", bundle.as_str()][..], extra].concat();
    ternary(config, &args)
}

fn verify_bundle(config: &Path, bundle: &Path) -> std::process::Output {
    ternary(config, &["verify", "--bundle", &bundle.to_string_lossy()])
}

fn python(script: &str, dir: &Path) -> String {
    let output = Command::new("python3")
        .arg("-c")
        .arg(script)
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "python failed (install the README's test packages): {}",
        stderr(&output)
    );
    stdout(&output)
}

/// `frictionless validate datapackage.json`, the plain command a reader
/// runs (it failed on every table's `bytes` until the tables dropped them),
/// passes. Skipped, saying why, only where frictionless is not installed.
fn assert_frictionless_valid(bundle: &Path) {
    let importable = Command::new("python3")
        .args(["-c", "import frictionless"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !importable {
        eprintln!("skipped `frictionless validate`: python3 cannot import frictionless");
        return;
    }
    let validation = Command::new("python3")
        .args(["-m", "frictionless", "validate", "datapackage.json"])
        .current_dir(bundle)
        .output()
        .unwrap();
    assert!(
        validation.status.success(),
        "frictionless: {}{}",
        stdout(&validation),
        stderr(&validation)
    );
}

/// Rows and the sum of the first numeric column with a finite sum, as
/// `ternary show` reports them for a file of the bundle.
fn shown_rows_and_sum(config: &Path, file: &Path) -> (u64, String, f64) {
    let text = stdout(&ternary(
        config,
        &["show", &file.to_string_lossy(), "--rows", "1"],
    ));
    let rows = text
        .lines()
        .next()
        .and_then(|line| line.rsplit_once('(')?.1.split(' ').next()?.parse().ok())
        .unwrap_or_else(|| panic!("no row count in {text}"));
    let sums: Vec<(String, f64)> = text
        .lines()
        .filter_map(|line| {
            let words: Vec<&str> = line.split_whitespace().collect();
            let sum: f64 = words.get(2)?.parse().ok()?;
            (sum.is_finite() && sum != 0.0 && words[1].starts_with("Float64"))
                .then(|| (words[0].to_string(), sum))
        })
        .collect();
    // An error column has no cancellation, so every reader's sum agrees closely.
    // No finite float: no rows, or every value null (a kernel without a
    // model); the caller then checks the row count alone.
    let (column, sum) = sums
        .iter()
        .find(|(name, _)| name.ends_with("stderr") || name.ends_with("error"))
        .or(sums.first())
        .cloned()
        .unwrap_or_default();
    (rows, column, sum)
}

/// The bundle of the small study passes `frictionless validate` (plain),
/// `sha256sum -c`, and DuckDB and polars read every table with the row counts and
/// column sums `ternary show` reports.
#[test]
fn a_bundle_passes_tools_that_are_not_ours() {
    let (config, dir) = computed("export-tools");
    let bundle = dir.join("bundle");
    let output = export(&config, &bundle, &[]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stdout(&output).starts_with("export: 18 tables, 16 figure files, "),
        "{}",
        stdout(&output)
    );
    assert_frictionless_valid(&bundle);
    let sums = Command::new("sha256sum")
        .args(["-c", "SHA256SUMS"])
        .current_dir(&bundle)
        .output()
        .unwrap();
    assert!(sums.status.success(), "{}", stdout(&sums));
    let descriptor: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(bundle.join("datapackage.json")).unwrap())
            .unwrap();
    let resources = descriptor["resources"].as_array().unwrap();
    let count = |format: &str| resources.iter().filter(|r| r["format"] == format).count();
    assert_eq!(count("parquet"), 18, "14 result tables and 4 figure tables");
    assert_eq!(
        (count("svg"), count("png")),
        (8, 8 + 4),
        "4 figures at 2 sizes, and the report's 4"
    );
    assert_eq!(count("html"), 1, "the report's page");
    assert!(bundle.join("report/index.html").is_file());
    assert_eq!(
        resources.len(),
        18 + 16 + 4 + 5,
        "and 4 documents and the report's page and figures"
    );
    for resource in resources.iter().filter(|r| r["type"] == "table") {
        let path = resource["path"].as_str().unwrap();
        let (rows, column, sum) = shown_rows_and_sum(&config, &bundle.join(path));
        assert_eq!(resource["ternary"]["rows"].as_u64(), Some(rows), "{path}");
        if column.is_empty() {
            // No float to sum (the small study's kernel model: two
            // randomizations cannot choose its knots): the row counts agree.
            let script = format!(
                "import duckdb, polars as pl\nprint(duckdb.sql(\"SELECT count(*) FROM '{path}'\").fetchall()[0][0], pl.read_parquet('{path}').height)"
            );
            assert_eq!(
                python(&script, &bundle).trim(),
                format!("{rows} {rows}"),
                "{path}"
            );
            continue;
        }
        let script = format!(
            r#"
import duckdb, polars as pl
rows = duckdb.sql("SELECT count(*) FROM '{path}'").fetchall()[0][0]
total = duckdb.sql("SELECT sum(\"{column}\") FROM '{path}'").fetchall()[0][0]
frame = pl.read_parquet("{path}")
print(rows, total, frame.height, frame["{column}"].sum(), frame["{column}"].abs().sum())
"#
        );
        let line = python(&script, &bundle);
        let values: Vec<f64> = line
            .split_whitespace()
            .map(|v| v.parse().unwrap())
            .collect();
        assert_eq!(values[0], rows as f64, "{path}: duckdb rows");
        assert_eq!(values[2], rows as f64, "{path}: polars rows");
        // Sums in another order differ by rounding, at most ~n eps sum |x|
        // (`du` and the +-1 rule's `G` of a randomization cancel to ~0).
        let scale = values[4];
        for reader_sum in [values[1], values[3]] {
            assert!(
                (reader_sum - sum).abs() <= 1e-9 * scale,
                "{path}: sum of {column} {reader_sum} against {sum}"
            );
        }
    }
    let verify = verify_bundle(&config, &bundle);
    assert!(verify.status.success(), "{}", stdout(&verify));
    // CITATION.cff is written line by line (docs/crates.md): a YAML parser
    // reads it back as the Citation File Format's structure.
    let citation: serde_json::Value = serde_json::from_str(&python(
        "import json, yaml; print(json.dumps(yaml.safe_load(open('CITATION.cff'))))",
        &bundle,
    ))
    .unwrap();
    assert_eq!(citation["cff-version"], "1.2.0", "{citation}");
    assert_eq!(citation["type"], "dataset", "{citation}");
    assert_eq!(citation["date-released"], "2026-11-23", "{citation}");
    assert_eq!(citation["authors"][0]["family-names"], "Lovelace");
    assert_eq!(
        citation["authors"][0]["orcid"],
        "https://orcid.org/0000-0002-1825-0097"
    );
    assert_eq!(citation["authors"][1]["name"], "The ternary developers");
    assert_eq!(citation["keywords"], serde_json::json!(["test"]));
    let zenodo: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(bundle.join(".zenodo.json")).unwrap()).unwrap();
    assert_eq!(zenodo["creators"][0]["name"], "Lovelace, Ada");
    assert_eq!(zenodo["title"], descriptor["title"]);
    assert_eq!(zenodo["version"], descriptor["version"]);
}

/// Missing values are Parquet nulls, read by pyarrow: no float column of a
/// bundle table holds NaN or infinity, a column holds nulls only where its
/// schema says what a null means (nullable in the Parquet file, `null` in
/// `datapackage.json`), and every other column is `required`. The small
/// study's nulls: the untruncated row's `truncation`, the Lennard-Jones
/// temperature `theta` of an inverse power law, and the rows whose fit did
/// not converge.
#[test]
fn missing_values_are_declared_nulls() {
    let (config, dir) = computed("export-nulls");
    let bundle = dir.join("bundle");
    let output = export(&config, &bundle, &[]);
    assert!(output.status.success(), "{}", stderr(&output));
    let script = r#"
import json, pyarrow as pa, pyarrow.compute as pc, pyarrow.parquet as pq
descriptor = json.load(open("datapackage.json"))
nulls = set()
for resource in descriptor["resources"]:
    if resource.get("type") != "table":
        continue
    table = pq.read_table(resource["path"])
    for field, declared in zip(table.schema, resource["schema"]["fields"]):
        where = resource["path"] + ": " + field.name
        assert field.name == declared["name"], where
        meaning = declared.get("null")
        assert field.nullable == (meaning is not None), where
        assert (declared.get("constraints") == {"required": True}) == (meaning is None), where
        if meaning is not None:
            assert field.metadata[b"null"].decode() == meaning, where
        column = table[field.name]
        if pa.types.is_floating(field.type):
            assert not pc.any(pc.is_nan(column)).as_py(), where + " holds NaN"
            assert not pc.any(pc.is_inf(column)).as_py(), where + " holds infinity"
        if column.null_count:
            assert meaning is not None, where + " holds an undeclared null"
            nulls.add(resource["ternary"]["stage"] + "." + field.name)
print(" ".join(sorted(nulls)))
"#;
    let nulls = python(script, &bundle);
    for column in [
        "moments.truncation",
        "table.theta",
        "fit.alpha",
        "fit.chi2_per_dof",
    ] {
        assert!(
            nulls.split_whitespace().any(|c| c == column),
            "{column} null: {nulls}"
        );
    }
    let readme = fs::read_to_string(bundle.join("README.md")).unwrap();
    assert!(
        readme.contains("| `truncation` | number | v_th | half-width X: only \\|u - u'\\| <= X counts | no truncation: every \\|u - u'\\| counts |"),
        "{readme}"
    );
    assert_frictionless_valid(&bundle);
}

/// The README shows the headline tables first and each kind of table (one
/// stage's table of one name) under one heading with its files, so it
/// stays short; the reading examples use a table with rows.
#[test]
fn the_readme_describes_each_table_kind_once() {
    let (config, dir) = computed("export-readme");
    let bundle = dir.join("bundle");
    assert!(export(&config, &bundle, &[]).status.success());
    let readme = fs::read_to_string(bundle.join("README.md")).unwrap();
    assert!(readme.len() < 60_000, "{} bytes", readme.len());
    let headings: Vec<&str> = readme.lines().filter(|l| l.starts_with("### ")).collect();
    let descriptor: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(bundle.join("datapackage.json")).unwrap())
            .unwrap();
    let mut kinds: Vec<String> = descriptor["resources"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["type"] == "table")
        .map(|r| {
            let meta = &r["ternary"];
            format!(
                "### `{}` table `{}`",
                meta["stage"].as_str().unwrap(),
                meta["table"].as_str().unwrap()
            )
        })
        .collect();
    kinds.sort();
    kinds.dedup();
    assert_eq!(headings.len(), kinds.len(), "{headings:?}");
    for kind in &kinds {
        assert_eq!(readme.matches(kind.as_str()).count(), 1, "{kind}");
    }
    let headline = readme.find("## Headline tables").unwrap();
    assert!(headline < readme.find("## Other tables").unwrap());
    assert!(
        readme.contains("pl.read_parquet(\"table/study.parquet\")"),
        "{readme}"
    );
    assert!(readme.contains("`figures/kernels/kernels.svg`"));
}

/// Two exports of one store are identical byte for byte.
#[test]
fn exporting_twice_gives_the_same_bytes() {
    let (config, dir) = computed("export-twice");
    let (one, two) = (dir.join("one"), dir.join("two"));
    assert!(export(&config, &one, &[]).status.success());
    assert!(export(&config, &two, &[]).status.success());
    let files = files_under(&one);
    assert_eq!(files, files_under(&two));
    for file in files {
        assert_eq!(
            fs::read(one.join(&file)).unwrap(),
            fs::read(two.join(&file)).unwrap(),
            "{}",
            file.display()
        );
    }
}

/// Options choose stages and add the scene tables; a stale instance or a
/// non-empty target is refused, naming it.
#[test]
fn export_options_and_refusals() {
    let (config, dir) = computed("export-options");
    let kernel = dir.join("kernel-only");
    assert!(
        export(&config, &kernel, &["--stage", "kernel"])
            .status
            .success()
    );
    let paths: Vec<PathBuf> = files_under(&kernel)
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "parquet"))
        .collect();
    assert_eq!(
        paths,
        [
            PathBuf::from("kernel/ipp-6_u0_rho0/kernel.parquet"),
            PathBuf::from("kernel/ipp-6_u0_rho0/kernel_log.parquet"),
            PathBuf::from("kernel/ipp-6_u0_rho0/kernel_replicates.parquet")
        ]
    );
    let events = dir.join("events");
    assert!(
        export(&config, &events, &["--include-events"])
            .status
            .success()
    );
    assert!(events.join("collisions/ipp-6.parquet").exists());
    let refused = export(&config, &kernel, &[]);
    assert!(!refused.status.success());
    assert!(
        stderr(&refused).contains("is not empty"),
        "{}",
        stderr(&refused)
    );
    let dir_of = config.parent().unwrap();
    let changed =
        format!("{}{PUBLICATION}", small_study("data")).replace("points = 7", "points = 9");
    write_config(dir_of, &changed);
    let stale = export(&config, &dir.join("stale"), &[]);
    assert!(!stale.status.success());
    assert!(
        stderr(&stale).contains("scan[ipp-6]: stale: parameter grid.points: 7 -> 9"),
        "{}",
        stderr(&stale)
    );
    assert!(!dir.join("stale").exists());
}

/// A flipped byte, a missing file and an edited descriptor each fail
/// `verify --bundle`, naming the file; `show` reads a bundle's table.
#[test]
fn verify_bundle_names_each_problem() {
    let (config, dir) = computed("export-verify");
    let bundle = dir.join("bundle");
    assert!(export(&config, &bundle, &[]).status.success());
    let copy = |name: &str| {
        let target = dir.join(name);
        for file in files_under(&bundle) {
            let path = target.join(&file);
            fs::create_dir_all(path.parent().unwrap()).unwrap();
            fs::copy(bundle.join(&file), path).unwrap();
        }
        target
    };
    let flipped = copy("flipped");
    flip_byte(&flipped.join("kernel/ipp-6_u0_rho0/kernel.parquet"));
    let missing = copy("missing");
    fs::remove_file(missing.join("fit/ipp-6_u0_rho0/fit.parquet")).unwrap();
    let edited = copy("edited");
    let descriptor = fs::read_to_string(edited.join("datapackage.json")).unwrap();
    fs::write(
        edited.join("datapackage.json"),
        descriptor.replace("A test bundle", "A better bundle"),
    )
    .unwrap();
    for (bundle, file) in [
        (&flipped, "kernel/ipp-6_u0_rho0/kernel.parquet"),
        (&missing, "fit/ipp-6_u0_rho0/fit.parquet"),
        (&edited, "datapackage.json"),
    ] {
        let output = verify_bundle(&config, bundle);
        assert!(!output.status.success(), "{file}: verify passed");
        assert!(
            stdout(&output)
                .lines()
                .any(|line| line.starts_with(&format!("PROBLEM  {file}"))),
            "{file}: {}",
            stdout(&output)
        );
    }
    let shown = ternary(
        &config,
        &[
            "show",
            &bundle
                .join("kernel/ipp-6_u0_rho0/kernel.parquet")
                .to_string_lossy(),
        ],
    );
    assert!(shown.status.success(), "{}", stderr(&shown));
    assert!(stdout(&shown).contains("ternary.stage: kernel"));
}

/// An export into an empty directory that is a mount point failed with
/// "Device or resource busy" and left a full hidden copy beside it; a killed
/// export left its staging copy forever; a file as target gave an error
/// without its path; a user's folder named like staging debris
/// (`.export-2023/`, `.results.export-2024/`) was deleted. Now the bundle is
/// staged inside an existing target, staging carries the store's id, this
/// process and a marker, what a killed export left is removed by its marker
/// (beside the same target, or by `run`/`gc` wherever it lies), nothing that
/// merely looks like staging is touched, and errors name paths.
#[test]
fn exports_land_in_empty_mount_points_and_leave_no_debris() {
    let (config, dir) = computed("export-places");
    // A user's folders named like staging of a long-gone process: kept.
    let user_beside = dir.join(".bundle.export-2024");
    let user_inside = dir.join("u/.export-2023");
    for folder in [&user_beside, &user_inside] {
        fs::create_dir_all(folder).unwrap();
        fs::write(folder.join("thesis.tex"), "t").unwrap();
    }
    let refused = export(&config, &dir.join("u"), &["--stage", "kernel"]);
    assert!(!refused.status.success());
    assert!(
        stderr(&refused).contains("not empty"),
        "{}",
        stderr(&refused)
    );
    let bundle = dir.join("bundle");
    let exported = export(&config, &bundle, &["--stage", "kernel"]);
    assert!(exported.status.success(), "{}", stderr(&exported));
    assert!(verify_bundle(&config, &bundle).status.success());
    for folder in [&user_beside, &user_inside] {
        assert_eq!(fs::read_to_string(folder.join("thesis.tex")).unwrap(), "t");
    }
    // Exports killed as they move their bundle into place leave marked
    // staging: the next export to the same target removes it, and `gc`
    // removes what lies beside any other target.
    if strace_works() {
        let killed = |target: &Path| {
            let output = Command::new("strace")
                .args([
                    "-qq",
                    "-o",
                    "/dev/null",
                    "-e",
                    "trace=rename,renameat,renameat2",
                ])
                .args(["-e", "inject=rename,renameat,renameat2:signal=KILL:when=1"])
                .args([common::BINARY, "--config"])
                .arg(&config)
                .arg("export")
                .arg(target)
                .args(["--stage", "kernel"])
                .output()
                .unwrap();
            assert!(!output.status.success(), "the export was not killed");
        };
        let staged = || -> Vec<String> {
            fs::read_dir(&dir)
                .unwrap()
                .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .filter(|name| name.contains(".export-") && !name.ends_with("2024"))
                .collect()
        };
        killed(&dir.join("again"));
        killed(&dir.join("elsewhere"));
        assert_eq!(staged().len(), 2, "{:?}", staged());
        let again = export(&config, &dir.join("again"), &["--stage", "kernel"]);
        assert!(again.status.success(), "{}", stderr(&again));
        assert_eq!(staged().len(), 1, "{:?}", staged());
        let collected = ternary(&config, &["gc"]);
        assert!(collected.status.success(), "{}", stderr(&collected));
        assert!(staged().is_empty(), "{:?}", staged());
        let verified = ternary(&config, &["verify"]);
        assert!(verified.status.success(), "{}", stdout(&verified));
    } else {
        eprintln!("skipped the killed exports: strace cannot trace here");
    }
    assert!(user_beside.join("thesis.tex").exists());
    // An existing empty directory takes the bundle (staged inside it).
    let empty = dir.join("empty");
    fs::create_dir_all(&empty).unwrap();
    assert!(
        export(&config, &empty, &["--stage", "kernel"])
            .status
            .success()
    );
    assert!(verify_bundle(&config, &empty).status.success());
    // A file as target: the error names it.
    let file = dir.join("a-file");
    fs::write(&file, "mine").unwrap();
    let refused = export(&config, &file, &[]);
    assert!(!refused.status.success());
    assert!(
        stderr(&refused).contains(&file.display().to_string()),
        "{}",
        stderr(&refused)
    );
    assert_eq!(fs::read_to_string(&file).unwrap(), "mine");
    // A mount point (when this process may mount: root in CI).
    let mount = dir.join("mounted");
    fs::create_dir_all(&mount).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "none"])
        .arg(&mount)
        .output()
        .is_ok_and(|o| o.status.success());
    if !mounted {
        eprintln!("skipped the mount point: cannot mount a tmpfs here");
        return;
    }
    let exported = export(&config, &mount, &["--stage", "kernel"]);
    let checked = verify_bundle(&config, &mount);
    let _ = Command::new("umount").arg(&mount).output();
    assert!(exported.status.success(), "{}", stderr(&exported));
    assert!(checked.status.success(), "{}", stdout(&checked));
}
