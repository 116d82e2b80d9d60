//! Helpers shared by the integration tests that drive the `ternary` binary.
#![allow(dead_code)]

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub const BINARY: &str = env!("CARGO_BIN_EXE_ternary");

/// The table `name` of the artifact a ref of `store` names
/// (`<stage>/<instance>`).
pub fn table(store: &Path, stage: &str, instance: &str, name: &str) -> arrow_array::RecordBatch {
    let reference: serde_json::Value = serde_json::from_str(
        &fs::read_to_string(store.join(format!("refs/{stage}/{instance}.json"))).unwrap(),
    )
    .unwrap();
    let dir: PathBuf = store
        .join("artifacts")
        .join(stage)
        .join(reference["key"].as_str().unwrap());
    ternary::pipeline::table::read_parquet(&dir.join(format!("{name}.parquet")))
        .unwrap()
        .0
}

/// A fresh directory for one test.
pub fn workspace(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ternary-test-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn write_config(dir: &Path, text: &str) -> PathBuf {
    let path = dir.join("pipeline.toml");
    fs::write(&path, text).unwrap();
    path
}

/// `ternary run --quiet` of only the instances of `stages`; it must succeed.
pub fn run_stages(config: &Path, stages: &[&str]) {
    let mut args = vec!["run", "--quiet"];
    stages.iter().for_each(|s| args.extend(["--only", s]));
    let output = ternary(config, &args);
    assert!(output.status.success(), "{}", stderr(&output));
}

pub fn ternary(config: &Path, args: &[&str]) -> Output {
    Command::new(BINARY)
        .arg("--config")
        .arg(config)
        .args(args)
        .output()
        .unwrap()
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// Runs `ternary run` and returns (computed, fresh) from its closing line.
pub fn run_counts(config: &Path, args: &[&str]) -> (usize, usize) {
    let output = ternary(config, &[&["run"], args].concat());
    assert!(output.status.success(), "run failed: {}", stderr(&output));
    let text = stdout(&output);
    let line = text
        .lines()
        .find(|l| l.starts_with("run: "))
        .expect("closing line");
    let number = |word: &str| -> usize {
        let before = line.split(word).next().unwrap();
        before
            .split_whitespace()
            .last()
            .unwrap()
            .trim_start_matches("run:")
            .parse()
            .unwrap()
    };
    (number(" computed"), number(" fresh"))
}

/// A scan of the symmetric launch (`u2 = 1`, `u3 = -1`) at seven offsets:
/// the least a study needs.
pub const SYMMETRIC_SCAN: &str = r#"
[scan]
offset_min = -3.0
offset_max = 3.0
points = 7

[[scan.launch]]
name = "symmetric"
u2 = 1.0
u3 = -1.0
"#;

/// A study of one potential (`ipp-6`) small enough to run in a fraction of a
/// second: scan, collisions, kernel, moments, fit, table, paper and four figures
/// (kernels, kernel with fit, truncation, kicks).
pub fn small_study(store: &str) -> String {
    format!(
        r#"
[store]
path = "{store}"

[potentials]
inverse_power = [6]

{SYMMETRIC_SCAN}
[collisions]
randomizations = 2
points = 64
pilot_points = 0

[sweep]
enabled = false

[spectrum]
enabled = false
"#
    )
}

/// Stage instances of [`small_study`].
pub const SMALL_STUDY_INSTANCES: usize = 12;

/// Every file under `dir`, recursively, as paths relative to `dir`.
pub fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut pending = vec![dir.to_path_buf()];
    while let Some(next) = pending.pop() {
        for entry in fs::read_dir(&next).into_iter().flatten().flatten() {
            let path = entry.path();
            if path.is_dir() {
                pending.push(path);
            } else {
                found.push(path.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    found.sort();
    found
}

/// SHA-256 of every artifact table and ref of a store, by relative path: what
/// two stores holding the same results share (manifests are left out, as they
/// record wall times).
pub fn result_bytes(store: &Path) -> std::collections::BTreeMap<PathBuf, String> {
    files_under(store)
        .into_iter()
        .filter(|path| {
            let top = path.components().next().unwrap().as_os_str();
            (top == "artifacts" && path.extension().is_some_and(|e| e == "parquet"))
                || (top == "refs" && !is_hidden(path))
        })
        .map(|path| {
            let bytes = fs::read(store.join(&path)).unwrap();
            (path, ternary::pipeline::key::sha256_hex(&bytes))
        })
        .collect()
}

fn is_hidden(path: &Path) -> bool {
    path.file_name()
        .is_some_and(|name| name.to_string_lossy().starts_with('.'))
}

/// What an interrupted run may leave and `gc` must remove: staging entries in
/// `tmp/` and temporary files of atomic writes.
pub fn debris(store: &Path) -> Vec<PathBuf> {
    files_under(store)
        .into_iter()
        .filter(|path| path.starts_with("tmp") || is_hidden(path))
        .collect()
}

/// `true` when `strace` can trace a child here (installed, and ptrace allowed).
pub fn strace_works() -> bool {
    Command::new("strace")
        .args(["-f", "-qq", "-o", "/dev/null", "true"])
        .output()
        .is_ok_and(|output| output.status.success())
}

/// Flips one bit of a file in its middle (an empty file gets one byte).
pub fn flip_byte(path: &Path) {
    let mut bytes = fs::read(path).unwrap();
    match bytes.len() {
        0 => bytes.push(0x01),
        n => bytes[n / 2] ^= 0x01,
    }
    fs::write(path, bytes).unwrap();
}

/// A reduced study that runs every stage (scan, collisions and the sweep's
/// own, kernel, moments, fit, sweep, convergence, evolve, md for an inverse
/// power law, the n = 2 ring and Lennard-Jones, compare, gases, table, paper,
/// figures) in about a second.
pub const REDUCED_STUDY: &str = r#"
[potentials]
inverse_power = [2, 6]
lennard_jones = [0.1, 0.1052]

[scan]
offset_min = -3.0
offset_max = 3.0
points = 9

[[scan.launch]]
name = "symmetric"
u2 = 1.0
u3 = -1.0

[[scan.launch]]
name = "asymmetric"
u2 = 1.1
u3 = -0.9

[collisions]
randomizations = 4
points = 256
pilot_points = 64

[kernel]
u_prime = [0.0, 0.5, -0.25]
density = [0.0, 1e-3]

[sweep]
points = 5
balance_separations = [0.02, 0.04]

[dissociation]
points = 1024
randomizations = 4

# The near_integrable table over n = 6 (its fits need four potentials: null).
[spectrum]
near_integrable_max_n = 6.0

[convergence]
enabled = true
inverse_power = 6
densities = [1e-3]
offset_bounds = [3, 30]
tolerances = [1e-10]
bin_widths = [2e-4, 1e-3]

[evolve]
enabled = true
potential = "ipp-6"
times = [0.1, 1.0]
early_times = [1e-3]
velocity_range = 2.0
grid_step = 0.1
gas = "ring6"
times_ns = [100.0]

[md]
enabled = true
runs = 4
samples = 3

[[md.system]]
name = "ring6"
gas = "ring6"
final_time_ns = 100.0

[[md.system]]
name = "ring6_early"
gas = "ring6"
final_time_ns = 50.0

[[md.system]]
name = "ring6_dense"
gas = "ring6_dense"
final_time_ns = 25.0

[[md.system]]
name = "ring6_dense_hot"
gas = "ring6_dense_hot"
final_time_ns = 12.5
runs = 16

[[md.system]]
name = "sutherland"
gas = "sutherland"
final_time_ns = 5.0
runs = 2

[[md.system]]
name = "lj"
gas = "lj"
final_time_ns = 5.0
runs = 2

[[gas]]
name = "ring6"
potential = "ipp-6"
l0_um = 1.0
eps_ev = 1.0
kt_ev = 0.1
mass_electron = 1.0
ring_particles = 21
ring_radius_um = 1600.0

[[gas]]
name = "ring6_dense"
potential = "ipp-6"
l0_um = 1.0
eps_ev = 1.0
kt_ev = 0.1
mass_electron = 1.0
ring_particles = 21
ring_radius_um = 800.0

[[gas]]
name = "ring6_dense_hot"
potential = "ipp-6"
l0_um = 1.0
eps_ev = 1.0
kt_ev = 0.8
mass_electron = 1.0
ring_particles = 21
ring_radius_um = 800.0

[[gas]]
name = "sutherland"
potential = "ipp-2"
l0_um = 1.0
eps_ev = 1.0
kt_ev = 0.1
mass_electron = 1.0
ring_particles = 11
ring_radius_um = 200.0

[[gas]]
name = "lj"
potential = "lj-0.1"
l0_um = 1.0
eps_ev = 1.0
kt_ev = 0.1
mass_electron = 1.0
ring_particles = 11
ring_radius_um = 400.0

[[gas]]
name = "N2_10K"
potential = "lj-0.1052"
l0_um = 3.698e-4
eps_ev = 8.19077526e-3
kt_ev = 8.61669557352e-4
mass_amu = 28.0134
density_per_um = 0.1

[[gas]]
name = "hot"
potential = "ipp-6"
l0_um = 1.0
eps_ev = 1.0
kt_ev = 0.8
mass_electron = 1.0
density_per_um = 5e-4
"#;
