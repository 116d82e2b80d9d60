//! docs/tutorial.md followed step by step: its study runs, each change makes
//! stale exactly what the page's `status --changed` blocks say, the bundle
//! exports and verifies, and the Python example (examples/bundle.py) reads it.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::{run_counts, stderr, stdout, ternary, workspace};

/// A file of the repository.
fn repository(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// The outputs the tutorial shows after each `$ ternary status ... --changed`:
/// the lines of each block up to the estimate (which depends on the machine's
/// speed), without their indentation.
fn shown_status_blocks() -> Vec<Vec<String>> {
    let tutorial = fs::read_to_string(repository("docs/tutorial.md")).unwrap();
    let mut blocks = Vec::new();
    let mut lines = tutorial.lines();
    while let Some(line) = lines.next() {
        if line.trim_start().starts_with("$ ternary status") {
            let block = lines
                .by_ref()
                .take_while(|l| l.starts_with("    ") && !l.trim_start().starts_with('$'))
                .map(|l| l.trim().to_string())
                .collect();
            blocks.push(block);
        }
    }
    blocks
}

/// `status --changed` as the tutorial shows it: without the estimate line.
fn changed(config: &Path) -> Vec<String> {
    let output = ternary(config, &["status", "--changed"]);
    stdout(&output)
        .lines()
        .filter(|line| !line.starts_with("estimate:"))
        .map(|line| line.trim().to_string())
        .collect()
}

/// Appends `text` to the study, or replaces `from` by `to` in it.
fn edit(config: &Path, from: &str, to: &str) {
    let text = fs::read_to_string(config).unwrap();
    let edited = if from.is_empty() {
        format!("{text}\n{to}\n")
    } else {
        assert!(text.contains(from), "the study has no {from:?}");
        text.replacen(from, to, 1)
    };
    fs::write(config, edited).unwrap();
}

#[test]
fn the_tutorial_runs_as_written() {
    let dir = workspace("tutorial");
    let config = dir.join("my-study.toml");
    fs::copy(repository("docs/studies/tutorial.toml"), &config).unwrap();
    let shown = shown_status_blocks();
    assert_eq!(shown.len(), 2, "the tutorial shows two status blocks");

    // 1. A first study, then nothing to do.
    assert_eq!(run_counts(&config, &[]), (18, 0));
    assert_eq!(run_counts(&config, &[]), (0, 18));

    // 2. One parameter changed: exactly what the page says reruns.
    edit(&config, "", "[kernel]\nfit_range = [2e-4, 0.04]");
    assert_eq!(changed(&config), shown[0]);
    assert_eq!(run_counts(&config, &[]), (5, 13));

    // 3. A potential added.
    edit(
        &config,
        "inverse_power = [6, 8]",
        "inverse_power = [6, 8, 10]",
    );
    assert_eq!(changed(&config), shown[1]);
    assert_eq!(run_counts(&config, &[]), (9, 15));

    // 4. Export and verify the bundle.
    let bundle = dir.join("my-bundle");
    let export = ternary(&config, &["export", bundle.to_str().unwrap()]);
    assert!(export.status.success(), "{}", stderr(&export));
    assert!(
        stdout(&export).starts_with("export: 42 tables, 16 figure files"),
        "{}",
        stdout(&export)
    );
    let verify = ternary(&config, &["verify", "--bundle", bundle.to_str().unwrap()]);
    assert!(verify.status.success(), "{}", stdout(&verify));

    // 5. The Python example reads it, and its checks pass.
    let example = Command::new("python3")
        .arg(repository("examples/bundle.py"))
        .arg(&bundle)
        .args(["--out", "kernels.png"])
        .current_dir(&dir)
        .output()
        .unwrap();
    let printed = stdout(&example);
    assert!(
        example.status.success(),
        "examples/bundle.py failed (install the README's test packages):\n{printed}\n{}",
        stderr(&example)
    );
    assert_eq!(printed.matches(" agrees").count(), 7, "{printed}");
    assert!(fs::metadata(dir.join("kernels.png")).unwrap().len() > 10_000);
    let _ = fs::remove_dir_all(&dir);
}
