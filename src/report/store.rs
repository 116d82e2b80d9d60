//! The store's integrity and cleanup: `verify` (content hashes),
//! `verify --recompute` (`audit`, byte for byte) and `gc`.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Result;

use crate::pipeline::executor::{self, Audit, Verbosity};
use crate::pipeline::shards;
use crate::pipeline::store::{Depth, Store, is_live_staging, listing_problem};
use crate::pipeline::{InstanceId, Stage};

/// Checks every artifact down to its tables' content hashes (and, for stages
/// of the study, that it holds exactly the tables the stage writes): the
/// report and the number of damaged artifacts.
pub fn verify(store: &Store, stages: &[Box<dyn Stage>]) -> Result<(String, usize)> {
    let outputs: BTreeMap<InstanceId, Vec<String>> = stages
        .iter()
        .map(|stage| (stage.id(), executor::output_files(stage.as_ref())))
        .collect();
    let mut out = String::new();
    let mut damaged = 0;
    let artifacts = store.artifacts()?;
    for (stage, key) in &artifacts {
        let inspected = store
            .inspect(stage, key, None, Depth::Contents)
            .and_then(|manifest| {
                let id = InstanceId::new(stage, &manifest.instance);
                match outputs
                    .get(&id)
                    .and_then(|files| listing_problem(&manifest, files))
                {
                    Some(problem) => Err(vec![problem]),
                    None => Ok(manifest),
                }
            });
        match inspected {
            Ok(_) => writeln!(out, "ok       {stage}/{key}")?,
            Err(problems) => {
                damaged += 1;
                writeln!(out, "DAMAGED  {stage}/{key}: {}", problems.join("; "))?;
            }
        }
    }
    for path in store.foreign_entries()? {
        writeln!(
            out,
            "foreign  {} (not written by ternary: left alone)",
            path.display()
        )?;
    }
    let (live, debris): (Vec<PathBuf>, Vec<PathBuf>) =
        store.staging_debris()?.into_iter().partition(|path| {
            path.file_name()
                .is_some_and(|name| is_live_staging(&name.to_string_lossy()))
        });
    if !live.is_empty() {
        writeln!(
            out,
            "{} staging entries of runs in progress (not checked: not yet artifacts)",
            live.len()
        )?;
    }
    if !debris.is_empty() {
        writeln!(
            out,
            "{} staging entries from interrupted runs are ignored (the next run or gc removes them)",
            debris.len()
        )?;
    }
    writeln!(
        out,
        "verify: {} artifacts, {} intact, {} damaged",
        artifacts.len(),
        artifacts.len() - damaged,
        damaged
    )?;
    Ok((out, damaged))
}

/// `verify --recompute`: every current artifact of the stages in `only` (all
/// when empty) recomputed from its stored inputs and compared byte for byte
/// (each instance reported to `on_event` as it is checked); the summary, and
/// the number of instances that differ or could not be checked.
pub fn audit(
    store: &Store,
    stages: &[Box<dyn Stage>],
    only: &[String],
    on_event: &mut dyn FnMut(executor::Event<'_>),
) -> Result<(String, usize)> {
    let audits = executor::recompute(store, stages, only, Verbosity::Normal, on_event)?;
    let count = |wanted: fn(&Audit) -> bool| audits.iter().filter(|(_, a)| wanted(a)).count();
    let same = count(|a| matches!(a, Audit::Same { .. }));
    let differ = count(|a| matches!(a, Audit::Differs(_)));
    let unchecked = count(|a| matches!(a, Audit::NotFresh(_)));
    let mut out = String::new();
    writeln!(
        out,
        "verify --recompute: {} instances, {same} same bytes, {differ} same key with different bytes, {unchecked} not checked",
        audits.len()
    )?;
    Ok((out, differ + unchecked))
}

/// Removes artifacts that neither the current key nor the last computed key of
/// a current instance names (shards are kept while their current artifact
/// waits to be merged), and staging debris. Only names ternary gives are
/// removed; foreign entries are reported and kept.
pub fn gc(store: &Store, stages: &[Box<dyn Stage>]) -> Result<String> {
    let lock = store.lock()?;
    let mut keep: BTreeSet<(String, String)> = BTreeSet::new();
    for line in executor::status(store, stages, 1)? {
        if let Some(key) = line.key {
            keep.insert((line.id.stage.clone(), key));
        }
        if let Some(entry) = store.read_ref(&line.id.stage, &line.id.instance) {
            keep.insert((line.id.stage, entry.key));
        }
    }
    let mut removed = 0;
    let mut bytes = 0;
    let awaiting_merge = |stage: &str, key: &str| {
        let whole = store
            .inspect(stage, key, None, Depth::Sizes)
            .ok()
            .as_ref()
            .and_then(shards::whole_of);
        whole.is_some_and(|(stage, key)| {
            !store.artifact_dir(&stage, &key).is_dir() && keep.contains(&(stage, key))
        })
    };
    let mut held = Vec::new();
    for (stage, key) in store.artifacts()? {
        if !keep.contains(&(stage.clone(), key.clone())) && !awaiting_merge(&stage, &key) {
            if store.foreign_in_artifact(&stage, &key, &[]).is_empty() {
                bytes += store.remove_artifact(&lock, &stage, &key)?;
                removed += 1;
            } else {
                held.push(store.artifact_dir(&stage, &key));
            }
        }
    }
    let debris = store.clean_staging(&lock)?;
    let mut out =
        format!("gc: removed {removed} artifacts ({bytes} bytes) and {debris} staging entries\n");
    for dir in held {
        writeln!(
            out,
            "gc: kept {} (unreferenced, but it holds entries ternary did not write; remove them to let gc remove it)",
            dir.display()
        )?;
    }
    for path in store.foreign_entries()? {
        writeln!(out, "gc: kept {} (not written by ternary)", path.display())?;
    }
    Ok(out)
}
