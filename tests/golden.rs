//! Byte identity of every stage's output across code changes: a reduced study
//! that runs every stage (scan, collisions and the sweep's own, kernel,
//! moments, fit, sweep, convergence, evolve, md for an inverse power law, the
//! n = 2 ring and Lennard-Jones, compare, gases, table, paper, figures) is computed and the
//! SHA-256 of each output file is compared with `tests/golden/reduced-study.txt`.
//!
//! A refactoring must leave the file unchanged. A change meant to move bytes
//! bumps the stage's version and rewrites the file with
//! `TERNARY_BLESS=1 cargo test --release --test golden`; the commit says why.
//!
//! Floating-point results depend on the CPU's vector paths (rustfft picks
//! AVX or SSE at run time): the golden file records the features it was made
//! with, and on a machine with other features the comparison is skipped, saying so.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

mod common;

use common::{REDUCED_STUDY, files_under, ternary, workspace, write_config};

const GOLDEN: &str = "tests/golden/reduced-study.txt";

/// The CPU features that decide vectorized floating-point paths.
fn cpu_features() -> String {
    #[cfg(target_arch = "x86_64")]
    {
        let features = [
            ("sse4.1", std::arch::is_x86_feature_detected!("sse4.1")),
            ("avx", std::arch::is_x86_feature_detected!("avx")),
            ("avx2", std::arch::is_x86_feature_detected!("avx2")),
            ("fma", std::arch::is_x86_feature_detected!("fma")),
        ];
        let present: Vec<&str> = features
            .iter()
            .filter(|(_, on)| *on)
            .map(|(name, _)| *name)
            .collect();
        format!("x86_64 {}", present.join(" "))
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        std::env::consts::ARCH.to_string()
    }
}

/// `<stage> <instance> <file> <sha256>` of every output file, sorted.
fn output_hashes(store: &Path) -> BTreeMap<String, String> {
    files_under(&store.join("artifacts"))
        .into_iter()
        .filter(|path| path.file_name().is_some_and(|n| n != "manifest.json"))
        .map(|path| {
            let dir: PathBuf = store.join("artifacts").join(path.parent().unwrap());
            let manifest: serde_json::Value =
                serde_json::from_str(&fs::read_to_string(dir.join("manifest.json")).unwrap())
                    .unwrap();
            let bytes = fs::read(store.join("artifacts").join(&path)).unwrap();
            let name = format!(
                "{} {} {}",
                manifest["stage"].as_str().unwrap(),
                manifest["instance"].as_str().unwrap(),
                path.file_name().unwrap().to_string_lossy()
            );
            (name, ternary::pipeline::key::sha256_hex(&bytes))
        })
        .collect()
}

#[test]
fn every_stage_keeps_its_bytes() {
    let dir = workspace("golden");
    let config = write_config(&dir, REDUCED_STUDY);
    let run = ternary(&config, &["run", "--quiet"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let hashes = output_hashes(&dir.join("data"));
    let stages: std::collections::BTreeSet<&str> = hashes
        .keys()
        .map(|name| name.split(' ').next().unwrap())
        .collect();
    assert_eq!(stages.len(), 15, "every stage runs: {stages:?}");
    let mut text = format!("# cpu: {}\n", cpu_features());
    for (name, sha) in &hashes {
        text.push_str(&format!("{name} {sha}\n"));
    }
    let golden = Path::new(env!("CARGO_MANIFEST_DIR")).join(GOLDEN);
    if std::env::var_os("TERNARY_BLESS").is_some() {
        fs::create_dir_all(golden.parent().unwrap()).unwrap();
        fs::write(&golden, &text).unwrap();
        return;
    }
    let expected = fs::read_to_string(&golden).expect("tests/golden/reduced-study.txt");
    let recorded_cpu = expected.lines().next().unwrap_or_default();
    if recorded_cpu != format!("# cpu: {}", cpu_features()) {
        eprintln!(
            "skipped: the golden hashes were made on `{recorded_cpu}`, this machine is `{}`",
            cpu_features()
        );
        return;
    }
    let differing: Vec<String> = expected
        .lines()
        .skip(1)
        .zip(text.lines().skip(1))
        .filter(|(a, b)| a != b)
        .map(|(a, b)| format!("expected {a}\n     got {b}"))
        .collect();
    assert!(
        differing.is_empty() && expected == text,
        "output bytes changed ({} lines differ; if intended, bump the stage version and bless):\n{}",
        differing.len(),
        differing.join("\n")
    );
}
