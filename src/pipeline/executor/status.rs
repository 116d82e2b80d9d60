//! `ternary status`: the freshness of every instance, and why, without
//! computing anything.

use std::collections::BTreeMap;
use std::ops::Range;

use super::job::stored_shard;
use super::*;
use crate::pipeline::code::CodeRecord;
use crate::pipeline::key::{InputRecord, changed_params};
use crate::pipeline::shards;
use crate::pipeline::store::{InstanceRef, Manifest, Store};
use crate::pipeline::{InstanceId, Stage};

/// Freshness of one instance, as `status` reports it.
#[derive(Clone, Debug, PartialEq)]
pub enum Freshness {
    /// Up to date.
    Fresh,
    /// Computed before, but something it depends on changed.
    Stale(Vec<String>),
    /// Its artifact exists under the current key but fails its checks.
    Damaged(Vec<String>),
    /// Never computed, or its artifact is gone.
    Missing(String),
}

impl Freshness {
    /// `fresh`, `stale`, `damaged` or `missing`.
    pub fn name(&self) -> &'static str {
        match self {
            Freshness::Fresh => "fresh",
            Freshness::Stale(_) => "stale",
            Freshness::Damaged(_) => "damaged",
            Freshness::Missing(_) => "missing",
        }
    }
}

/// One line of `status`.
#[derive(Clone, Debug)]
pub struct StatusLine {
    /// The instance.
    pub id: InstanceId,
    /// Its current key, when its inputs are available.
    pub key: Option<String>,
    /// Fresh, stale or missing, and why.
    pub freshness: Freshness,
    /// For a shardable instance that is not fresh, in a sharded status: the
    /// shard indices present and missing.
    pub shards: Option<ShardProgress>,
    /// For a fresh instance, the CPU seconds its computation took, when its
    /// manifest records them.
    pub cpu_seconds: Option<f64>,
}

/// Shards of one instance present and missing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ShardProgress {
    /// Indices of intact shards (empty shards count as done).
    pub done: Vec<u32>,
    /// Indices still to compute.
    pub missing: Vec<u32>,
}

/// Freshness of every instance, with reasons, without computing anything.
/// Artifacts are checked as `run` checks them (down to file hashes). With
/// `shards > 1`, a shardable instance that is not fresh also reports which of
/// its shards are done.
pub fn status(
    store: &Store,
    stages: &[Box<dyn Stage>],
    shards: u32,
) -> Result<Vec<StatusLine>, ExecError> {
    check_plan(stages, &[])?;
    let mut resolved: BTreeMap<InstanceId, Manifest> = BTreeMap::new();
    let mut lines = Vec::new();
    for stage in stages {
        let id = stage.id();
        let previous = store.read_ref(&id.stage, &id.instance).or_else(|| {
            store
                .latest_manifest_of(&id.stage, &id.instance)
                .map(|manifest| InstanceRef::from(&manifest))
        });
        let mut key = None;
        let mut progress = None;
        let mut cpu_seconds = None;
        let freshness = match input_records(stage.as_ref(), &resolved) {
            None => {
                let waiting: Vec<String> = stage
                    .inputs()
                    .iter()
                    .filter(|input| !resolved.contains_key(input))
                    .map(ToString::to_string)
                    .collect();
                let reason = format!("waiting on {}", waiting.join(", "));
                if stage.shard_units() > 0 && shards > 1 {
                    // No shard of an instance whose key is not known yet
                    // exists: every non-empty one is still to compute (its
                    // task first computes the missing prerequisites).
                    progress = Some(shard_progress_with(stage.as_ref(), shards, |_| false));
                }
                match previous {
                    Some(_) => Freshness::Stale(vec![reason]),
                    None => Freshness::Missing(reason),
                }
            }
            Some(inputs) => {
                let whole = keyed(stage.as_ref(), inputs);
                let freshness = match stored(store, stage.as_ref(), &whole.key) {
                    Stored::Intact(manifest) => {
                        cpu_seconds = manifest.cpu_seconds;
                        resolved.insert(id.clone(), *manifest);
                        Freshness::Fresh
                    }
                    Stored::Damaged(problems) => Freshness::Damaged(problems),
                    Stored::Absent => explain(stage.as_ref(), &whole.key, &whole.inputs, previous),
                };
                if freshness != Freshness::Fresh && stage.shard_units() > 0 && shards > 1 {
                    progress = Some(shard_progress(store, stage.as_ref(), &whole, shards));
                }
                key = Some(whole.key);
                freshness
            }
        };
        lines.push(StatusLine {
            id,
            key,
            freshness,
            shards: progress,
            cpu_seconds,
        });
    }
    Ok(lines)
}

/// Which of the `shards` shards of `whole` are present.
fn shard_progress(
    store: &Store,
    stage: &dyn Stage,
    whole: &InstanceRef,
    shards: u32,
) -> ShardProgress {
    shard_progress_with(stage, shards, |units| {
        matches!(stored_shard(store, stage, whole, units), Stored::Intact(_))
    })
}

/// Which of the `shards` shards of `stage` are done, by `present` (empty
/// shards count as done).
fn shard_progress_with(
    stage: &dyn Stage,
    shards: u32,
    present: impl Fn(&Range<u32>) -> bool,
) -> ShardProgress {
    let mut progress = ShardProgress::default();
    for index in 0..shards {
        let units = shards::range(stage.shard_units(), shards, index);
        if units.is_empty() || present(&units) {
            progress.done.push(index);
        } else {
            progress.missing.push(index);
        }
    }
    progress
}

fn explain(
    stage: &dyn Stage,
    key: &str,
    inputs: &[InputRecord],
    previous: Option<InstanceRef>,
) -> Freshness {
    let Some(previous) = previous else {
        return Freshness::Missing("never computed".to_string());
    };
    if previous.key == key {
        return Freshness::Missing("its artifact was removed".to_string());
    }
    let mut reasons = Vec::new();
    let code = CodeRecord::from(stage.code());
    if previous.code.fingerprint.is_empty() {
        reasons.push("code changed (computed before keys followed the code)".to_string());
    } else if previous.code.fingerprint != code.fingerprint {
        reasons.push(format!(
            "code changed ({})",
            previous.code.changed_parts(&code).join(", ")
        ));
    }
    reasons.extend(
        changed_params(&previous.params, &stage.params())
            .into_iter()
            .map(|c| format!("parameter {c}")),
    );
    for input in inputs {
        let before = previous
            .inputs
            .iter()
            .find(|p| p.stage == input.stage && p.instance == input.instance);
        if before.map(|p| &p.files) != Some(&input.files) {
            reasons.push(format!("input {}[{}] changed", input.stage, input.instance));
        }
    }
    if reasons.is_empty() {
        reasons.push("key changed".to_string());
    }
    Freshness::Stale(reasons)
}
