//! `[slurm]`: what `ternary slurm submit` asks of the scheduler (shards,
//! resources, placement, extra `sbatch` options); each key can be overridden
//! on its command line. Not a stage parameter: it changes no artifact key.
//!
//! Every value here is written into a `#SBATCH` line, so each must be in
//! Slurm's own syntax: a newline would end the directive and turn the rest
//! into a shell command of the job script.

use serde::{Deserialize, Serialize};

use super::check::{Invalid, check};

/// Most shards of one instance (array task indices stay below it).
const MAX_SLURM_SHARDS: u32 = 4096;

/// Most CPUs one task asks for (the largest nodes have a few hundred cores).
const MAX_CPUS_PER_TASK: u32 = 1024;

/// `[slurm]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SlurmConfig {
    /// Shards per shardable instance: the array's tasks.
    pub shards: u32,
    /// `--cpus-per-task` of every job, also its runs' `--threads`.
    pub cpus_per_task: Option<u32>,
    /// `--mem` of every job (`4000`, `500M`, `16G`; megabytes without a unit).
    pub mem: Option<String>,
    /// `--account` of every job.
    pub account: Option<String>,
    /// `--partition` of every job (a comma-separated list lets Slurm choose).
    pub partition: Option<String>,
    /// `--qos` of every job.
    pub qos: Option<String>,
    /// `--time` of each shard task (Slurm's formats, e.g. `2:00:00`).
    pub time: Option<String>,
    /// `--time` of the merge job; `time` when not given.
    pub merge_time: Option<String>,
    /// Most array tasks running at once (`--array=...%K`).
    pub max_parallel: Option<u32>,
    /// Further `sbatch` options, one `#SBATCH` line each (`--exclusive`,
    /// `--constraint=avx2`).
    pub sbatch_args: Vec<String>,
}

impl Default for SlurmConfig {
    /// 8 shards: a few nodes' worth of tasks for the default study's
    /// collisions, each still minutes long; nothing else asked (the
    /// cluster's defaults apply).
    fn default() -> Self {
        SlurmConfig {
            shards: 8,
            cpus_per_task: None,
            mem: None,
            account: None,
            partition: None,
            qos: None,
            time: None,
            merge_time: None,
            max_parallel: None,
            sbatch_args: Vec::new(),
        }
    }
}

impl SlurmConfig {
    /// The `[slurm]` checks, failing with the `slurm.<key>` path.
    pub(super) fn validate(&self) -> Result<(), Invalid> {
        self.check()
            .map_err(|(key, message)| (format!("slurm.{key}"), message))
    }

    /// Every value is in Slurm's syntax and range; a failure names its key
    /// within the section (`partition`, `sbatch_args[2]`), so the command
    /// line can name its own option instead.
    pub fn check(&self) -> Result<(), Invalid> {
        check(
            (2..=MAX_SLURM_SHARDS).contains(&self.shards),
            "shards",
            format!("{} is outside [2, {MAX_SLURM_SHARDS}]", self.shards),
        )?;
        if let Some(cpus) = self.cpus_per_task {
            check(
                (1..=MAX_CPUS_PER_TASK).contains(&cpus),
                "cpus_per_task",
                format!("{cpus} is outside [1, {MAX_CPUS_PER_TASK}]"),
            )?;
        }
        if let Some(k) = self.max_parallel {
            check(
                k >= 1,
                "max_parallel",
                "0 tasks at once: must be at least 1",
            )?;
        }
        let texts = [
            ("mem", &self.mem, is_memory as fn(&str) -> bool, MEMORY),
            ("account", &self.account, is_name, NAME),
            ("partition", &self.partition, is_name_list, NAME_LIST),
            ("qos", &self.qos, is_name, NAME),
            ("time", &self.time, is_time_limit, TIME_LIMIT),
            ("merge_time", &self.merge_time, is_time_limit, TIME_LIMIT),
        ];
        for (key, value, valid, syntax) in texts {
            if let Some(value) = value {
                check(valid(value), key, format!("{value:?} is not {syntax}"))?;
            }
        }
        for (k, arg) in self.sbatch_args.iter().enumerate() {
            let key = format!("sbatch_args[{k}]");
            check(
                is_sbatch_option(arg),
                key.as_str(),
                format!("{arg:?} is not {SBATCH_OPTION}"),
            )?;
            if let Some((option, instead)) = reserved_option(arg) {
                return Err((
                    key,
                    format!("{arg:?}: ternary writes `--{option}` itself; {instead}"),
                ));
            }
        }
        Ok(())
    }
}

const MEMORY: &str = "a Slurm memory size (an integer, megabytes, or with a unit: `500M`, `16G`)";
const NAME: &str = "a Slurm name (letters, digits, `_`, `-`, `.`)";
const NAME_LIST: &str =
    "a Slurm partition name (letters, digits, `_`, `-`, `.`; several separated by commas)";
const TIME_LIMIT: &str =
    "a Slurm time limit (`M`, `M:S`, `H:M:S`, `D-H`, `D-H:M`, `D-H:M:S` or `UNLIMITED`)";
const SBATCH_OPTION: &str = "an sbatch long option (`--name` or `--name=value`; value of letters, digits and `_-.,:/%@+=`, no spaces, quotes or shell characters)";

/// Letters, digits, `_`, `-` and `.`, at least one.
fn is_name(text: &str) -> bool {
    !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

/// `name[,name...]`, each an [`is_name`].
fn is_name_list(text: &str) -> bool {
    text.split(',').all(is_name)
}

/// Slurm's memory sizes: an integer (megabytes), optionally with a unit
/// `K`, `M`, `G` or `T` (either case).
fn is_memory(text: &str) -> bool {
    let digits = text.trim_end_matches(['K', 'M', 'G', 'T', 'k', 'm', 'g', 't']);
    text.len() - digits.len() <= 1
        && (1..=9).contains(&digits.len())
        && digits.bytes().all(|b| b.is_ascii_digit())
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

/// The options the scripts write themselves, each with what to use
/// instead: an extra argument repeating one would override the job's
/// array, log or dependency, or contradict its resources.
const RESERVED_OPTIONS: [(&str, &str); 14] = [
    ("array", "set `shards` and `max_parallel`"),
    ("output", "logs go to the store's slurm/logs/"),
    ("error", "logs go to the store's slurm/logs/"),
    (
        "job-name",
        "the jobs are named ternary-shards and ternary-merge",
    ),
    ("dependency", "the merge job depends on the shards' jobs"),
    (
        "kill-on-invalid-dep",
        "the merge job is cancelled when a shard fails",
    ),
    ("parsable", "submission reads the job ids itself"),
    ("wrap", "the jobs run the scripts ternary writes"),
    ("cpus-per-task", "set `cpus_per_task`"),
    ("mem", "set `mem`"),
    ("account", "set `account`"),
    ("partition", "set `partition`"),
    ("qos", "set `qos`"),
    ("time", "set `time` and `merge_time`"),
];

/// The reserved option `arg` names and what to use instead, if any.
/// sbatch, like getopt, takes any unambiguous prefix of a long option
/// (`--arr=0-3` is `--array`), so a prefix of a reserved name is one too.
fn reserved_option(arg: &str) -> Option<(&'static str, &'static str)> {
    let option = arg.strip_prefix("--")?;
    let name = option.split_once('=').map_or(option, |(name, _)| name);
    RESERVED_OPTIONS
        .into_iter()
        .find(|(reserved, _)| reserved.starts_with(name))
}

/// `--name` or `--name=value`: a long option whose name is letters, digits
/// and `-`, and whose value holds none of what would end the `#SBATCH`
/// line, split it (whitespace, quotes) or mean something to a shell.
fn is_sbatch_option(text: &str) -> bool {
    let Some(option) = text.strip_prefix("--") else {
        return false;
    };
    let (name, value) = match option.split_once('=') {
        Some((name, value)) => (name, Some(value)),
        None => (option, None),
    };
    let name_ok = name.starts_with(|c: char| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-');
    let value_ok = value.is_none_or(|value| {
        !value.is_empty()
            && value.chars().all(|c| {
                c.is_ascii_alphanumeric()
                    || matches!(c, '_' | '-' | '.' | ',' | ':' | '/' | '%' | '@' | '+' | '=')
            })
    });
    name_ok && value_ok
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
            assert!(is_name_list(good), "{good}");
        }
        for bad in ["", ",", "a,", "a b", "a\nb", "a;b", "$(x)"] {
            assert!(!is_name_list(bad), "{bad:?}");
        }
    }

    #[test]
    fn memory_sizes_are_an_integer_with_at_most_one_unit() {
        for good in ["4000", "0", "500M", "16G", "1T", "64k"] {
            assert!(is_memory(good), "{good}");
        }
        for bad in ["", "G", "16GB", "1.5G", "16 G", "-1", "16G\n", "1234567890"] {
            assert!(!is_memory(bad), "{bad:?}");
        }
    }

    /// An extra option cannot end its `#SBATCH` line, add a second option
    /// to it, or carry shell syntax.
    #[test]
    fn sbatch_options_are_single_long_options_without_shell_syntax() {
        for good in [
            "--exclusive",
            "--constraint=avx2",
            "--gres=gpu:1",
            "--mail-user=a.b@example.org",
            "--mail-type=END,FAIL",
            "--nodelist=node01,node02",
        ] {
            assert!(is_sbatch_option(good), "{good}");
        }
        for bad in [
            "",
            "exclusive",
            "-x",
            "--",
            "--=1",
            "--constraint=",
            "--exclusive\necho injected",
            "--constraint=a b",
            "--comment='x'",
            "--comment=\"x\"",
            "--comment=$(id)",
            "--comment=`id`",
            "--comment=a;b",
            "--comment=a|b",
            "--comment=a&b",
            "--comment=a>b",
            "--bad name",
        ] {
            assert!(!is_sbatch_option(bad), "{bad:?}");
        }
    }

    #[test]
    fn a_failed_check_names_the_key_within_the_section() {
        let mut slurm = SlurmConfig {
            sbatch_args: vec!["--exclusive".into(), "rm -rf".into()],
            ..SlurmConfig::default()
        };
        assert_eq!(slurm.check().unwrap_err().0, "sbatch_args[1]");
        slurm.sbatch_args.clear();
        slurm.mem = Some("lots".into());
        assert_eq!(slurm.check().unwrap_err().0, "mem");
        slurm.mem = None;
        slurm.shards = 1;
        assert_eq!(slurm.check().unwrap_err().0, "shards");
    }
}
