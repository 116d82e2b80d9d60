//! Fault injection against the store: kill -9 at random times and at every
//! rename and fsync, ENOSPC at writes and EIO at fsyncs (by `strace`'s
//! syscall injection where the machine allows ptrace), and damage to every
//! file of a store (a flipped byte, truncation, deletion). After each fault:
//! nothing damaged is trusted, the next run ends with the same bytes as a
//! clean run, and `gc` leaves no debris.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

mod common;

use common::{
    BINARY, debris, files_under, flip_byte, result_bytes, small_study, stderr, stdout,
    strace_works, ternary, workspace, write_config,
};

/// Result bytes of a clean run of the small study.
fn reference() -> &'static BTreeMap<PathBuf, String> {
    static REFERENCE: OnceLock<BTreeMap<PathBuf, String>> = OnceLock::new();
    REFERENCE.get_or_init(|| {
        let dir = workspace("faults-reference");
        let config = write_config(&dir, &small_study("data"));
        assert!(ternary(&config, &["run"]).status.success());
        result_bytes(&dir.join("data"))
    })
}

/// A fresh workspace with the small study and no store yet.
fn study(name: &str) -> (PathBuf, PathBuf) {
    let dir = workspace(name);
    (write_config(&dir, &small_study("data")), dir.join("data"))
}

/// Runs `check(worker, case)` for every case, on one worker per core
/// (each case is a run of the binary and its recovery: independent of the
/// others when each worker keeps its own workspace, named by `worker`).
fn on_every_core<T: Sync>(cases: &[T], check: impl Fn(usize, &T) + Sync) {
    let next = AtomicUsize::new(0);
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
    std::thread::scope(|scope| {
        for worker in 0..workers {
            let (next, check) = (&next, &check);
            scope.spawn(move || {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(case) = cases.get(k) else { break };
                    check(worker, case);
                }
            });
        }
    });
}

/// The checks after any fault: no artifact in place is damaged unless the
/// fault damaged it (`damaged_allowed`), the next run succeeds, the store
/// holds exactly the clean run's bytes and verifies, and `gc` leaves no debris.
fn recovers(config: &Path, store: &Path, damaged_allowed: bool, what: &str) {
    if store.join("ternary-store.json").exists() && !damaged_allowed {
        let verify = stdout(&ternary(config, &["verify"]));
        assert!(!verify.contains("DAMAGED"), "{what}: {verify}");
    }
    let run = ternary(config, &["run", "--quiet"]);
    assert!(run.status.success(), "{what}: {}", stderr(&run));
    assert_eq!(&result_bytes(store), reference(), "{what}");
    let verify = ternary(config, &["verify"]);
    assert!(verify.status.success(), "{what}: {}", stdout(&verify));
    let gc = ternary(config, &["gc"]);
    assert!(gc.status.success(), "{what}: {}", stderr(&gc));
    assert!(
        stdout(&gc).contains("removed 0 artifacts"),
        "{what}: {}",
        stdout(&gc)
    );
    assert_eq!(debris(store), Vec::<PathBuf>::new(), "{what}");
}

/// `ternary --config <config> run --quiet --jobs 1` under strace with
/// `injection`, tracing only the main thread (which, one instance at a time,
/// does every store write; with more jobs each instance's thread writes
/// through the same staging, and strace would count per thread).
fn run_under_strace(config: &Path, trace: &str, injection: Option<String>) -> Output {
    let mut command = Command::new("strace");
    command.args(["-qq", "-o", "/dev/null", "-e", &format!("trace={trace}")]);
    if let Some(injection) = injection {
        command.args(["-e", &injection]);
    }
    command
        .args([BINARY, "--config"])
        .arg(config)
        .args(["run", "--quiet", "--jobs", "1"])
        .output()
        .unwrap()
}

/// How often the main thread of a clean run calls `syscall`.
fn calls_in_a_clean_run(syscall: &str) -> usize {
    let (config, _) = study(&format!("faults-count-{syscall}"));
    let log = config.with_file_name("strace.log");
    let output = Command::new("strace")
        .args(["-qq", "-e", &format!("trace={syscall}"), "-o"])
        .arg(&log)
        .args([BINARY, "--config"])
        .arg(&config)
        .args(["run", "--quiet", "--jobs", "1"])
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr(&output));
    fs::read_to_string(&log)
        .unwrap()
        .lines()
        .filter(|line| line.starts_with(&format!("{syscall}(")))
        .count()
}

/// Syscalls the store's atomic writes go through.
const RENAMES_AND_SYNCS: [&str; 5] = ["rename", "renameat", "renameat2", "fsync", "fdatasync"];

/// kill -9 at the entry of every rename and fsync of a run (the rename or
/// sync does not happen; everything before it did), on an empty store.
#[test]
fn kill_at_every_rename_and_fsync_recovers() {
    if !strace_works() {
        eprintln!("skipped: strace cannot trace here");
        return;
    }
    let cases: Vec<(&str, usize, usize)> = RENAMES_AND_SYNCS
        .into_iter()
        .flat_map(|syscall| {
            let calls = calls_in_a_clean_run(syscall);
            (1..=calls).map(move |when| (syscall, when, calls))
        })
        .collect();
    assert!(cases.len() >= 20, "only {} renames and syncs", cases.len());
    on_every_core(&cases, |worker, &(syscall, when, calls)| {
        let what = format!("kill at {syscall} #{when} of {calls}");
        let (config, store) = study(&format!("faults-kill-syscall-{worker}"));
        let injection = format!("inject={syscall}:signal=KILL:when={when}");
        let output = run_under_strace(&config, syscall, Some(injection));
        assert!(!output.status.success(), "{what}: the run was not killed");
        recovers(&config, &store, false, &what);
    });
}

/// ENOSPC at writes spread over a run, and EIO at every fsync: the run fails with an error naming the file, and leaves
/// nothing trusted.
#[test]
fn enospc_and_eio_fail_the_run_and_recover() {
    if !strace_works() {
        eprintln!("skipped: strace cannot trace here");
        return;
    }
    let writes = calls_in_a_clean_run("write");
    assert!(writes >= 20, "{writes} writes");
    // One failing write each (the error message itself must still reach stderr).
    let mut cases: Vec<(String, String)> = (0..12)
        .map(|k| {
            let when = 1 + (writes - 1) * k / 11;
            let injection = format!("inject=write:error=ENOSPC:when={when}..{when}");
            ("write".to_string(), injection)
        })
        .collect();
    for when in 1..=calls_in_a_clean_run("fsync") {
        cases.push((
            "fsync".into(),
            format!("inject=fsync:error=EIO:when={when}"),
        ));
    }
    let failed = AtomicUsize::new(0);
    on_every_core(&cases, |worker, (syscall, injection)| {
        let (config, store) = study(&format!("faults-errno-{worker}"));
        let output = run_under_strace(&config, syscall, Some(injection.clone()));
        if output.status.success() {
            // Only stdout writes were hit (a quiet run writes none) or the
            // error came after the last store write: the run is complete.
            assert_eq!(&result_bytes(&store), reference(), "{injection}");
            return;
        }
        let message = stderr(&output);
        assert!(
            message.contains("No space left on device") || message.contains("Input/output error"),
            "{injection}: {message}"
        );
        recovers(&config, &store, false, injection);
        failed.fetch_add(1, Ordering::Relaxed);
    });
    let failed = failed.into_inner();
    assert!(
        failed + 2 >= cases.len(),
        "only {failed} of {} injections failed the run",
        cases.len()
    );
}

/// kill -9 at pseudo-random times of a run, each on the store the previous
/// kill left (so kills land in every stage), then once on a fresh store.
#[test]
fn kill_at_random_times_recovers() {
    let (config, store) = study("faults-kill-random");
    let started = Instant::now();
    assert!(ternary(&config, &["run", "--quiet"]).status.success());
    let clean = started.elapsed();
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    for round in 0..16 {
        if round % 4 == 0 {
            fs::remove_dir_all(&store).unwrap();
        }
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let fraction = (state >> 11) as f64 / (1u64 << 53) as f64;
        let delay = clean.mul_f64(fraction);
        let mut child = Command::new(BINARY)
            .arg("--config")
            .arg(&config)
            .args(["run", "--quiet", "--jobs", "1"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(delay);
        let _ = child.kill();
        child.wait().unwrap();
        if store.join("ternary-store.json").exists() {
            let verify = stdout(&ternary(&config, &["verify"]));
            assert!(
                !verify.contains("DAMAGED"),
                "kill after {delay:?}: {verify}"
            );
        }
    }
    recovers(&config, &store, false, "random kills");
    let timeout = Duration::from_secs(60);
    assert!(started.elapsed() < timeout, "took {:?}", started.elapsed());
}

/// Every file of a computed store, damaged three ways (a flipped byte,
/// truncated to nothing, deleted): a damaged artifact is never called fresh
/// and is recomputed to the same bytes; a damaged ref or lock file is
/// rewritten; a damaged marker is rewritten when the rest is a store.
#[test]
fn damage_to_every_file_of_a_store_recovers() {
    let (config, store) = study("faults-damage-clean");
    assert!(ternary(&config, &["run", "--quiet"]).status.success());
    let files = files_under(&store);
    assert!(files.len() >= 15, "{files:?}");
    let damages: [(&str, Damage); 3] = [
        ("flipped byte", flip_byte),
        ("truncated", |path| fs::write(path, b"").unwrap()),
        ("deleted", |path| fs::remove_file(path).unwrap()),
    ];
    let cases: Vec<(&PathBuf, (&str, Damage))> = files
        .iter()
        .flat_map(|file| damages.map(|damage| (file, damage)))
        .collect();
    on_every_core(&cases, |worker, &(file, (damage, apply))| {
        let what = format!("{damage} {}", file.display());
        let (copy_config, copy) = study(&format!("faults-damage-{worker}"));
        copy_tree(&store, &copy);
        apply(&copy.join(file));
        let in_artifact = file.starts_with("artifacts");
        if in_artifact {
            let key = file
                .components()
                .nth(2)
                .unwrap()
                .as_os_str()
                .to_string_lossy();
            let status = stdout(&ternary(&copy_config, &["status"]));
            let line = status
                .lines()
                .find(|line| line.contains(&format!("key {}", &key[..12])))
                .unwrap_or_else(|| panic!("{what}: no line with key {key}: {status}"));
            assert!(line.contains("damaged"), "{what}: {line}");
            assert!(
                !ternary(&copy_config, &["verify"]).status.success(),
                "{what}"
            );
        }
        recovers(&copy_config, &copy, in_artifact, &what);
    });
}

/// A way to damage a file.
type Damage = fn(&Path);

fn copy_tree(from: &Path, to: &Path) {
    for file in files_under(from) {
        let target = to.join(&file);
        fs::create_dir_all(target.parent().unwrap()).unwrap();
        fs::copy(from.join(&file), target).unwrap();
    }
}
