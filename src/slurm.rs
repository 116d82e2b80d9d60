//! `ternary slurm submit`: the shardable stages of a study as a Slurm array
//! job (one task per missing shard index), and a dependent job that merges
//! the shards and runs the rest of the DAG.
//!
//! Scripts and logs live in the store, under `slurm/`:
//!
//! ```text
//! slurm/shards.sbatch                 the array job (task k: `run --shards N --shard k`)
//! slurm/merge.sbatch                  the dependent job (`run --shards N`)
//! slurm/logs/shard-<job>_<task>.out   one log per task (progress lines per instance)
//! slurm/logs/merge-<job>.out          the merge job's log
//! ```
//!
//! Resubmitting after a failed or cancelled task submits only the shard
//! indices still missing; a shard is an artifact committed atomically, so a
//! task that did not finish leaves nothing the merge uses. The merge job is
//! submitted with `--kill-on-invalid-dep=yes`: if a task fails, it is
//! cancelled rather than left pending.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::fs;
use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, bail};

use crate::pipeline::Stage;
use crate::pipeline::executor;
use crate::pipeline::store::Store;

/// What `ternary slurm submit` asks of the scheduler.
#[derive(Clone, Debug)]
pub struct SubmitOptions {
    /// Shards per shardable instance.
    pub shards: u32,
    /// `--partition`.
    pub partition: Option<String>,
    /// `--time` of each job (Slurm's formats, e.g. `2:00:00`).
    pub time: Option<String>,
    /// Most array tasks running at once (`%K`).
    pub max_parallel: Option<u32>,
    /// Print the scripts and commands instead of submitting.
    pub dry_run: bool,
    /// The study was allowed beyond `[limits]`: its jobs' runs are too.
    pub i_know: bool,
}

impl SubmitOptions {
    /// Refuses a value that is not in Slurm's own syntax: whatever goes into
    /// a `#SBATCH` line must not end it (a newline would turn the rest into
    /// a shell command) or change its meaning.
    pub fn check(&self) -> Result<()> {
        if let Some(partition) = &self.partition
            && !is_partition_list(partition)
        {
            bail!(
                "--partition {partition:?}: not a Slurm partition name (letters, digits, `_`, `-`, `.`; several separated by commas)"
            );
        }
        if let Some(time) = &self.time
            && !is_time_limit(time)
        {
            bail!(
                "--time {time:?}: not a Slurm time limit (`M`, `M:S`, `H:M:S`, `D-H`, `D-H:M`, `D-H:M:S` or `UNLIMITED`)"
            );
        }
        Ok(())
    }
}

/// `name[,name...]`, each of letters, digits, `_`, `-` and `.`.
fn is_partition_list(text: &str) -> bool {
    text.split(',').all(|name| {
        !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
    })
}

/// Slurm's time formats: `M`, `M:S`, `H:M:S`, `D-H`, `D-H:M`, `D-H:M:S`,
/// `UNLIMITED` or `infinite`.
fn is_time_limit(text: &str) -> bool {
    if text.eq_ignore_ascii_case("unlimited") || text.eq_ignore_ascii_case("infinite") {
        return true;
    }
    let digits = |part: &str| {
        !part.is_empty() && part.len() <= 9 && part.bytes().all(|b| b.is_ascii_digit())
    };
    let (days, clock) = match text.split_once('-') {
        Some((days, clock)) => (Some(days), clock),
        None => (None, text),
    };
    let fields: Vec<&str> = clock.split(':').collect();
    let counted = match days {
        Some(days) => digits(days) && (1..=3).contains(&fields.len()),
        None => (1..=3).contains(&fields.len()),
    };
    counted && fields.iter().all(|f| digits(f))
}

/// A path that goes into a `#SBATCH` line as is: no control characters,
/// whitespace or quotes, which would end or split the directive.
fn directive_path(path: &Path) -> Result<String> {
    let text = path.display().to_string();
    if text
        .chars()
        .any(|c| c.is_control() || c.is_whitespace() || matches!(c, '"' | '\''))
    {
        bail!(
            "{text:?}: Slurm's #SBATCH --output cannot take a path with whitespace, quotes or control characters; use a store path without them"
        );
    }
    Ok(text)
}

/// The shard indices with at least one shard still to compute.
pub fn missing_shards(
    store: &Store,
    plan: &[Box<dyn Stage>],
    shards: u32,
) -> Result<BTreeSet<u32>> {
    Ok(executor::status(store, plan, shards)?
        .into_iter()
        .filter_map(|line| line.shards)
        .flat_map(|progress| progress.missing)
        .collect())
}

/// A `#SBATCH` header: job name, log file and the chosen resources (all
/// checked: [`SubmitOptions::check`], [`directive_path`]).
fn header(name: &str, output: &str, options: &SubmitOptions) -> String {
    let mut out = format!("#!/bin/bash\n#SBATCH --job-name={name}\n#SBATCH --output={output}\n");
    if let Some(partition) = &options.partition {
        let _ = writeln!(out, "#SBATCH --partition={partition}");
    }
    if let Some(time) = &options.time {
        let _ = writeln!(out, "#SBATCH --time={time}");
    }
    out
}

/// A shell word in single quotes.
fn quoted(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', r"'\''"))
}

/// The array script over shard indices `tasks` and the merge script.
fn scripts(
    binary: &Path,
    config: &Path,
    logs: &Path,
    tasks: &BTreeSet<u32>,
    options: &SubmitOptions,
) -> Result<(String, String)> {
    let allowed = if options.i_know { " --i-know" } else { "" };
    let command = format!("{} --config {}", quoted(binary), quoted(config));
    let list: Vec<String> = tasks.iter().map(ToString::to_string).collect();
    let throttle = options
        .max_parallel
        .map_or(String::new(), |k| format!("%{k}"));
    let array_log = directive_path(&logs.join("shard-%A_%a.out"))?;
    let merge_log = directive_path(&logs.join("merge-%j.out"))?;
    let mut array = header("ternary-shards", &array_log, options);
    let _ = writeln!(array, "#SBATCH --array={}{throttle}", list.join(","));
    let _ = writeln!(
        array,
        "set -euo pipefail\nexec {command} run{allowed} --shards {} --shard \"$SLURM_ARRAY_TASK_ID\"",
        options.shards
    );
    let mut merge = header("ternary-merge", &merge_log, options);
    let _ = writeln!(
        merge,
        "set -euo pipefail\nexec {command} run{allowed} --shards {}",
        options.shards
    );
    Ok((array, merge))
}

/// `sbatch --parsable [args] script`: the job id.
fn sbatch(args: &[String], script: &Path) -> Result<String> {
    let output = Command::new("sbatch")
        .arg("--parsable")
        .args(args)
        .arg(script)
        .output()
        .context("running sbatch (is Slurm installed and SLURM_CONF set?)")?;
    if !output.status.success() {
        bail!(
            "sbatch {}: {}",
            script.display(),
            String::from_utf8_lossy(&output.stderr).trim()
        );
    }
    let text = String::from_utf8_lossy(&output.stdout);
    let id = text
        .trim()
        .split(';')
        .next()
        .unwrap_or_default()
        .to_string();
    if id.is_empty() {
        bail!("sbatch printed no job id");
    }
    Ok(id)
}

/// Writes the scripts and submits the array job over the missing shard
/// indices and the dependent merge job (or prints them with `dry_run`).
pub fn submit(
    config: &Path,
    store: &Store,
    plan: &[Box<dyn Stage>],
    options: &SubmitOptions,
) -> Result<String> {
    options.check()?;
    let tasks = missing_shards(store, plan, options.shards)?;
    let binary = std::env::current_exe().context("locating the ternary binary")?;
    let config =
        fs::canonicalize(config).with_context(|| format!("resolving {}", config.display()))?;
    let dir = fs::canonicalize(store.root())?.join("slurm");
    let logs = dir.join("logs");
    let (array, merge) = scripts(&binary, &config, &logs, &tasks, options)?;
    let (array_path, merge_path) = (dir.join("shards.sbatch"), dir.join("merge.sbatch"));
    let mut out = String::new();
    if options.dry_run {
        if !tasks.is_empty() {
            let _ = writeln!(out, "# {}\n{array}", array_path.display());
        }
        let _ = writeln!(out, "# {}\n{merge}", merge_path.display());
        let _ = writeln!(
            out,
            "# submit: sbatch --parsable {}; sbatch --parsable --dependency=afterok:<array job> --kill-on-invalid-dep=yes {}",
            array_path.display(),
            merge_path.display()
        );
        return Ok(out);
    }
    fs::create_dir_all(&logs)?;
    fs::write(&array_path, &array)?;
    fs::write(&merge_path, &merge)?;
    let mut merge_args = Vec::new();
    if !tasks.is_empty() {
        let array_id = sbatch(&[], &array_path)?;
        let _ = writeln!(
            out,
            "submitted shards job {array_id}: tasks {:?} of {} (logs {}/shard-{array_id}_<task>.out)",
            tasks,
            options.shards,
            logs.display()
        );
        merge_args = vec![
            format!("--dependency=afterok:{array_id}"),
            "--kill-on-invalid-dep=yes".to_string(),
        ];
    }
    let merge_id = sbatch(&merge_args, &merge_path)?;
    let _ = writeln!(
        out,
        "submitted merge job {merge_id} (log {}/merge-{merge_id}.out)",
        logs.display()
    );
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_limits_follow_slurms_formats() {
        for good in [
            "30",
            "30:00",
            "2:00:00",
            "1-0",
            "1-12:30",
            "1-12:30:00",
            "UNLIMITED",
            "infinite",
        ] {
            assert!(is_time_limit(good), "{good}");
        }
        for bad in [
            "",
            ":",
            "1:",
            "1:2:3:4",
            "1-",
            "-1",
            "1-2-3",
            "1-1:2:3:4",
            "1h",
            " 1",
            "1\n",
        ] {
            assert!(!is_time_limit(bad), "{bad:?}");
        }
    }

    #[test]
    fn partition_lists_are_names_separated_by_commas() {
        for good in ["debug", "a,b", "long.q", "gpu_a-1"] {
            assert!(is_partition_list(good), "{good}");
        }
        for bad in ["", ",", "a,", "a b", "a\nb", "a;b", "$(x)"] {
            assert!(!is_partition_list(bad), "{bad:?}");
        }
    }
}
