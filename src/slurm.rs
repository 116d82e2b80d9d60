//! `ternary slurm submit`: the shardable stages of a study as a Slurm array
//! job (one task per missing shard index), and a dependent job that merges
//! the shards and runs the rest of the DAG.
//!
//! Scripts and logs live in the store, under `slurm/`:
//!
//! ```text
//! slurm/shards.sbatch                 the array job (task k: `run --shards N --shard k`)
//! slurm/shards-from-<K>.sbatch        further array jobs, task k running shard K + k
//! slurm/merge.sbatch                  the dependent job (`run --shards N`)
//! slurm/logs/shard-<job>_<task>.out   one log per task (progress lines per instance)
//! slurm/logs/merge-<job>.out          the merge job's log
//! ```
//!
//! Shards, resources (`--cpus-per-task`, which the runs also take as
//! `--threads`, `--mem`), placement (`--account`, `--partition`, `--qos`),
//! time limits (the merge job's its own) and extra options come from
//! `[slurm]` ([`SlurmConfig`]) with the command line's overrides.
//!
//! Slurm refuses array indices at or above the cluster's `MaxArraySize`
//! (1001 by default), so shard indices beyond it go to further array jobs
//! whose tasks add an offset; the merge job waits for all of them, and
//! `max_parallel` throttles each array job on its own.
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

use anyhow::{Context, Result, anyhow, bail};

use crate::config::SlurmConfig;
use crate::pipeline::Stage;
use crate::pipeline::executor::{self, Freshness, StatusLine};
use crate::pipeline::store::Store;

/// What `ternary slurm submit` asks of the scheduler.
#[derive(Clone, Debug)]
pub struct SubmitOptions {
    /// Shards, resources and placement: `[slurm]` with the command line's
    /// overrides.
    pub slurm: SlurmConfig,
    /// Print the scripts and commands instead of submitting, changing
    /// nothing on the filesystem.
    pub dry_run: bool,
    /// The study was allowed beyond `[limits]`: its jobs' runs are too.
    pub i_know: bool,
}

impl SubmitOptions {
    /// Refuses a value that is not in Slurm's own syntax ([`SlurmConfig::check`]),
    /// naming the command-line option: `[slurm]` was checked when the study
    /// loaded, so a value failing here came from the command line.
    pub fn check(&self) -> Result<()> {
        self.slurm.check().map_err(|(key, message)| {
            let option = match key.split_once('[') {
                Some(("sbatch_args", _)) => "sbatch-arg".to_string(),
                _ => key.replace('_', "-"),
            };
            anyhow!("--{option}: {message}")
        })
    }
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

/// The shard indices with at least one shard still to compute, from a
/// sharded status.
fn missing_shards(lines: &[StatusLine]) -> BTreeSet<u32> {
    lines
        .iter()
        .filter_map(|line| line.shards.as_ref())
        .flat_map(|progress| progress.missing.iter().copied())
        .collect()
}

/// Slurm's `--array` index list: runs of consecutive indices as ranges
/// (`0-31`, `0-3,7,9-12`), so the directive stays short for any shard count.
fn array_indices(tasks: &BTreeSet<u32>) -> String {
    let mut runs: Vec<(u32, u32)> = Vec::new();
    for &task in tasks {
        match runs.last_mut() {
            Some((_, last)) if *last + 1 == task => *last = task,
            _ => runs.push((task, task)),
        }
    }
    let ranges: Vec<String> = runs
        .iter()
        .map(|&(first, last)| {
            if first == last {
                first.to_string()
            } else {
                format!("{first}-{last}")
            }
        })
        .collect();
    ranges.join(",")
}

/// A `#SBATCH` header: job name, log file, time limit and the resources
/// and extra options every job shares (all checked: [`SubmitOptions::check`],
/// [`directive_path`]).
fn header(name: &str, output: &str, time: Option<&str>, slurm: &SlurmConfig) -> String {
    let mut out = format!("#!/bin/bash\n#SBATCH --job-name={name}\n#SBATCH --output={output}\n");
    let directives = [
        ("account", slurm.account.as_deref()),
        ("partition", slurm.partition.as_deref()),
        ("qos", slurm.qos.as_deref()),
        ("time", time),
        ("mem", slurm.mem.as_deref()),
    ];
    for (option, value) in directives {
        if let Some(value) = value {
            let _ = writeln!(out, "#SBATCH --{option}={value}");
        }
    }
    if let Some(cpus) = slurm.cpus_per_task {
        let _ = writeln!(out, "#SBATCH --cpus-per-task={cpus}");
    }
    for arg in &slurm.sbatch_args {
        let _ = writeln!(out, "#SBATCH {arg}");
    }
    out
}

/// A shell word in single quotes.
fn quoted(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', r"'\''"))
}

/// Slurm's default `MaxArraySize`: array indices stay below it.
const DEFAULT_MAX_ARRAY_SIZE: u32 = 1001;

/// The cluster's `MaxArraySize` from `scontrol show config`, or Slurm's
/// default when `scontrol` is absent or does not say (a dry run off the
/// cluster).
fn max_array_size() -> u32 {
    let Ok(output) = Command::new("scontrol").args(["show", "config"]).output() else {
        return DEFAULT_MAX_ARRAY_SIZE;
    };
    String::from_utf8_lossy(&output.stdout)
        .lines()
        .find_map(|line| {
            let (key, value) = line.split_once('=')?;
            (key.trim() == "MaxArraySize").then(|| value.trim().parse().ok())?
        })
        .filter(|&size| size >= 1)
        .unwrap_or(DEFAULT_MAX_ARRAY_SIZE)
}

/// One array job: its task `k` computes shard `offset + k`.
struct ArrayJob {
    /// Added to `$SLURM_ARRAY_TASK_ID` to give the shard index.
    offset: u32,
    /// The task indices (shard indices less `offset`).
    tasks: BTreeSet<u32>,
    /// The `sbatch` script.
    script: String,
}

impl ArrayJob {
    /// The script's file name: `shards.sbatch`, or `shards-from-K.sbatch`
    /// for the array job starting at shard K.
    fn file_name(&self) -> String {
        match self.offset {
            0 => "shards.sbatch".to_string(),
            offset => format!("shards-from-{offset}.sbatch"),
        }
    }

    /// The shard indices its tasks compute, as an `--array` list.
    fn shards(&self) -> String {
        array_indices(&self.tasks.iter().map(|&k| k + self.offset).collect())
    }
}

/// The missing shard `tasks` split into array jobs whose indices stay
/// below `max_array_size`: shards `[j M, (j + 1) M)` go to the job with
/// offset `j M`.
fn array_chunks(tasks: &BTreeSet<u32>, max_array_size: u32) -> Vec<(u32, BTreeSet<u32>)> {
    let mut chunks: Vec<(u32, BTreeSet<u32>)> = Vec::new();
    for &shard in tasks {
        let offset = shard - shard % max_array_size;
        match chunks.last_mut() {
            Some((last, chunk)) if *last == offset => {
                chunk.insert(shard - offset);
            }
            _ => chunks.push((offset, BTreeSet::from([shard - offset]))),
        }
    }
    chunks
}

/// The scripts of one submission: the array jobs (none without missing
/// shards) and the merge job.
struct Scripts {
    arrays: Vec<ArrayJob>,
    merge: String,
}

/// The array scripts over shard indices `tasks` (indices below
/// `max_array_size`) and the merge script. Both runs use the CPUs they ask
/// for (`--threads` = `--cpus-per-task`).
fn scripts(
    binary: &Path,
    config: &Path,
    logs: &Path,
    tasks: &BTreeSet<u32>,
    max_array_size: u32,
    options: &SubmitOptions,
) -> Result<Scripts> {
    let slurm = &options.slurm;
    let allowed = if options.i_know { " --i-know" } else { "" };
    let threads = slurm
        .cpus_per_task
        .map_or(String::new(), |n| format!(" --threads {n}"));
    let run = format!(
        "set -euo pipefail\nexec {} --config {} run{allowed}{threads} --shards {}",
        quoted(binary),
        quoted(config),
        slurm.shards
    );
    let array_log = directive_path(&logs.join("shard-%A_%a.out"))?;
    let merge_log = directive_path(&logs.join("merge-%j.out"))?;
    let throttle = slurm
        .max_parallel
        .map_or(String::new(), |k| format!("%{k}"));
    let arrays = array_chunks(tasks, max_array_size)
        .into_iter()
        .map(|(offset, tasks)| {
            let shard = match offset {
                0 => "\"$SLURM_ARRAY_TASK_ID\"".to_string(),
                offset => format!("\"$((SLURM_ARRAY_TASK_ID + {offset}))\""),
            };
            let mut script = header("ternary-shards", &array_log, slurm.time.as_deref(), slurm);
            let _ = writeln!(
                script,
                "#SBATCH --array={}{throttle}",
                array_indices(&tasks)
            );
            let _ = writeln!(script, "{run} --shard {shard}");
            ArrayJob {
                offset,
                tasks,
                script,
            }
        })
        .collect();
    let merge_time = slurm.merge_time.as_deref().or(slurm.time.as_deref());
    let mut merge = header("ternary-merge", &merge_log, merge_time, slurm);
    let _ = writeln!(merge, "{run}");
    Ok(Scripts { arrays, merge })
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
/// indices and the dependent merge job, or with `dry_run` prints them and
/// the commands, creating nothing (not even the store). A study with every
/// instance fresh submits nothing; one with no shard missing submits the
/// merge job alone.
pub fn submit(
    config: &Path,
    store: &Store,
    plan: &[Box<dyn Stage>],
    options: &SubmitOptions,
) -> Result<String> {
    options.check()?;
    let shards = options.slurm.shards;
    let lines = executor::status(store, plan, shards)?;
    // Not canonicalized: in a dry run the store may not exist yet.
    let root = std::path::absolute(store.root())
        .with_context(|| format!("resolving {}", store.root().display()))?;
    if lines.iter().all(|line| line.freshness == Freshness::Fresh) {
        return Ok(format!(
            "nothing to submit: every stage instance is fresh (store {})\n",
            root.display()
        ));
    }
    let tasks = missing_shards(&lines);
    let binary = std::env::current_exe().context("locating the ternary binary")?;
    let config =
        fs::canonicalize(config).with_context(|| format!("resolving {}", config.display()))?;
    let dir = root.join("slurm");
    let logs = dir.join("logs");
    let scripts = scripts(&binary, &config, &logs, &tasks, max_array_size(), options)?;
    let merge_path = dir.join("merge.sbatch");
    if options.dry_run {
        return Ok(dry_run_text(&scripts, &dir, &merge_path));
    }
    fs::create_dir_all(&logs)?;
    let mut out = String::new();
    let mut array_ids = Vec::new();
    for array in &scripts.arrays {
        let path = dir.join(array.file_name());
        fs::write(&path, &array.script)?;
        let array_id = sbatch(&[], &path)?;
        let _ = writeln!(
            out,
            "submitted shards job {array_id}: shards {} of {shards} (logs {}/shard-{array_id}_<task>.out)",
            array.shards(),
            logs.display()
        );
        array_ids.push(array_id);
    }
    let merge_args = if array_ids.is_empty() {
        let _ = writeln!(out, "no shards to compute: submitting the merge job alone");
        Vec::new()
    } else {
        vec![
            format!("--dependency=afterok:{}", array_ids.join(":")),
            "--kill-on-invalid-dep=yes".to_string(),
        ]
    };
    fs::write(&merge_path, &scripts.merge)?;
    let merge_id = sbatch(&merge_args, &merge_path)?;
    let _ = writeln!(
        out,
        "submitted merge job {merge_id} (log {}/merge-{merge_id}.out)",
        logs.display()
    );
    Ok(out)
}

/// What a dry run prints: each script under the path it would be written
/// to (in `dir`), then the `sbatch` commands that would submit them.
fn dry_run_text(scripts: &Scripts, dir: &Path, merge_path: &Path) -> String {
    let mut out = String::new();
    let mut commands = Vec::new();
    for array in &scripts.arrays {
        let path = dir.join(array.file_name());
        let _ = writeln!(out, "# {}\n{}", path.display(), array.script);
        commands.push(format!("sbatch --parsable {}", path.display()));
    }
    if scripts.arrays.is_empty() {
        let _ = writeln!(
            out,
            "# no shards to compute: the merge job alone would run\n"
        );
        commands.push(format!("sbatch --parsable {}", merge_path.display()));
    } else {
        commands.push(format!(
            "sbatch --parsable --dependency=afterok:<each shards job, joined by :> --kill-on-invalid-dep=yes {}",
            merge_path.display()
        ));
    }
    let _ = writeln!(out, "# {}\n{}", merge_path.display(), scripts.merge);
    let _ = writeln!(out, "# submit: {}", commands.join("; "));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_indices_compact_runs_into_ranges() {
        let indices = |tasks: &[u32]| array_indices(&tasks.iter().copied().collect());
        assert_eq!(indices(&(0..32).collect::<Vec<_>>()), "0-31");
        assert_eq!(indices(&[0, 1, 2, 3, 7, 9, 10, 11, 12]), "0-3,7,9-12");
        assert_eq!(indices(&[5]), "5");
        assert_eq!(indices(&[3, 4]), "3-4");
        assert_eq!(indices(&[0, 2, 4]), "0,2,4");
    }

    /// The scripts of a submission with `slurm` over `tasks`.
    fn scripts_of(slurm: SlurmConfig, tasks: &[u32]) -> Scripts {
        let options = SubmitOptions {
            slurm,
            dry_run: true,
            i_know: false,
        };
        let tasks = tasks.iter().copied().collect();
        scripts(
            Path::new("/opt/ternary"),
            Path::new("/study/pipeline.toml"),
            Path::new("/study/data/slurm/logs"),
            &tasks,
            DEFAULT_MAX_ARRAY_SIZE,
            &options,
        )
        .unwrap()
    }

    /// Every resource goes into both scripts, the CPUs also into the runs'
    /// `--threads`; the merge job has its own time limit.
    #[test]
    fn scripts_ask_for_the_resources_and_runs_use_the_cpus() {
        let slurm = SlurmConfig {
            shards: 16,
            cpus_per_task: Some(4),
            mem: Some("8G".into()),
            account: Some("physics".into()),
            partition: Some("normal,long".into()),
            qos: Some("high".into()),
            time: Some("30:00".into()),
            merge_time: Some("4:00:00".into()),
            max_parallel: Some(8),
            sbatch_args: vec!["--exclusive".into(), "--constraint=avx2".into()],
        };
        let scripts = scripts_of(slurm, &[0, 1, 2, 3, 7, 9, 10, 11, 12]);
        let [array] = &scripts.arrays[..] else {
            panic!("one array job expected")
        };
        let array = array.script.as_str();
        let shared =
            "#SBATCH --account=physics\n#SBATCH --partition=normal,long\n#SBATCH --qos=high\n";
        let resources = "#SBATCH --mem=8G\n#SBATCH --cpus-per-task=4\n#SBATCH --exclusive\n#SBATCH --constraint=avx2\n";
        assert_eq!(
            array,
            &format!(
                "#!/bin/bash\n#SBATCH --job-name=ternary-shards\n#SBATCH --output=/study/data/slurm/logs/shard-%A_%a.out\n{shared}#SBATCH --time=30:00\n{resources}#SBATCH --array=0-3,7,9-12%8\nset -euo pipefail\nexec '/opt/ternary' --config '/study/pipeline.toml' run --threads 4 --shards 16 --shard \"$SLURM_ARRAY_TASK_ID\"\n"
            )
        );
        assert_eq!(
            scripts.merge,
            format!(
                "#!/bin/bash\n#SBATCH --job-name=ternary-merge\n#SBATCH --output=/study/data/slurm/logs/merge-%j.out\n{shared}#SBATCH --time=4:00:00\n{resources}set -euo pipefail\nexec '/opt/ternary' --config '/study/pipeline.toml' run --threads 4 --shards 16\n"
            )
        );
    }

    /// Without `merge_time` the merge job takes `time`; without resources
    /// the scripts ask for none (the cluster's defaults) and the runs use
    /// the threads they find; without missing shards there is no array.
    #[test]
    fn scripts_without_resources_ask_for_none() {
        let slurm = SlurmConfig {
            time: Some("1:00:00".into()),
            ..SlurmConfig::default()
        };
        let scripts = scripts_of(slurm.clone(), &[0, 1, 2, 3, 4, 5, 6, 7]);
        let array = &scripts.arrays[0].script;
        assert!(array.contains("#SBATCH --array=0-7\n"), "{array}");
        assert!(array.contains(" run --shards 8 --shard "), "{array}");
        for absent in [
            "--cpus-per-task",
            "--mem",
            "--account",
            "--qos",
            "--partition",
        ] {
            assert!(!array.contains(absent), "{array}");
            assert!(!scripts.merge.contains(absent), "{}", scripts.merge);
        }
        assert!(
            scripts.merge.contains("#SBATCH --time=1:00:00\n"),
            "{}",
            scripts.merge
        );
        assert!(scripts_of(slurm, &[]).arrays.is_empty());
    }

    /// Shards at or beyond the cluster's `MaxArraySize` go to further array
    /// jobs whose tasks add their offset: every missing shard is computed
    /// once, and no array index reaches the limit.
    #[test]
    fn shards_beyond_the_largest_array_index_go_to_offset_jobs() {
        let slurm = SlurmConfig {
            shards: 4096,
            ..SlurmConfig::default()
        };
        let missing: Vec<u32> = (0..4096).filter(|k| k % 7 != 3).collect();
        let scripts = scripts_of(slurm, &missing);
        let offsets: Vec<u32> = scripts.arrays.iter().map(|a| a.offset).collect();
        assert_eq!(offsets, [0, 1001, 2002, 3003, 4004]);
        let mut computed = Vec::new();
        for array in &scripts.arrays {
            assert!(array.tasks.iter().all(|&k| k < DEFAULT_MAX_ARRAY_SIZE));
            computed.extend(array.tasks.iter().map(|&k| k + array.offset));
            let shard = match array.offset {
                0 => "--shard \"$SLURM_ARRAY_TASK_ID\"\n".to_string(),
                offset => format!("--shard \"$((SLURM_ARRAY_TASK_ID + {offset}))\"\n"),
            };
            assert!(array.script.ends_with(&shard), "{}", array.script);
        }
        assert_eq!(computed, missing);
        assert_eq!(scripts.arrays[4].file_name(), "shards-from-4004.sbatch");
        assert_eq!(
            scripts.arrays[4].shards(),
            "4004-4006,4008-4013,4015-4020,4022-4027,4029-4034,4036-4041,4043-4048,4050-4055,4057-4062,4064-4069,4071-4076,4078-4083,4085-4090,4092-4095"
        );
    }

    /// A bad command-line value is refused naming its option.
    #[test]
    fn a_bad_value_names_its_command_line_option() {
        let refused = |slurm: SlurmConfig| {
            let options = SubmitOptions {
                slurm,
                dry_run: true,
                i_know: false,
            };
            options.check().unwrap_err().to_string()
        };
        let message = refused(SlurmConfig {
            merge_time: Some("soon".into()),
            ..SlurmConfig::default()
        });
        assert!(message.starts_with("--merge-time: \"soon\""), "{message}");
        let message = refused(SlurmConfig {
            sbatch_args: vec!["--comment=$(id)".into()],
            ..SlurmConfig::default()
        });
        assert!(message.starts_with("--sbatch-arg: "), "{message}");
        for (arg, instead) in [
            ("--array=0-3", "set `shards` and `max_parallel`"),
            ("--arr=0-3", "set `shards` and `max_parallel`"),
            ("--output=/tmp/x", "logs go to the store's slurm/logs/"),
            ("--cpus-per-task=8", "set `cpus_per_task`"),
            (
                "--dependency=afterok:1",
                "the merge job depends on the shards' jobs",
            ),
        ] {
            let message = refused(SlurmConfig {
                sbatch_args: vec!["--exclusive".into(), arg.into()],
                ..SlurmConfig::default()
            });
            assert!(message.starts_with("--sbatch-arg: "), "{message}");
            assert!(message.ends_with(instead), "{message}");
        }
    }
}
