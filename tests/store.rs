//! Regression tests of the store's guarantees, one per defect found by fault
//! testing: a foreign folder is never emptied, a damaged artifact is never
//! trusted, refs survive interruptions, counts and ids are bounded at load,
//! and bad command-line input is refused instead of panicking or hanging.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;

use common::{
    BINARY, REDUCED_STUDY, SMALL_STUDY_INSTANCES, flip_byte, result_bytes, run_counts, small_study,
    stderr, stdout, strace_works, ternary, workspace, write_config,
};

/// A workspace with the small study, its store at `data/`, computed once.
fn computed_study(name: &str) -> (PathBuf, PathBuf) {
    let dir = workspace(name);
    let config = write_config(&dir, &small_study("data"));
    assert_eq!(run_counts(&config, &[]), (SMALL_STUDY_INSTANCES, 0));
    (config, dir.join("data"))
}

/// The single artifact directory of `stage`.
fn artifact_of(store: &Path, stage: &str) -> PathBuf {
    let dirs: Vec<PathBuf> = fs::read_dir(store.join("artifacts").join(stage))
        .unwrap()
        .map(|entry| entry.unwrap().path())
        .collect();
    assert_eq!(dirs.len(), 1, "{stage}: {dirs:?}");
    dirs[0].clone()
}

/// The line of `status` for one instance.
fn status_of(config: &Path, instance: &str) -> String {
    let text = stdout(&ternary(config, &["status"]));
    text.lines()
        .find(|line| line.starts_with(instance))
        .unwrap_or_else(|| panic!("no {instance} in {text}"))
        .to_string()
}

/// The id in a store's marker.
fn store_id(store: &Path) -> String {
    let marker: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(store.join("ternary-store.json")).unwrap())
            .unwrap();
    marker["id"].as_str().expect("the marker's id").to_string()
}

/// A change to a manifest document.
type ManifestEdit = fn(&mut serde_json::Value);

fn edit_manifest(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = dir.join("manifest.json");
    let mut manifest: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut manifest);
    fs::write(&path, serde_json::to_vec_pretty(&manifest).unwrap()).unwrap();
}

/// A user's project folder as a store path: `run` and `gc` refuse it and no
/// file of it is touched (today's code deleted `tmp/my_project/src/main.c`
/// and `artifacts/release/v1.0/`).
#[test]
fn a_foreign_folder_is_refused_and_keeps_every_file() {
    let dir = workspace("foreign");
    let project = dir.join("project");
    let files = [
        "tmp/my_project/src/main.c",
        "artifacts/release/v1.0/notes.txt",
        "src/lib.rs",
    ];
    for file in files {
        let path = project.join(file);
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(&path, file).unwrap();
    }
    let config = write_config(&dir, &small_study("project"));
    for command in [&["run"][..], &["gc"], &["status"], &["verify"]] {
        let output = ternary(&config, command);
        assert!(
            !output.status.success(),
            "{command:?} accepted a foreign folder"
        );
        assert!(
            stderr(&output).contains("is not a ternary store"),
            "{command:?}: {}",
            stderr(&output)
        );
    }
    for file in files {
        assert_eq!(fs::read_to_string(project.join(file)).unwrap(), file);
    }
    assert!(!project.join("ternary-store.json").exists());
}

/// A folder is a store only when its marker is ours, a marker that is not
/// ours is never written over, and `gc` removes only debris named with the
/// store's id. Before: a `mine/` holding only
/// `artifacts/collisions/<64 hex>/manifest.json` (any JSON) and a file beside
/// it was accepted (verify called the manifest unreadable, gc deleted both);
/// a user's `ternary-store.json` was overwritten by `run` and `store.lock`
/// rewritten by `gc`; `gc` deleted `tmp/<64 hex>.123/thesis.tex` and
/// `refs/kernel/.notes.json.42`.
#[test]
fn only_a_store_of_ours_is_adopted_and_only_its_debris_removed() {
    let dir = workspace("adoption");
    let key = "a".repeat(64);
    let shaped = dir.join("mine");
    let artifact = shaped.join("artifacts/collisions").join(&key);
    let own = [
        (shaped.join("ternary-store.json"), "my notes on the store"),
        (shaped.join("store.lock"), "my lock"),
        (artifact.join("manifest.json"), "{\"any\": \"json\"}"),
        (artifact.join("thesis.txt"), "mine"),
    ];
    for (path, text) in &own {
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(path, text).unwrap();
    }
    let config = write_config(&dir, &small_study("mine"));
    for command in [&["run"][..], &["verify"], &["gc"], &["status"]] {
        let output = ternary(&config, command);
        assert!(!output.status.success(), "{command:?} adopted the folder");
        assert!(
            stderr(&output).contains("is not a ternary store"),
            "{}",
            stderr(&output)
        );
    }
    for (path, text) in &own {
        assert_eq!(
            fs::read_to_string(path).unwrap(),
            *text,
            "{}",
            path.display()
        );
    }
    // In a store of ours: a user's entries shaped like debris are kept, the
    // store's own debris (named with its id) is removed.
    let (config, store) = computed_study("adoption-debris");
    let id = store_id(&store);
    assert_eq!(id.len(), 16, "{id}");
    let users = [
        store
            .join("tmp")
            .join(format!("{key}.123"))
            .join("thesis.tex"),
        store.join("refs/kernel/.notes.json.42"),
    ];
    for path in &users {
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(path, "mine").unwrap();
    }
    let ours = [
        store
            .join("tmp")
            .join(format!("{key}.{id}.77@node-1"))
            .join("kernel.parquet"),
        store
            .join("refs/kernel")
            .join(format!(".ipp-6.json.{id}.77")),
    ];
    for path in &ours {
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(path, "debris").unwrap();
    }
    let verify = stdout(&ternary(&config, &["verify"]));
    assert!(
        verify.contains(&format!("foreign  {}", users[1].display())),
        "{verify}"
    );
    let gc = ternary(&config, &["gc"]);
    assert!(gc.status.success(), "{}", stderr(&gc));
    for path in &users {
        assert_eq!(
            fs::read_to_string(path).unwrap(),
            "mine",
            "{}",
            path.display()
        );
    }
    for path in &ours {
        assert!(!path.exists(), "{}", path.display());
    }
}

/// An empty or missing folder becomes a store with its marker.
#[test]
fn an_empty_or_missing_folder_becomes_a_marked_store() {
    let dir = workspace("marker");
    fs::create_dir_all(dir.join("empty")).unwrap();
    for store in ["empty", "missing/deeper"] {
        let config = write_config(&dir, &small_study(store));
        assert_eq!(run_counts(&config, &[]), (SMALL_STUDY_INSTANCES, 0));
        let marker = fs::read_to_string(dir.join(store).join("ternary-store.json")).unwrap();
        assert!(marker.contains("\"ternary-store\""), "{marker}");
    }
}

/// Entries ternary did not create in `tmp/` and `artifacts/` are reported and
/// kept by `run`, `verify` and `gc`, and do not make a run fail (today a
/// foreign file in `tmp/` failed every later run).
#[test]
fn foreign_entries_inside_a_store_are_left_alone() {
    let (config, store) = computed_study("foreign-entries");
    let foreign = [
        store.join("tmp/notes.txt"),
        store.join("tmp/keep/inside.txt"),
        store.join("artifacts/scan/my-results/table.csv"),
    ];
    for path in &foreign {
        fs::create_dir_all(path.parent().unwrap()).unwrap();
        fs::write(path, "mine").unwrap();
    }
    assert_eq!(run_counts(&config, &[]), (0, SMALL_STUDY_INSTANCES));
    let verify = ternary(&config, &["verify"]);
    assert!(verify.status.success(), "{}", stdout(&verify));
    assert!(stdout(&verify).contains("foreign"), "{}", stdout(&verify));
    let gc = ternary(&config, &["gc"]);
    assert!(gc.status.success(), "{}", stderr(&gc));
    assert!(
        stdout(&gc).contains("removed 0 artifacts"),
        "{}",
        stdout(&gc)
    );
    for path in &foreign {
        assert_eq!(
            fs::read_to_string(path).unwrap(),
            "mine",
            "{}",
            path.display()
        );
    }
}

/// A user's file (and folder) inside an artifact directory was deleted by
/// `run` ("replaced a damaged artifact: notes.txt: not listed in the
/// manifest"). Now it is no damage: the artifact stays fresh and `verify`
/// lists the entries as foreign; a forced recomputation moves the old
/// artifact aside with them (`<key>.kept-1`, kept by every command) and says
/// so; `gc` keeps an unreferenced artifact that holds them.
#[test]
fn a_users_files_inside_an_artifact_are_kept() {
    let (config, store) = computed_study("user-files-in-artifact");
    let kernel = artifact_of(&store, "kernel");
    let notes = kernel.join("notes.txt");
    let folder = kernel.join("mine/plot.py");
    fs::write(&notes, "mine").unwrap();
    fs::create_dir_all(folder.parent().unwrap()).unwrap();
    fs::write(&folder, "mine").unwrap();
    assert_eq!(run_counts(&config, &[]), (0, SMALL_STUDY_INSTANCES));
    let verify = ternary(&config, &["verify"]);
    let text = stdout(&verify);
    assert!(verify.status.success(), "{text}");
    assert!(
        text.contains(&format!("foreign  {}", notes.display())),
        "{text}"
    );
    assert!(
        text.contains(&format!("foreign  {}", kernel.join("mine").display())),
        "{text}"
    );
    let forced = ternary(&config, &["run", "--only", "kernel", "--force", "kernel"]);
    let line = stdout(&forced);
    assert!(forced.status.success(), "{}", stderr(&forced));
    let aside = kernel.with_file_name(format!(
        "{}.kept-1",
        kernel.file_name().unwrap().to_string_lossy()
    ));
    assert!(
        line.contains(&format!("moved it to {}", aside.display())),
        "{line}"
    );
    assert!(line.contains("mine, notes.txt"), "{line}");
    assert_eq!(fs::read_to_string(aside.join("notes.txt")).unwrap(), "mine");
    assert_eq!(
        fs::read_to_string(aside.join("mine/plot.py")).unwrap(),
        "mine"
    );
    assert!(kernel.join("manifest.json").is_file());
    assert!(ternary(&config, &["verify"]).status.success());
    // Unreferenced once the kernel's parameters change: gc keeps it (the
    // user's file inside), and the set-aside copy, a foreign entry.
    fs::write(kernel.join("notes.txt"), "mine again").unwrap();
    let changed = small_study("data").replace("[sweep]", "[kernel]\nbin_width = 1e-4\n\n[sweep]");
    let config = write_config(config.parent().unwrap(), &changed);
    assert!(ternary(&config, &["run", "--quiet"]).status.success());
    let gc = ternary(&config, &["gc"]);
    let text = stdout(&gc);
    assert!(gc.status.success(), "{}", stderr(&gc));
    assert!(
        text.contains(&format!("gc: kept {} (unreferenced", kernel.display())),
        "{text}"
    );
    assert_eq!(
        fs::read_to_string(kernel.join("notes.txt")).unwrap(),
        "mine again"
    );
    assert_eq!(fs::read_to_string(aside.join("notes.txt")).unwrap(), "mine");
}

/// A stray file where ternary keeps directories blocked the store: after
/// `refs/notes.txt`, `run`, `verify` and `gc` exited 1 with "Not a directory
/// (os error 20)"; after `artifacts/notes.txt`, `verify` and `gc` did. Now
/// they are listed as foreign and kept, and every command goes on.
#[test]
fn stray_files_among_the_stores_folders_are_foreign_not_fatal() {
    let (config, store) = computed_study("stray-files");
    let stray = [
        store.join("refs/notes.txt"),
        store.join("artifacts/notes.txt"),
        store.join("refs/kernel/notes.md"),
    ];
    for path in &stray {
        fs::write(path, "mine").unwrap();
    }
    assert_eq!(run_counts(&config, &[]), (0, SMALL_STUDY_INSTANCES));
    let verify = ternary(&config, &["verify"]);
    let text = stdout(&verify);
    assert!(verify.status.success(), "{text}{}", stderr(&verify));
    for path in &stray {
        assert!(
            text.contains(&format!("foreign  {}", path.display())),
            "{text}"
        );
    }
    let gc = ternary(&config, &["gc"]);
    assert!(gc.status.success(), "{}", stderr(&gc));
    let status = ternary(&config, &["status"]);
    assert!(status.status.success(), "{}", stderr(&status));
    for path in &stray {
        assert_eq!(
            fs::read_to_string(path).unwrap(),
            "mine",
            "{}",
            path.display()
        );
    }
}

/// One flipped byte in an input: `status` calls it damaged, a forced
/// downstream stage refuses to read it (today it wrote different bytes under
/// the same key), and the next run recomputes it to the original bytes while
/// its consumers stay fresh.
#[test]
fn a_flipped_byte_in_an_input_is_never_used_and_is_repaired() {
    let (config, store) = computed_study("flip-input");
    let clean = result_bytes(&store);
    flip_byte(&artifact_of(&store, "collisions").join("events.parquet"));
    let line = status_of(&config, "collisions[ipp-6]");
    assert!(
        line.contains("damaged (key ") && line.contains("events.parquet: sha256"),
        "{line}"
    );
    let forced = ternary(&config, &["run", "--only", "moments", "--force", "moments"]);
    assert!(!forced.status.success(), "a damaged input was read");
    assert!(
        stderr(&forced).contains("input is not available"),
        "{}",
        stderr(&forced)
    );
    let output = ternary(&config, &["run"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = stdout(&output);
    assert!(
        text.contains("replaced a damaged artifact: events.parquet: sha256"),
        "{text}"
    );
    assert!(text.contains("run: 1 computed"), "{text}");
    assert_eq!(result_bytes(&store), clean);
    assert!(ternary(&config, &["verify"]).status.success());
}

/// A damaged final table (no consumer reads it) is recomputed by a plain run
/// (today the store stayed damaged until `--force`).
#[test]
fn a_damaged_final_table_is_recomputed_without_force() {
    let (config, store) = computed_study("flip-table");
    let clean = result_bytes(&store);
    flip_byte(&artifact_of(&store, "table").join("table.parquet"));
    assert!(status_of(&config, "table[study]").contains("damaged"));
    assert_eq!(run_counts(&config, &[]), (1, SMALL_STUDY_INSTANCES - 1));
    assert_eq!(result_bytes(&store), clean);
}

/// Edited manifests are damaged artifacts for `verify`, `status` and `run`
/// (today `files = []` verified and was called fresh).
#[test]
fn an_edited_manifest_is_damaged() {
    let (config, store) = computed_study("edit-manifest");
    let clean = result_bytes(&store);
    let edits: [(&str, ManifestEdit); 4] = [
        ("files = []", |m| m["files"] = serde_json::json!([])),
        ("parameters", |m| m["params"]["window"] = 0.3.into()),
        ("content hash", |m| {
            m["files"][0]["content_sha256"] = "0".repeat(64).into()
        }),
        ("seal", |m| m["manifest_sha256"] = "1".repeat(64).into()),
    ];
    for (what, edit) in edits {
        let kernel = artifact_of(&store, "kernel");
        edit_manifest(&kernel, edit);
        // `show` warns and exits non-zero (before: rows, exit 0, no warning).
        let key = kernel.file_name().unwrap().to_string_lossy().into_owned();
        let show = ternary(&config, &["show", &key[..12]]);
        assert!(!show.status.success(), "{what}: show passed");
        assert!(
            stdout(&show).starts_with("DAMAGED "),
            "{what}: {}",
            stdout(&show)
        );
        let verify = ternary(&config, &["verify"]);
        assert!(!verify.status.success(), "{what}: verify passed");
        assert!(stdout(&verify).contains("DAMAGED  kernel/"), "{what}");
        assert!(
            status_of(&config, "kernel[").contains("damaged"),
            "{what}: not damaged in status"
        );
        assert_eq!(
            run_counts(&config, &[]),
            (1, SMALL_STUDY_INSTANCES - 1),
            "{what}"
        );
        assert_eq!(result_bytes(&store), clean, "{what}");
    }
    // Hand-written manifests without a seal are still checked against their
    // key, listing and hashes: a params edit shows.
    edit_manifest(&artifact_of(&store, "fit"), |m| {
        m.as_object_mut().unwrap().remove("manifest_sha256");
        m["params"]["range_min"] = 1e-3.into();
    });
    let line = status_of(&config, "fit[");
    assert!(line.contains("do not give its key"), "{line}");
}

/// A run killed between committing an artifact and writing its ref loses the
/// ref: the next run rewrites it, `status` still names a changed parameter
/// (from the latest manifest) and the orphan temporary ref is removed.
#[test]
fn a_lost_ref_is_rewritten_and_status_still_explains() {
    let (config, store) = computed_study("lost-ref");
    let refs = store.join("refs/scan");
    let reference = fs::read(refs.join("ipp-6.json")).unwrap();
    fs::remove_file(refs.join("ipp-6.json")).unwrap();
    let temporary = format!(".ipp-6.json.{}.4242", store_id(&store));
    fs::write(refs.join(&temporary), "{").unwrap();
    let dir = config.parent().unwrap();
    write_config(
        dir,
        &small_study("data").replace("points = 7", "points = 9"),
    );
    let line = status_of(&config, "scan[ipp-6]");
    assert!(line.contains("parameter grid.points: 7 -> 9"), "{line}");
    write_config(dir, &small_study("data"));
    assert_eq!(run_counts(&config, &[]), (0, SMALL_STUDY_INSTANCES));
    assert_eq!(fs::read(refs.join("ipp-6.json")).unwrap(), reference);
    assert!(!refs.join(&temporary).exists());
}

/// `verify` on a store that does not exist fails and creates nothing (today
/// it created the store and passed).
#[test]
fn verify_of_a_missing_store_fails_and_creates_nothing() {
    let dir = workspace("verify-missing");
    let config = write_config(&dir, &small_study("data"));
    let verify = ternary(&config, &["verify"]);
    assert!(!verify.status.success());
    assert!(
        stderr(&verify).contains("no store at"),
        "{}",
        stderr(&verify)
    );
    let status = ternary(&config, &["status"]);
    assert!(status.status.success(), "{}", stderr(&status));
    assert!(stdout(&status).contains("missing: never computed"));
    assert!(!dir.join("data").exists());
}

/// A store that cannot be written (the lock file cannot be opened) still runs
/// when everything is fresh, and says what it cannot compute otherwise
/// (today it failed at `store.lock`). The read-only filesystem is simulated by
/// strace injecting EROFS into every call on the lock file.
#[test]
fn a_read_only_store_runs_when_everything_is_fresh() {
    if !strace_works() {
        eprintln!("skipped: strace cannot trace here");
        return;
    }
    let (config, store) = computed_study("read-only");
    let read_only = |args: &[&str]| {
        Command::new("strace")
            .args(["-f", "-qq", "-o", "/dev/null", "-P"])
            .arg(store.join("store.lock"))
            .args(["-e", "inject=openat:error=EROFS", BINARY, "--config"])
            .arg(&config)
            .args(args)
            .output()
            .unwrap()
    };
    let output = read_only(&["run"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let fresh = format!("run: 0 computed, {SMALL_STUDY_INSTANCES} fresh");
    assert!(stdout(&output).contains(&fresh), "{}", stdout(&output));
    let dir = config.parent().unwrap();
    write_config(
        dir,
        &small_study("data").replace("points = 7", "points = 9"),
    );
    let output = read_only(&["run"]);
    assert!(!output.status.success());
    assert!(
        stderr(&output).contains("scan[ipp-6] needs computing, but the store cannot be written"),
        "{}",
        stderr(&output)
    );
}

/// While another process holds the lock, a run says so (today the message
/// could read "held by process " with no holder).
#[test]
fn a_waiting_run_names_the_lock_holder_plainly() {
    let (config, store) = computed_study("lock-holder");
    let lock = fs::OpenOptions::new()
        .write(true)
        .truncate(true)
        .open(store.join("store.lock"))
        .unwrap();
    lock.lock().unwrap();
    let child = Command::new(BINARY)
        .arg("--config")
        .arg(&config)
        .arg("run")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    std::thread::sleep(Duration::from_millis(300));
    lock.unlock().unwrap();
    let output = child.wait_with_output().unwrap();
    assert!(output.status.success());
    assert!(started.elapsed() < Duration::from_secs(30));
    let message = stderr(&output);
    assert!(message.contains("(held by another process)"), "{message}");
}

/// Every count has an upper bound and every potential a short id, checked at
/// load with the key and line (today these allocated gigabytes, ran on, or
/// failed with "File name too long" after committing an artifact).
#[test]
fn counts_ranges_and_ids_are_bounded_at_load() {
    let dir = workspace("bounds");
    let study = small_study("data");
    let cases: [(&str, &str, &str); 12] = [
        ("points = 7", "points = 4000000000", "scan.points"),
        (
            "randomizations = 2",
            "randomizations = 1000000000",
            "collisions.randomizations",
        ),
        ("points = 64", "points = 4294967295", "collisions.points"),
        (
            "pilot_points = 0",
            "pilot_points = 5",
            "collisions.pilot_points",
        ),
        (
            "inverse_power = [6]",
            "inverse_power = [1e300]",
            "potentials.inverse_power[0]",
        ),
        (
            "inverse_power = [6]",
            "inverse_power = [6.12345678901234567890123]\nlennard_jones = [1e-9]",
            "potentials.lennard_jones[0]",
        ),
        ("offset_max = 3.0", "offset_max = inf", "scan.offset_max"),
        (
            "[sweep]",
            "[[gas]]\nname = \"dense\"\npotential = \"ipp-6\"\nl0_um = 1.0\neps_ev = 1.0\nkt_ev = 0.1\nmass_electron = 1.0\nring_particles = 100000\nring_radius_um = 1.0\n\n[sweep]",
            "gas[0].ring_radius_um",
        ),
        (
            "pilot_points = 0",
            "pilot_points = 0\n\n[collisions.points_per_potential]\n\"ipp-6\" = 1",
            "collisions.points_per_potential.ipp-6",
        ),
        (
            "pilot_points = 0",
            "pilot_points = 0\n\n[collisions.strata_per_potential]\n\"ipp-6\" = { opposite = 64, same_side = 24 }",
            "collisions.strata_per_potential.ipp-6.same_side",
        ),
        (
            "pilot_points = 0",
            "pilot_points = 0\n\n[collisions.slow_launch_per_potential]\n\"ipp-6\" = { share = 0.3, speed = 0.5 }",
            "collisions.slow_launch_per_potential.ipp-6.share",
        ),
        (
            "[sweep]\nenabled = false",
            "[sweep]\nenabled = false\npoints = 100000",
            "sweep.points",
        ),
    ];
    for (from, to, key) in cases {
        let text = study.replace(from, to);
        assert_ne!(text, study, "{from}");
        let config = write_config(&dir, &text);
        let started = Instant::now();
        let output = ternary(&config, &["dag"]);
        assert!(!output.status.success(), "{key}: accepted");
        assert!(started.elapsed() < Duration::from_secs(5), "{key}: slow");
        let message = stderr(&output);
        assert!(message.contains(&format!("`{key}`")), "{key}: {message}");
        let first = text[..text.find(to).unwrap()].matches('\n').count() + 1;
        let last = first + to.matches('\n').count();
        let line: usize = message
            .split("pipeline.toml:")
            .nth(1)
            .and_then(|rest| rest.split(':').next())
            .and_then(|number| number.parse().ok())
            .unwrap_or_else(|| panic!("{key}: no line in {message}"));
        assert!(
            (first..=last).contains(&line),
            "{key}: line {line}: {message}"
        );
        assert!(message.len() < 400, "{key}: {message}");
    }
}

/// TOML syntax errors and non-UTF-8 files are reported with their line
/// (today: an empty key and no line).
#[test]
fn syntax_and_encoding_errors_name_their_line() {
    let dir = workspace("syntax");
    let config = dir.join("pipeline.toml");
    fs::write(&config, "[potentials]\ninverse_power = [6\n[scan]\n").unwrap();
    let message = stderr(&ternary(&config, &["dag"]));
    assert!(
        message.contains("pipeline.toml:3: TOML syntax:"),
        "{message}"
    );
    assert!(!message.contains("``"), "{message}");
    fs::write(&config, b"[potentials]\n# caf\xe9\ninverse_power = [6]\n").unwrap();
    let message = stderr(&ternary(&config, &["dag"]));
    assert!(
        message.contains("pipeline.toml:2: the file is not UTF-8 text"),
        "{message}"
    );
}

/// Bench arguments are validated: each bad value exits with an error naming
/// it, quickly, without a panic (before: index out of bounds, CrowdedRing,
/// Breakdown, hangs, a 48 TB allocation, NaN tables with exit 0; balance's
/// bin width "capacity overflow" (exit 101) and NaN tables).
#[test]
fn bench_arguments_are_validated() {
    let cases: [(&[&str], &str); 14] = [
        (&["md", "--particles", "0"], "--particles"),
        (&["md", "--radius-um", "0"], "--radius-um"),
        (&["md", "--kt-ev", "0"], "--kt-ev"),
        (&["md", "--kt-ev", "nan"], "--kt-ev"),
        (&["md", "--radius-um=-100"], "--radius-um"),
        (&["md", "--final-time-ns", "1e30"], "--final-time-ns"),
        (
            &["md", "--particles", "100000", "--radius-um", "1"],
            "--radius-um",
        ),
        (&["integrators", "--scenes", "1", "--n=-1"], "--n"),
        (&["integrators", "--scenes", "1000000000000"], "--scenes"),
        (&["integrators", "--scenes", "0"], "--scenes"),
        (&["integrators", "--n", "nan"], "--n"),
        (
            &["balance", "--bin-width", "1e-300", "--randomizations", "2"],
            "--bin-width",
        ),
        (&["balance", "--bin-width", "1e300"], "--bin-width"),
        (&["balance", "--separation", "1000"], "--separation"),
    ];
    for (args, option) in cases {
        let started = Instant::now();
        let output = Command::new(BINARY)
            .arg("bench")
            .args(args)
            .output()
            .unwrap();
        let message = stderr(&output);
        assert!(!output.status.success(), "{args:?} succeeded");
        assert!(!message.contains("panicked"), "{args:?}: {message}");
        assert!(message.contains(option), "{args:?}: {message}");
        assert!(started.elapsed() < Duration::from_secs(5), "{args:?}: slow");
    }
}

/// Runs share the store: three at once on an empty store all succeed (each
/// commits what it computed first, or keeps an identical copy another run
/// committed), the store holds the bytes of a single run and verifies, and
/// `gc` afterwards finds nothing to remove and no debris.
#[test]
fn concurrent_runs_agree_on_every_byte() {
    let single = workspace("concurrent-single");
    let text = small_study("data").replace("points = 7", "points = 2001");
    let config = write_config(&single, &text);
    assert_eq!(run_counts(&config, &[]), (SMALL_STUDY_INSTANCES, 0));
    let dir = workspace("concurrent");
    let config = write_config(&dir, &text);
    let runs: Vec<_> = (0..3)
        .map(|_| {
            Command::new(BINARY)
                .arg("--config")
                .arg(&config)
                .arg("run")
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut computed = 0;
    for run in runs {
        let output = run.wait_with_output().unwrap();
        assert!(output.status.success(), "{}", stderr(&output));
        computed += stdout(&output).matches("computed in").count();
    }
    assert!(computed >= SMALL_STUDY_INSTANCES, "{computed}");
    let store = dir.join("data");
    assert_eq!(result_bytes(&store), result_bytes(&single.join("data")));
    assert!(ternary(&config, &["verify"]).status.success());
    let gc = ternary(&config, &["gc"]);
    assert!(
        stdout(&gc).contains("removed 0 artifacts (0 bytes) and 0 staging entries"),
        "{}",
        stdout(&gc)
    );
}

/// Products of bounded counts were unbounded: `md.runs = 65536` with
/// `final_time_ns = 1.5e8` loaded (~60 CPU-years at the measured speed), and
/// 256 u' x 256 densities with bins of 2.1e-7 loaded as 65 536 kernel
/// instances (~2.8 TB), refused by the estimate only after planning them
/// (187 s and 1.8 GB on the default study). Now `run` and `slurm submit`
/// refuse a study whose estimate exceeds `[limits]`, naming it and creating
/// nothing; `status` shows the estimate; a raised limit or `--i-know` lets
/// it start; and more than 4096 kernels are refused at load, before any
/// planning, on the default study too.
#[test]
fn a_study_beyond_the_limits_is_refused_unless_allowed() {
    let dir = workspace("limits");
    let years = REDUCED_STUDY
        .replacen("runs = 4", "runs = 65536", 1)
        .replacen("final_time_ns = 100.0", "final_time_ns = 1.5e8", 1);
    let lists = |u_primes: u32, densities: u32| {
        let u_primes: Vec<String> = (0..u_primes)
            .map(|k| format!("{}", -3.0 + 6.0 * f64::from(k) / 255.0))
            .collect();
        let densities: Vec<String> = (0..densities)
            .map(|k| format!("{}", 0.1 * f64::from(k) / 255.0))
            .collect();
        format!(
            "u_prime = [{}]\ndensity = [{}]\n",
            u_primes.join(", "),
            densities.join(", ")
        )
    };
    let terabytes = small_study("data").replacen(
        "[sweep]",
        &format!("[kernel]\n{}bin_width = 2.1e-7\n\n[sweep]", lists(64, 63)),
        1,
    );
    let default_study =
        fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("pipeline.toml")).unwrap();
    let listed = "u_prime = [0.0, -0.25, -0.5, -1.0, -2.0, -3.0]\ndensity = [0.0]\n";
    assert_eq!(default_study.matches(listed).count(), 1);
    let at_load = default_study.replacen(listed, &lists(256, 256), 1);
    let config = write_config(&dir, &at_load);
    for command in [&["run"][..], &["status"], &["slurm", "submit", "--dry-run"]] {
        let started = Instant::now();
        let output = ternary(&config, command);
        assert!(
            !output.status.success(),
            "{command:?} accepted 65 536 kernels"
        );
        assert!(
            stderr(&output).contains("more than 4096"),
            "{}",
            stderr(&output)
        );
        assert!(
            started.elapsed() < Duration::from_secs(5),
            "{:?}",
            started.elapsed()
        );
    }
    for (name, study, beyond, within) in [
        ("years", years, "limits.cpu_hours", Some("limits.store_gb")),
        ("terabytes", terabytes, "limits.store_gb", None),
    ] {
        let config = write_config(&dir, &study);
        for command in [&["run"][..], &["slurm", "submit", "--dry-run"]] {
            let started = Instant::now();
            let output = ternary(&config, command);
            let message = stderr(&output);
            assert!(!output.status.success(), "{name}: {command:?} started");
            assert!(
                message.contains("beyond [limits]") && message.contains(beyond),
                "{message}"
            );
            assert!(within.is_none_or(|key| !message.contains(key)), "{message}");
            assert!(
                started.elapsed() < Duration::from_secs(10),
                "{name}: slow refusal of {command:?}: {:?}",
                started.elapsed()
            );
        }
        assert!(!dir.join("data").exists(), "{name}: a store was created");
        let status = stdout(&ternary(&config, &["status"]));
        let estimate = status.lines().last().unwrap();
        assert!(estimate.starts_with("estimate: "), "{estimate}");
    }
    // A small study under a limit lowered below it: refused, then allowed.
    let tiny = format!("{}\n[limits]\ncpu_hours = 1e-9\n", small_study("data"));
    let config = write_config(&dir, &tiny);
    assert!(!ternary(&config, &["run", "--quiet"]).status.success());
    // Before anything is computed, the dry run's scripts pass the permission on.
    let dry = stdout(&ternary(
        &config,
        &["slurm", "submit", "--dry-run", "--i-know"],
    ));
    assert!(dry.contains("run --i-know --shards"), "{dry}");
    assert!(
        ternary(&config, &["run", "--quiet", "--i-know"])
            .status
            .success()
    );
}

/// A `gc` killed while deleting an unreferenced artifact left its folder
/// without a manifest: every later `gc` kept it as "holds entries ternary did
/// not write", and `verify` exited 1 for good (issue 54, item 3). Now `gc`
/// renames an artifact into its own debris before deleting it: killed at
/// any unlink, the next `gc` removes the rest and `verify` passes.
#[test]
fn a_killed_gc_leaves_nothing_a_later_gc_keeps() {
    if !strace_works() {
        eprintln!("skipped: strace cannot trace here");
        return;
    }
    for when in [1, 3, 7] {
        let (config, store) = computed_study(&format!("gc-killed-{when}"));
        let changed =
            small_study("data").replace("[sweep]", "[kernel]\nbin_width = 1e-4\n\n[sweep]");
        let config = write_config(config.parent().unwrap(), &changed);
        assert!(ternary(&config, &["run", "--quiet"]).status.success());
        let output = Command::new("strace")
            .args(["-f", "-qq", "-o", "/dev/null", "-e", "trace=unlinkat"])
            .args(["-e", &format!("inject=unlinkat:signal=KILL:when={when}")])
            .args([BINARY, "--config"])
            .arg(&config)
            .arg("gc")
            .output()
            .unwrap();
        assert!(!output.status.success(), "gc #{when} was not killed");
        let gc = ternary(&config, &["gc"]);
        let text = stdout(&gc);
        assert!(gc.status.success(), "{}", stderr(&gc));
        assert!(
            !text.contains("gc: kept"),
            "kill at unlinkat #{when}: {text}"
        );
        let verify = ternary(&config, &["verify"]);
        assert!(
            verify.status.success(),
            "kill at unlinkat #{when}: {}",
            stdout(&verify)
        );
        assert!(
            common::debris(&store).is_empty(),
            "{:?}",
            common::debris(&store)
        );
    }
}

/// `show <key>` of a truncated, appended or deleted table, or of an
/// artifact without its manifest, printed a raw "Corrupt footer" (issue 54,
/// messages). Now it prints the `DAMAGED` listing, each unreadable file named.
#[test]
fn show_lists_a_damaged_artifact_instead_of_failing() {
    type Damage = fn(&Path);
    let damages: [(&str, Damage); 4] = [
        ("truncated", |dir| {
            let path = dir.join("kernel.parquet");
            let bytes = fs::read(&path).unwrap();
            fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        }),
        ("appended", |dir| {
            let path = dir.join("kernel.parquet");
            let mut bytes = fs::read(&path).unwrap();
            bytes.extend_from_slice(b"trailing");
            fs::write(&path, bytes).unwrap();
        }),
        ("deleted", |dir| {
            fs::remove_file(dir.join("kernel.parquet")).unwrap()
        }),
        ("no manifest", |dir| {
            fs::remove_file(dir.join("manifest.json")).unwrap()
        }),
    ];
    for (what, damage) in damages {
        let (config, store) = computed_study(&format!("show-damaged-{}", what.replace(' ', "-")));
        let kernel = artifact_of(&store, "kernel");
        damage(&kernel);
        let key = kernel.file_name().unwrap().to_string_lossy().into_owned();
        for target in [key.as_str(), "kernel[ipp-6_u0_rho0]"] {
            let shown = ternary(&config, &["show", target]);
            let text = stdout(&shown);
            assert!(
                text.starts_with("DAMAGED "),
                "{what}, show {target}: {text}{}",
                stderr(&shown)
            );
            assert!(!shown.status.success(), "{what}: show exited 0");
            assert!(
                !stderr(&shown).contains("Corrupt footer"),
                "{}",
                stderr(&shown)
            );
        }
    }
}

/// `rate --mass-amu 1e-300` printed "rho^2 l v_th = inf", "Gamma =
/// undefined" and "1/Gamma = 0 s" with exit 0; `--temperature 1e308`
/// printed a 310-digit theta; `--temperature -10` said "unexpected argument
/// '-1'" (issue 54, item 11 and messages). Each is refused, with a reason
/// and short numbers, before any store is read.
#[test]
fn rate_refuses_inputs_whose_numbers_are_not_finite() {
    let dir = workspace("rate-inputs");
    let config = write_config(&dir, &small_study("data"));
    let gas = ["--density-per-um", "0.1"];
    let cases: [(&[&str], &str); 4] = [
        (
            &[
                "--eps-k",
                "10",
                "--sigma-angstrom",
                "3",
                "--mass-amu",
                "1e-300",
                "--temperature",
                "100",
            ],
            "rho^2 l v_th is inf",
        ),
        (
            &["--species", "N2", "--temperature", "1e308"],
            "theta = kT/eps = 1.0520778537611783e306",
        ),
        (
            &["--species", "N2", "--temperature", "-10"],
            "-10 must be a finite number > 0",
        ),
        (
            &["--species", "N2", "--temperature", "nan"],
            "must be a finite number > 0",
        ),
    ];
    for (args, reason) in cases {
        let output = ternary(&config, &[&["rate"], args, &gas].concat());
        let message = stderr(&output);
        assert!(
            !output.status.success(),
            "{args:?} succeeded: {}",
            stdout(&output)
        );
        assert!(message.contains(reason), "{args:?}: {message}");
        assert!(message.len() < 400, "{args:?}: a long message: {message}");
    }
}

/// `bench balance --separation 0.5 --randomizations 2` printed NaN ratios
/// with exit 0 after 90 s (issue 54, item 11): no scene joins bins that far
/// apart in so few randomizations. It now stops at the first such scene
/// set, naming it and the options to change.
#[test]
fn a_balance_bench_without_a_finite_ratio_fails() {
    let output = Command::new(BINARY)
        .args([
            "bench",
            "balance",
            "--separation",
            "0.5",
            "--randomizations",
            "2",
        ])
        .output()
        .unwrap();
    let message = stderr(&output);
    assert!(!output.status.success(), "{}", stdout(&output));
    assert!(!stdout(&output).contains("NaN"), "{}", stdout(&output));
    assert!(
        message.contains("--separation") && message.contains("NaN"),
        "{message}"
    );
}
