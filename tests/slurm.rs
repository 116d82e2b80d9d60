//! Sharded runs: the merged artifacts are byte-identical to an unsharded
//! run for any shard count; and on a real single-node Slurm cluster (started
//! by `.ci/slurm-cluster start`, found through `SLURM_CONF`), an array job of
//! shards with one task cancelled, resubmitted, ends with the store of a
//! single process.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

mod common;

use common::{
    result_bytes, run_counts, small_study, stderr, stdout, ternary, workspace, write_config,
};

/// The small study with 8 randomizations (8 shardable units).
fn study() -> String {
    small_study("data").replace("randomizations = 2", "randomizations = 8")
}

/// Result bytes without the shard artifacts (intermediate, not in an
/// unsharded store).
fn merged_bytes(store: &Path) -> BTreeMap<PathBuf, String> {
    result_bytes(store)
        .into_iter()
        .filter(|(path, _)| !path.to_string_lossy().contains(".shard"))
        .collect()
}

/// The bytes of an unsharded run of [`study`], computed once: tests run
/// in parallel, and two runs in the one workspace removed each other's
/// store.
fn single_process() -> &'static BTreeMap<PathBuf, String> {
    static BYTES: OnceLock<BTreeMap<PathBuf, String>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let dir = workspace("shards-single");
        run_counts(&write_config(&dir, &study()), &[]);
        merged_bytes(&dir.join("data"))
    })
}

/// Runs the shard tasks `tasks` of `shards`, then a merging run; returns the
/// sharded status between the two.
fn shard_then_merge(config: &Path, shards: u32, tasks: impl IntoIterator<Item = u32>) -> String {
    let n = shards.to_string();
    for task in tasks {
        let output = ternary(
            config,
            &["run", "--shards", &n, "--shard", &task.to_string()],
        );
        assert!(output.status.success(), "{}", stderr(&output));
    }
    let status = stdout(&ternary(config, &["status", "--shards", &n]));
    let merge = ternary(config, &["run", "--shards", &n]);
    assert!(merge.status.success(), "{}", stderr(&merge));
    status
}

/// 2, 3, 5 and 8 shards, and more shards than units (12 of 8): shard tasks
/// in any order, then a merging run, give the unsharded bytes.
#[test]
fn merged_shards_equal_an_unsharded_run() {
    let reference = single_process();
    for shards in [2u32, 3, 5, 8, 12] {
        let dir = workspace(&format!("shards-{shards}"));
        let config = write_config(&dir, &study());
        let status = shard_then_merge(&config, shards, (0..shards).rev());
        assert!(
            status.contains(&format!("(shards: {shards} of {shards} done, missing [])")),
            "{status}"
        );
        assert_eq!(
            merged_bytes(&dir.join("data")),
            *reference,
            "{shards} shards"
        );
        // gc keeps no shard once merged.
        let gc = stdout(&ternary(&config, &["gc"]));
        let kept = common::files_under(&dir.join("data/artifacts"))
            .iter()
            .filter(|p| p.to_string_lossy().contains(".shard"))
            .count();
        assert_eq!(kept, 0, "{gc}");
    }
}

/// The small study with rings: an inverse power law ring of 5 runs and the
/// n = 2 Sutherland ring of 3 (md shards by runs, aggregates in the merge).
fn ring_study() -> String {
    let ring = |name: &str, potential: &str, particles: u32, radius: f64| {
        format!(
            "[[gas]]\nname = \"{name}\"\npotential = \"{potential}\"\nl0_um = 1.0\neps_ev = 1.0\nkt_ev = 0.1\nmass_electron = 1.0\nring_particles = {particles}\nring_radius_um = {radius}\n\n"
        )
    };
    format!(
        "{}\n{}{}[md]\nenabled = true\nruns = 5\n\n[[md.system]]\nname = \"ring\"\ngas = \"ring\"\nfinal_time_ns = 50.0\n\n[[md.system]]\nname = \"sutherland\"\ngas = \"sutherland\"\nfinal_time_ns = 5.0\nruns = 3\n",
        small_study("data").replace("inverse_power = [6]", "inverse_power = [2, 6]"),
        ring("ring", "ipp-6", 21, 1600.0),
        ring("sutherland", "ipp-2", 11, 200.0),
    )
}

/// Rings shard by runs: 2, 3 and 7 shards of the md and compare stages'
/// inputs merge to the bytes of an unsharded run.
#[test]
fn md_shards_by_runs_merge_to_the_same_bytes() {
    let single = workspace("md-shards-single");
    run_counts(&write_config(&single, &ring_study()), &[]);
    let reference = merged_bytes(&single.join("data"));
    assert!(reference.keys().any(|p| p.starts_with("artifacts/md")));
    for shards in [2u32, 3, 7] {
        let dir = workspace(&format!("md-shards-{shards}"));
        let config = write_config(&dir, &ring_study());
        shard_then_merge(&config, shards, 0..shards);
        assert_eq!(
            merged_bytes(&dir.join("data")),
            reference,
            "{shards} shards"
        );
    }
}

/// A merging run computes the shards still missing itself; shards present
/// before a gc stay (their artifact is not merged yet).
#[test]
fn a_merging_run_computes_missing_shards_and_gc_keeps_pending_ones() {
    let dir = workspace("shards-partial");
    let config = write_config(&dir, &study());
    assert!(
        ternary(&config, &["run", "--shards", "4", "--shard", "1"])
            .status
            .success()
    );
    let gc = ternary(&config, &["gc"]);
    assert!(
        stdout(&gc).contains("removed 0 artifacts"),
        "{}",
        stdout(&gc)
    );
    let status = stdout(&ternary(&config, &["status", "--shards", "4"]));
    assert!(status.contains("missing [0, 2, 3]"), "{status}");
    assert!(ternary(&config, &["run", "--shards", "4"]).status.success());
    assert_eq!(&merged_bytes(&dir.join("data")), single_process());
}

fn slurm_available() -> bool {
    std::env::var_os("SLURM_CONF").is_some()
        && Command::new("sinfo")
            .args(["-h", "-o", "%T"])
            .output()
            .is_ok_and(|o| o.status.success() && !o.stdout.is_empty())
}

/// Job ids of ternary's jobs still in the queue.
fn queued() -> Vec<String> {
    let output = Command::new("squeue")
        .args(["-h", "-o", "%i %j"])
        .output()
        .unwrap();
    stdout(&output)
        .lines()
        .filter(|line| line.contains("ternary-"))
        .map(|line| line.split_whitespace().next().unwrap().to_string())
        .collect()
}

fn wait_for_queue_to_empty() {
    let started = Instant::now();
    while !queued().is_empty() {
        assert!(
            started.elapsed() < Duration::from_secs(300),
            "jobs still queued: {:?}",
            queued()
        );
        std::thread::sleep(Duration::from_millis(500));
    }
}

/// 6 shards on the test cluster, whose `MaxArraySize` is 4 (indices 0-3):
/// two array jobs (shards 0-3, and 4-5 as tasks 0-1 with an offset), one
/// task at a time each. Shard 5 is cancelled while pending: the merge job,
/// which waits for both arrays, is cancelled with it, status shows shard 5
/// missing, a resubmission runs only shard 5 and the merge, and the store
/// ends with the bytes of a single process.
#[test]
fn a_slurm_array_with_a_cancelled_task_resubmits_only_what_is_missing() {
    if !slurm_available() {
        eprintln!(
            "skipped: no Slurm cluster (start one with .ci/slurm-cluster start and set SLURM_CONF)"
        );
        return;
    }
    wait_for_queue_to_empty();
    let dir = workspace("slurm");
    let config = write_config(&dir, &study());
    let submit = |extra: &[&str]| {
        let args = [
            &["slurm", "submit", "--shards", "6", "--max-parallel", "1"][..],
            extra,
        ]
        .concat();
        let output = ternary(&config, &args);
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let dry = submit(&["--dry-run"]);
    assert!(dry.contains("#SBATCH --array=0-3%1\n"), "{dry}");
    assert!(dry.contains("slurm/shards-from-4.sbatch\n"), "{dry}");
    assert!(dry.contains("#SBATCH --array=0-1%1\n"), "{dry}");
    assert!(
        dry.contains("--shard \"$((SLURM_ARRAY_TASK_ID + 4))\"\n"),
        "{dry}"
    );
    let first = submit(&[]);
    assert!(first.contains("shards 0-3 of 6 "), "{first}");
    assert!(first.contains("shards 4-5 of 6 "), "{first}");
    let offset_array = first
        .split("submitted shards job ")
        .nth(2)
        .and_then(|rest| rest.split(':').next())
        .unwrap()
        .to_string();
    let cancel = Command::new("scancel")
        .arg(format!("{offset_array}_1"))
        .output()
        .unwrap();
    assert!(cancel.status.success(), "{}", stderr(&cancel));
    wait_for_queue_to_empty();
    let status = stdout(&ternary(&config, &["status", "--shards", "6"]));
    assert!(
        status.contains("collisions[ipp-6]") && status.contains("missing [5]"),
        "{status}"
    );
    let logs = dir.join("data/slurm/logs");
    assert!(logs.join(format!("shard-{offset_array}_0.out")).exists());
    let second = submit(&[]);
    assert!(second.contains("shards 5 of 6 "), "{second}");
    assert!(!second.contains("shards 0-3"), "{second}");
    wait_for_queue_to_empty();
    assert_eq!(&merged_bytes(&dir.join("data")), single_process());
    let status = stdout(&ternary(&config, &["status"]));
    // Every instance fresh, then the estimate with nothing left to compute.
    let (estimate, instances) = status
        .trim_end()
        .lines()
        .collect::<Vec<_>>()
        .split_last()
        .map(|(last, rest)| (*last, rest.to_vec()))
        .unwrap();
    assert!(
        instances.iter().all(|line| line.contains("fresh")),
        "{status}"
    );
    assert!(
        estimate.starts_with("estimate: ")
            && estimate.contains("; 0 CPU-hours of it still to compute"),
        "{status}"
    );
}

/// Values that go into `#SBATCH` lines are in Slurm's own syntax: a newline
/// in `--partition` or `--time` wrote a bare `echo injected` line into both
/// scripts (run as a command), and `--partition ''` was accepted; so are the
/// other resources and the extra sbatch options. Valid lists and time
/// formats still produce the directives.
#[test]
fn slurm_options_cannot_inject_lines_into_the_scripts() {
    let dir = workspace("slurm-inject");
    let config = write_config(&dir, &study());
    let submit = |extra: &[&str]| {
        let args = [
            &["slurm", "submit", "--shards", "2", "--dry-run"][..],
            extra,
        ]
        .concat();
        ternary(&config, &args)
    };
    for (option, value) in [
        ("--partition", "p\necho injected"),
        ("--partition", ""),
        ("--partition", "a,,b"),
        ("--partition", "p q"),
        ("--time", "1:00\necho injected"),
        ("--time", "1:2:3:4"),
        ("--time", "tomorrow"),
        ("--time", "-1"),
        ("--merge-time", "1:00\necho injected"),
        ("--mem", "16G\necho injected"),
        ("--mem", "lots"),
        ("--account", "a b"),
        ("--qos", "$(id)"),
        ("--sbatch-arg", "--exclusive\necho injected"),
        ("--sbatch-arg", "--comment=a;b"),
        ("--sbatch-arg", "exclusive"),
        ("--shards", "1"),
        ("--cpus-per-task", "0"),
        ("--max-parallel", "0"),
    ] {
        let output = submit(&[&format!("{option}={value}")]);
        let message = stderr(&output);
        assert!(!output.status.success(), "{option} {value:?} accepted");
        assert!(message.contains(option), "{option} {value:?}: {message}");
        assert!(!stdout(&output).contains("echo injected"));
    }
    assert!(
        !dir.join("data/slurm/shards.sbatch").exists(),
        "no script is written"
    );
    for (partition, time) in [
        ("debug,long.q", "1-02:30:00"),
        ("gpu_a-1", "90"),
        ("x", "UNLIMITED"),
    ] {
        let output = submit(&["--partition", partition, "--time", time]);
        let text = stdout(&output);
        assert!(
            output.status.success(),
            "{partition} {time}: {}",
            stderr(&output)
        );
        assert!(
            text.contains(&format!("#SBATCH --partition={partition}\n")),
            "{text}"
        );
        assert!(text.contains(&format!("#SBATCH --time={time}\n")), "{text}");
    }
}

/// A dry run changes nothing on the filesystem: against a store path that
/// does not exist it prints both scripts (all shards missing) and leaves
/// the study directory as it was (it used to create the store: marker,
/// lock, folders).
#[test]
fn a_dry_run_creates_nothing() {
    let dir = workspace("slurm-dry-run");
    let config = write_config(&dir, &study());
    let before = common::files_under(&dir);
    let output = ternary(&config, &["slurm", "submit", "--shards", "4", "--dry-run"]);
    let text = stdout(&output);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(text.contains("slurm/shards.sbatch\n"), "{text}");
    assert!(text.contains("#SBATCH --array=0-3\n"), "{text}");
    assert!(text.contains("slurm/merge.sbatch\n"), "{text}");
    assert!(!dir.join("data").exists(), "the store was created");
    assert_eq!(common::files_under(&dir), before);
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        1,
        "only pipeline.toml"
    );
}

/// With every shard done but not merged, a dry run shows the merge job
/// alone and a command that submits only it (it named a `shards.sbatch` it
/// did not write); with every instance fresh there is nothing to submit.
#[test]
fn a_dry_run_without_missing_shards_names_only_what_would_run() {
    let dir = workspace("slurm-dry-run-done");
    let config = write_config(&dir, &study());
    for task in ["0", "1"] {
        let output = ternary(&config, &["run", "--shards", "2", "--shard", task]);
        assert!(output.status.success(), "{}", stderr(&output));
    }
    let dry_run = || {
        let output = ternary(&config, &["slurm", "submit", "--shards", "2", "--dry-run"]);
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let merge_only = dry_run();
    assert!(
        merge_only.starts_with("# no shards to compute: the merge job alone would run\n"),
        "{merge_only}"
    );
    assert!(!merge_only.contains("shards.sbatch"), "{merge_only}");
    assert!(!merge_only.contains("--array"), "{merge_only}");
    assert!(
        merge_only.contains("merge.sbatch\n#!/bin/bash\n"),
        "{merge_only}"
    );
    let submit = format!(
        "# submit: sbatch --parsable {}",
        dir.join("data/slurm/merge.sbatch").display()
    );
    assert_eq!(merge_only.lines().last(), Some(submit.as_str()));
    let store = common::files_under(&dir.join("data"));
    assert!(ternary(&config, &["run", "--shards", "2"]).status.success());
    assert_ne!(common::files_under(&dir.join("data")), store);
    let complete = common::files_under(&dir.join("data"));
    let nothing = dry_run();
    assert!(
        nothing.starts_with("nothing to submit: every stage instance is fresh"),
        "{nothing}"
    );
    assert!(!nothing.contains("sbatch"), "{nothing}");
    assert_eq!(common::files_under(&dir.join("data")), complete);
}

/// `[slurm]` keys shape the scripts and each command-line option replaces
/// its key: shards, CPUs (also the runs' threads), time and extra options.
#[test]
fn slurm_keys_shape_the_scripts_and_options_override_them() {
    let dir = workspace("slurm-config");
    let config = write_config(
        &dir,
        &format!(
            "{}\n[slurm]\nshards = 4\ncpus_per_task = 2\ntime = \"10:00\"\nsbatch_args = [\"--exclusive\"]\n",
            study()
        ),
    );
    let dry_run = |extra: &[&str]| {
        let output = ternary(
            &config,
            &[&["slurm", "submit", "--dry-run"][..], extra].concat(),
        );
        assert!(output.status.success(), "{}", stderr(&output));
        stdout(&output)
    };
    let configured = dry_run(&[]);
    for line in [
        "#SBATCH --array=0-3\n",
        "#SBATCH --cpus-per-task=2\n",
        "#SBATCH --time=10:00\n",
        "#SBATCH --exclusive\n",
        " run --threads 2 --shards 4 --shard ",
    ] {
        assert!(configured.contains(line), "{line:?} in {configured}");
    }
    let overridden = dry_run(&[
        "--shards",
        "2",
        "--cpus-per-task",
        "3",
        "--merge-time",
        "2:00:00",
        "--sbatch-arg=--requeue",
    ]);
    for line in [
        "#SBATCH --array=0-1\n",
        "#SBATCH --cpus-per-task=3\n",
        "#SBATCH --time=2:00:00\n",
        "#SBATCH --requeue\n",
        " run --threads 3 --shards 2 --shard ",
    ] {
        assert!(overridden.contains(line), "{line:?} in {overridden}");
    }
    assert!(!overridden.contains("--exclusive"), "{overridden}");
}
