//! `ternary status`: instances by freshness and why, and the estimated CPU
//! time and store size of what is still to compute.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;

use crate::pipeline::executor::{Freshness, StatusLine};
use crate::pipeline::{Cost, InstanceId};

/// The sum of `costs`.
pub fn total_cost<'a>(costs: impl IntoIterator<Item = &'a Cost>) -> Cost {
    costs.into_iter().fold(Cost::default(), |sum, cost| Cost {
        cpu_seconds: sum.cpu_seconds + cost.cpu_seconds,
        bytes: sum.bytes + cost.bytes,
        rows: sum.rows + cost.rows,
    })
}

/// `status` before its estimate: the count of instances by freshness, then
/// one line per instance (only those not fresh when `changed`) with why, and
/// with `shards > 1` which shards of a shardable one are done.
pub fn status(lines: &[StatusLine], shards: u32, changed: bool) -> String {
    let shown: Vec<&StatusLine> = lines
        .iter()
        .filter(|line| !changed || line.freshness != Freshness::Fresh)
        .collect();
    let width = shown
        .iter()
        .map(|line| line.id.to_string().chars().count())
        .max()
        .unwrap_or(0);
    let mut out = status_summary(lines);
    for line in shown {
        let key = line.key.as_deref().map_or("", |key| &key[..12]);
        let state = match &line.freshness {
            Freshness::Fresh => format!("fresh (key {key})"),
            Freshness::Stale(reasons) => format!("stale: {}", reasons.join("; ")),
            Freshness::Damaged(problems) => format!(
                "damaged (key {key}): {} (the next run recomputes it)",
                problems.join("; ")
            ),
            Freshness::Missing(reason) => format!("missing: {reason}"),
        };
        let progress = line.shards.as_ref().map_or(String::new(), |progress| {
            format!(
                " (shards: {} of {shards} done, missing {:?})",
                progress.done.len(),
                progress.missing
            )
        });
        let _ = writeln!(out, "{:<width$}  {state}{progress}", line.id.to_string());
    }
    out
}

/// The first line of `status`: `N instances: F fresh, S stale, M missing`,
/// and the damaged ones when there are any.
fn status_summary(lines: &[StatusLine]) -> String {
    let count = |name: &str| {
        lines
            .iter()
            .filter(|line| line.freshness.name() == name)
            .count()
    };
    let damaged = match count("damaged") {
        0 => String::new(),
        damaged => format!(", {damaged} damaged"),
    };
    format!(
        "{} instances: {} fresh, {} stale, {} missing{damaged}\n",
        lines.len(),
        count("fresh"),
        count("stale"),
        count("missing"),
    )
}

/// The closing line of `status`: the estimated CPU time and store size of
/// the whole study and of its instances in `lines` that are not fresh
/// (still to compute); `slowness`, how many times longer this machine takes
/// than the calibration machine, has scaled the CPU times in `costs`.
pub fn cost_estimate(costs: &[(InstanceId, Cost)], lines: &[StatusLine], slowness: f64) -> String {
    let unfresh: BTreeSet<&InstanceId> = lines
        .iter()
        .filter(|line| line.freshness != Freshness::Fresh)
        .map(|line| &line.id)
        .collect();
    let whole = total_cost(costs.iter().map(|(_, cost)| cost));
    let pending = total_cost(
        costs
            .iter()
            .filter(|(id, _)| unfresh.contains(id))
            .map(|(_, cost)| cost),
    );
    format!(
        "estimate: {} CPU-hours and {} of store for the whole study; {} CPU-hours of it still to compute (calibrated on the default study, 2-core VM; this machine takes {slowness:.2}x its time per scene){}\n",
        hours(whole.cpu_seconds),
        size(whole.bytes),
        hours(pending.cpu_seconds),
        measured(costs, lines)
    )
}

/// `; measured: <h> CPU-hours for the <n> fresh instances estimated at <h>`
/// over the fresh instances whose manifests record their CPU time; empty
/// when none does.
fn measured(costs: &[(InstanceId, Cost)], lines: &[StatusLine]) -> String {
    let recorded = recorded_cpu_seconds(lines);
    if recorded.is_empty() {
        return String::new();
    }
    let estimated = total_cost(
        costs
            .iter()
            .filter(|(id, _)| recorded.contains_key(id))
            .map(|(_, cost)| cost),
    );
    let seconds: f64 = recorded.values().sum();
    format!(
        "; measured: {} CPU-hours for the {} fresh instances estimated at {}",
        hours(seconds),
        recorded.len(),
        hours(estimated.cpu_seconds)
    )
}

/// The CPU seconds of each fresh instance in `lines` whose manifest records
/// them.
fn recorded_cpu_seconds(lines: &[StatusLine]) -> BTreeMap<&InstanceId, f64> {
    lines
        .iter()
        .filter(|line| line.freshness == Freshness::Fresh)
        .filter_map(|line| Some((&line.id, line.cpu_seconds?)))
        .collect()
}

/// `status --costs`: a line per stage (in the order the plan first runs
/// it) with its instance count, the estimated CPU seconds of all of them, and for the fresh ones
/// whose manifests record it the measured CPU seconds against their
/// estimate: how well the estimate is calibrated, stage by stage.
pub fn costs_by_stage(costs: &[(InstanceId, Cost)], lines: &[StatusLine]) -> String {
    let measured = recorded_cpu_seconds(lines);
    let mut stages: Vec<(&str, StageCosts)> = Vec::new();
    for (id, cost) in costs {
        let index = match stages.iter().position(|(stage, _)| *stage == id.stage) {
            Some(index) => index,
            None => {
                stages.push((&id.stage, StageCosts::default()));
                stages.len() - 1
            }
        };
        stages[index]
            .1
            .add(cost.cpu_seconds, measured.get(id).copied());
    }
    let width = stages
        .iter()
        .map(|(stage, _)| stage.len())
        .max()
        .unwrap_or(5);
    let mut out = format!(
        "{:<width$}  instances  estimated CPU s  measured CPU s (of estimated)  ratio\n",
        "stage"
    );
    for (stage, sums) in stages {
        let measured = match sums.recorded {
            0 => "-".to_string(),
            _ => format!(
                "{:.0} ({:.0}, {} instances)",
                sums.measured, sums.measured_estimate, sums.recorded
            ),
        };
        let ratio = match sums.recorded {
            0 => "-".to_string(),
            _ if sums.measured_estimate == 0.0 => "-".to_string(),
            _ => format!("{:.2}", sums.measured / sums.measured_estimate),
        };
        let _ = writeln!(
            out,
            "{stage:<width$}  {:>9}  {:>15.0}  {measured:>29}  {ratio:>5}",
            sums.instances, sums.estimate
        );
    }
    out
}

/// One stage's estimated and measured CPU seconds.
#[derive(Default)]
struct StageCosts {
    instances: usize,
    estimate: f64,
    recorded: usize,
    measured: f64,
    measured_estimate: f64,
}

impl StageCosts {
    fn add(&mut self, estimate: f64, measured: Option<f64>) {
        self.instances += 1;
        self.estimate += estimate;
        if let Some(measured) = measured {
            self.recorded += 1;
            self.measured += measured;
            self.measured_estimate += estimate;
        }
    }
}

/// An instance's state and why: `stale: <reasons>`, `missing: <reason>`.
pub fn describe(freshness: &Freshness) -> String {
    match freshness {
        Freshness::Fresh => "fresh".into(),
        Freshness::Stale(reasons) => format!("stale: {}", reasons.join("; ")),
        Freshness::Damaged(problems) => format!("damaged: {}", problems.join("; ")),
        Freshness::Missing(reason) => format!("missing: {reason}"),
    }
}

/// CPU-seconds as hours, two significant digits.
pub fn hours(seconds: f64) -> String {
    two_digits(seconds / 3600.0)
}

/// Bytes in MB or GB, two significant digits.
pub fn size(bytes: f64) -> String {
    if bytes >= 1e9 {
        format!("{} GB", two_digits(bytes / 1e9))
    } else {
        format!("{} MB", two_digits(bytes / 1e6))
    }
}

/// `value` rounded to two significant digits, in exponent form beyond 1e6.
fn two_digits(value: f64) -> String {
    let text = format!("{value:.1e}");
    match text.parse::<f64>() {
        Ok(rounded) if rounded.abs() < 1e6 => rounded.to_string(),
        _ => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A status line of `stage[instance]` in `freshness`, with `cpu_seconds`
    /// recorded by its manifest.
    fn line(stage: &str, freshness: Freshness, cpu_seconds: Option<f64>) -> StatusLine {
        StatusLine {
            id: InstanceId::new(stage, "a"),
            key: None,
            freshness,
            shards: None,
            cpu_seconds,
        }
    }

    /// An estimate of `cpu_seconds` for `stage[a]`.
    fn cost(stage: &str, cpu_seconds: f64) -> (InstanceId, Cost) {
        let cost = Cost {
            cpu_seconds,
            bytes: 1e6,
            rows: 0.0,
        };
        (InstanceId::new(stage, "a"), cost)
    }

    /// The measured line sums the recorded CPU of the fresh instances only,
    /// against the estimate of exactly those: a stale instance's old time
    /// and a fresh one without a record enter neither sum.
    #[test]
    fn the_measured_cpu_time_is_held_against_the_same_instances_estimate() {
        let costs = [
            cost("collisions", 3600.0),
            cost("kernel", 1800.0),
            cost("moments", 900.0),
            cost("sweep", 7200.0),
        ];
        let lines = [
            line("collisions", Freshness::Fresh, Some(5400.0)),
            line("kernel", Freshness::Fresh, Some(720.0)),
            line("moments", Freshness::Fresh, None),
            line("sweep", Freshness::Stale(vec!["code".into()]), Some(9000.0)),
        ];
        let estimate = cost_estimate(&costs, &lines, 1.0);
        assert!(
            estimate.ends_with(
                "still to compute (calibrated on the default study, 2-core VM; this machine takes 1.00x its time per scene); measured: 1.7 CPU-hours for the 2 fresh instances estimated at 1.5\n"
            ),
            "{estimate}"
        );
        assert!(
            estimate.starts_with("estimate: 3.8 CPU-hours"),
            "{estimate}"
        );
        let table = costs_by_stage(&costs, &lines);
        let row = |stage: &str| {
            let row = table.lines().find(|l| l.starts_with(stage)).unwrap();
            row.split_whitespace().skip(1).collect::<Vec<_>>().join(" ")
        };
        assert_eq!(row("collisions"), "1 3600 5400 (3600, 1 instances) 1.50");
        assert_eq!(row("kernel"), "1 1800 720 (1800, 1 instances) 0.40");
        assert_eq!(row("moments"), "1 900 - -");
        assert_eq!(row("sweep"), "1 7200 - -");
    }

    /// Without any recorded CPU time there is no measured line.
    #[test]
    fn no_record_no_measured_line() {
        let lines = [line("kernel", Freshness::Fresh, None)];
        let estimate = cost_estimate(&[cost("kernel", 10.0)], &lines, 1.0);
        assert!(!estimate.contains("measured"), "{estimate}");
    }
}
