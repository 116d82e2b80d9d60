//! Byte identity of every stage's output across code changes: a reduced study
//! that runs every stage (scan, collisions and the sweep's own, kernel,
//! moments, fit, sweep, convergence, evolve, md for an inverse power law, the
//! n = 2 ring and Lennard-Jones, compare, gases, table, paper, figures) is
//! computed, and each output file's key and content hash (data and its own
//! metadata, without provenance) are compared with `tests/golden/reduced-study.txt`.
//!
//! * Content that changes under an unchanged key is a broken promise (a
//!   non-deterministic stage, or code the fingerprint misses): always a failure.
//! * Content that changes with its key (the stage's code changed) fails until
//!   the file is rewritten with `TERNARY_BLESS=1 cargo test --release --test
//!   golden`; the commit says why. A refactoring leaves the content unchanged.
//! * A key that changes with the same content passes (a note says so).
//!
//! The recompute audit (`verify --recompute`) then runs on the same store,
//! and the store's bundle gives docs/tables.md, the manual's reference of
//! every table (each kind as the bundle's README describes it, from the
//! columns' own metadata), which must match the page (rewritten by the same
//! `TERNARY_BLESS=1`).
//!
//! Results do not depend on the CPU (no code path is picked at run time by
//! its features: transcendental functions from `libm`, our own FFT), so the
//! comparison runs on every x86-64 machine; a second test computes the study
//! with glibc's FMA and AVX variants turned off, as on an older CPU, and
//! finds the same content under the same keys.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

mod common;

use common::{
    BINARY, REDUCED_STUDY, files_under, stderr, stdout, ternary, workspace, write_config,
};

const GOLDEN: &str = "tests/golden/reduced-study.txt";

/// The manual's reference of every table.
const TABLES: &str = "docs/tables.md";

/// What an export needs beyond the study: a title and an author.
const PUBLICATION: &str = r#"
[publication]
title = "The reduced study of ternary's tests"

[[publication.authors]]
name = "The ternary developers"
"#;

/// docs/tables.md from a bundle's README: every table kind's section (its
/// heading, description and columns), without the files that hold it in this
/// study.
fn table_reference(bundle_readme: &str) -> String {
    let mut page = String::from(
        "# Every table\n\n\
         What each stage writes: one section per kind of table (a stage's table of one name), \
         with its columns, types, units and what a null means, as an exported bundle's \
         README.md describes them. Generated from the reduced study of `tests/golden.rs`, which \
         runs every stage, by `TERNARY_BLESS=1 cargo test --release --test golden`; the test \
         fails when a table's columns change and this page does not. What each stage computes: \
         [stages](stages.md).\n",
    );
    let mut keep = false;
    for line in bundle_readme.lines() {
        if line.starts_with("## ") {
            keep = false;
        } else if line.starts_with("### ") {
            keep = true;
            page.push_str("\n## ");
            page.push_str(line.trim_start_matches("### "));
            page.push('\n');
            continue;
        }
        if keep && !line.starts_with("Files `") {
            page.push_str(line);
            page.push('\n');
        }
    }
    let mut tidy = page.replace("\n\n\n", "\n\n");
    while tidy.ends_with("\n\n") {
        tidy.pop();
    }
    tidy
}

/// Exports the computed reduced study in `dir` and holds its table reference
/// against docs/tables.md (or rewrites the page when blessing).
fn check_table_reference(dir: &Path) {
    let config = dir.join("export.toml");
    fs::write(&config, format!("{REDUCED_STUDY}{PUBLICATION}")).unwrap();
    let bundle = dir.join("bundle");
    let export = ternary(
        &config,
        &["export", bundle.to_str().unwrap(), "--include-events"],
    );
    assert!(export.status.success(), "{}", stderr(&export));
    let readme = fs::read_to_string(bundle.join("README.md")).unwrap();
    let reference = table_reference(&readme);
    let page = Path::new(env!("CARGO_MANIFEST_DIR")).join(TABLES);
    if std::env::var_os("TERNARY_BLESS").is_some() {
        fs::write(&page, reference).unwrap();
        return;
    }
    assert!(
        fs::read_to_string(&page).is_ok_and(|text| text == reference),
        "{TABLES} differs from the tables the study writes: rewrite it with \
         `TERNARY_BLESS=1 cargo test --release --test golden` and say why in the commit"
    );
}

/// `<stage> <instance> <file>` -> `(key, content sha256)` of every output file.
fn output_records(store: &Path) -> BTreeMap<String, (String, String)> {
    files_under(&store.join("artifacts"))
        .into_iter()
        .filter(|path| path.file_name().is_some_and(|n| n == "manifest.json"))
        .flat_map(|path| {
            let text = fs::read_to_string(store.join("artifacts").join(&path)).unwrap();
            let manifest: serde_json::Value = serde_json::from_str(&text).unwrap();
            let field = |name: &str| manifest[name].as_str().unwrap().to_string();
            let (stage, instance, key) = (field("stage"), field("instance"), field("key"));
            manifest["files"]
                .as_array()
                .unwrap()
                .iter()
                .map(|file| {
                    let name = format!("{stage} {instance} {}", file["name"].as_str().unwrap());
                    let content = file["content_sha256"].as_str().unwrap().to_string();
                    (name, (key.clone(), content))
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The golden file's text for `records`.
fn golden_text(records: &BTreeMap<String, (String, String)>) -> String {
    let mut text = String::from("# stage instance file key=<key> content=<content sha256>\n");
    for (name, (key, content)) in records {
        text.push_str(&format!("{name} key={key} content={content}\n"));
    }
    text
}

/// The records of a golden file's text.
fn parse_golden(text: &str) -> BTreeMap<String, (String, String)> {
    text.lines()
        .skip(1)
        .map(|line| {
            let (name, rest) = line.split_once(" key=").expect("golden line");
            let (key, content) = rest.split_once(" content=").expect("golden line");
            (name.to_string(), (key.to_string(), content.to_string()))
        })
        .collect()
}

/// Every stage, named after its file in src/stages/ (one stage per file).
fn stage_files() -> std::collections::BTreeSet<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/stages");
    fs::read_dir(dir)
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .filter(|path| path.extension().is_some_and(|e| e == "rs"))
        .map(|path| path.file_stem().unwrap().to_string_lossy().into_owned())
        .filter(|stem| stem != "mod")
        .collect()
}

/// The workspace of the reduced study computed once for this file's tests,
/// on this CPU: its `pipeline.toml` and its store `data`.
fn native() -> &'static Path {
    static NATIVE: OnceLock<PathBuf> = OnceLock::new();
    NATIVE.get_or_init(|| {
        let dir = workspace("golden");
        let run = ternary(&write_config(&dir, REDUCED_STUDY), &["run", "--quiet"]);
        assert!(run.status.success(), "{}", stderr(&run));
        dir
    })
}

#[test]
fn every_stage_keeps_its_bytes() {
    let dir = native();
    let config = dir.join("pipeline.toml");
    let records = output_records(&dir.join("data"));
    let stages: std::collections::BTreeSet<String> = records
        .keys()
        .map(|name| name.split(' ').next().unwrap().to_string())
        .collect();
    assert_eq!(stages, stage_files(), "every stage runs");
    let audit = ternary(&config, &["verify", "--recompute"]);
    assert!(
        audit.status.success(),
        "recompute audit:\n{}",
        stdout(&audit)
    );
    check_table_reference(dir);
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join(GOLDEN);
    if std::env::var_os("TERNARY_BLESS").is_some() {
        fs::create_dir_all(golden.parent().unwrap()).unwrap();
        fs::write(&golden, golden_text(&records)).unwrap();
        return;
    }
    let expected = parse_golden(&fs::read_to_string(&golden).expect(GOLDEN));
    let mut broken = Vec::new();
    let mut changed = Vec::new();
    let mut rekeyed = 0;
    for name in expected.keys().chain(records.keys()) {
        match (expected.get(name), records.get(name)) {
            (Some(before), Some(now)) if before == now => {}
            (Some((key, _)), Some((now_key, _))) if key == now_key => broken.push(name.clone()),
            (Some((_, content)), Some((_, now_content))) if content == now_content => rekeyed += 1,
            _ => changed.push(name.clone()),
        }
    }
    changed.sort();
    changed.dedup();
    assert!(
        broken.is_empty(),
        "SAME KEY, DIFFERENT CONTENT (a stage is not deterministic, or its fingerprint misses code it runs; never bless this):\n{}",
        broken.join("\n")
    );
    assert!(
        changed.is_empty(),
        "content changed with the code ({} files; if intended, bless and say why in the commit):\n{}",
        changed.len(),
        changed.join("\n")
    );
    if rekeyed > 0 {
        eprintln!("note: {rekeyed} files have new keys (code changed) and the same content");
    }
}

/// glibc picks FMA and AVX2 variants of `exp`, `log`, `pow`, `sin`, ... at
/// run time; these tunables make it pick the baseline ones, as on a CPU
/// without those features. Before the study's math moved to `libm` and its
/// FFT to `evolve::fourier`, 200 of the reduced study's 217 files differed.
#[test]
fn a_cpu_without_fma_or_avx_computes_the_same_bytes() {
    let dir = workspace("cpu-baseline");
    let run = std::process::Command::new(BINARY)
        .arg("--config")
        .arg(write_config(&dir, REDUCED_STUDY))
        .args(["run", "--quiet"])
        .env(
            "GLIBC_TUNABLES",
            "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX,-AVX512F,-FMA4",
        )
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", stderr(&run));
    let native = output_records(&native().join("data"));
    let baseline = output_records(&dir.join("data"));
    let differing: Vec<&String> = native
        .keys()
        .filter(|name| native.get(*name) != baseline.get(*name))
        .collect();
    assert_eq!(native.len(), baseline.len());
    assert!(
        differing.is_empty(),
        "content differs without FMA/AVX: {differing:?}"
    );
}

const PLAN: &str = "tests/golden/default-plan.txt";

/// The default study's plan as text: each stage instance in plan order with
/// the instances it reads, computed from `pipeline.toml` without running
/// anything (like a query plan). A change to the DAG (a stage, an instance
/// name, an input) shows here as a diff, rewritten with `TERNARY_BLESS=1`;
/// the commit says why.
#[test]
fn the_default_plan_matches_its_snapshot() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let study = ternary::config::Study::load(&root.join("pipeline.toml")).expect("pipeline.toml");
    let mut text = String::from("# stage[instance] <- inputs, in plan order (pipeline.toml)\n");
    for stage in ternary::plan::plan(&study) {
        let inputs: Vec<String> = stage.inputs().iter().map(|id| id.to_string()).collect();
        let line = if inputs.is_empty() {
            stage.id().to_string()
        } else {
            format!("{} <- {}", stage.id(), inputs.join(", "))
        };
        text.push_str(&line);
        text.push('\n');
    }
    let golden = root.join(PLAN);
    if std::env::var_os("TERNARY_BLESS").is_some() {
        fs::write(&golden, &text).unwrap();
        return;
    }
    let expected = fs::read_to_string(&golden).expect(PLAN);
    let (old, new): (Vec<&str>, Vec<&str>) = (expected.lines().collect(), text.lines().collect());
    let gone: Vec<&&str> = old.iter().filter(|l| !new.contains(l)).collect();
    let added: Vec<&&str> = new.iter().filter(|l| !old.contains(l)).collect();
    assert!(
        expected == text,
        "the default plan changed (bless with TERNARY_BLESS=1 and say why in the commit):\n\
         gone: {gone:#?}\nadded: {added:#?}"
    );
}
