//! `verify --recompute`: fresh instances recomputed in memory and compared
//! byte for byte with their stored artifacts.

use std::collections::BTreeMap;
use std::time::Instant;

use super::job::{DecodedTables, Job, progress_bars};
use super::*;
use crate::pipeline::clock::CpuLedger;
use crate::pipeline::key::sha256_hex;
use crate::pipeline::shards::Sharding;
use crate::pipeline::store::{Manifest, Store};
use crate::pipeline::{InstanceId, Stage};

/// What `verify --recompute` found for one instance.
#[derive(Clone, Debug, PartialEq)]
pub enum Audit {
    /// Recomputed: every file has the stored bytes.
    Same {
        /// Wall time of the recomputation, seconds.
        seconds: f64,
    },
    /// Recomputed under the same key, some files with other bytes:
    /// `(file, stored SHA-256, recomputed SHA-256)` (`-` for a file one side lacks).
    Differs(Vec<(String, String, String)>),
    /// Not recomputed, and why: no intact artifact under the current key.
    NotFresh(String),
}

/// Recomputes the fresh instances of the stages in `only` (all when empty)
/// from their stored inputs, in memory, and compares every file's bytes with
/// the stored artifact under the same key: the audit that a key means its
/// bytes (`ternary verify --recompute`), each selected instance reported to
/// `on_event` as it is checked (unless quiet). Instances not selected are only resolved; nothing is written.
pub fn recompute(
    store: &Store,
    stages: &[Box<dyn Stage>],
    only: &[String],
    verbosity: Verbosity,
    on_event: &mut dyn FnMut(Event<'_>),
) -> Result<Vec<(InstanceId, Audit)>, ExecError> {
    check_plan(stages, only)?;
    let options = RunOptions {
        only: only.to_vec(),
        force: Vec::new(),
        verbosity,
        sharding: Sharding::default(),
        jobs: 1,
    };
    let decoded = DecodedTables::default();
    let bars = progress_bars(verbosity);
    let ledger = CpuLedger::default();
    let mut resolved: BTreeMap<InstanceId, Manifest> = BTreeMap::new();
    let mut audits = Vec::new();
    for stage in stages {
        let id = stage.id();
        let selected = only.is_empty() || only.contains(&id.stage);
        let inputs = input_records(stage.as_ref(), &resolved);
        let entry = inputs.map(|inputs| keyed(stage.as_ref(), inputs));
        let checked = entry
            .as_ref()
            .map(|entry| stored(store, stage.as_ref(), &entry.key));
        let (Some(entry), Some(Stored::Intact(manifest))) = (entry, &checked) else {
            if selected {
                let reason = match checked {
                    Some(Stored::Damaged(problems)) => {
                        format!("damaged ({})", problems.join("; "))
                    }
                    Some(_) => "no artifact under the current key".to_string(),
                    None => "an input is not fresh".to_string(),
                };
                let audit = Audit::NotFresh(reason);
                if verbosity != Verbosity::Quiet {
                    on_event(Event::Audited {
                        id: &id,
                        audit: &audit,
                    });
                }
                audits.push((id, audit));
            }
            continue;
        };
        if selected {
            let job = Job {
                store,
                stage: stage.as_ref(),
                resolved: &resolved,
                options: &options,
                decoded: &decoded,
                bars: bars.as_ref(),
                cpu: &ledger.open(),
            };
            let started = Instant::now();
            let files = job.recomputed_files(&entry)?;
            let audit = compare_files(manifest, files, started.elapsed().as_secs_f64());
            if verbosity != Verbosity::Quiet {
                on_event(Event::Audited {
                    id: &id,
                    audit: &audit,
                });
            }
            audits.push((id.clone(), audit));
        }
        resolved.insert(id, Manifest::clone(manifest));
    }
    Ok(audits)
}

/// The stored files of `manifest` against recomputed `(name, bytes)`.
fn compare_files(manifest: &Manifest, files: Vec<(String, Vec<u8>)>, seconds: f64) -> Audit {
    let recomputed: BTreeMap<String, String> = files
        .into_iter()
        .map(|(name, bytes)| (name, sha256_hex(&bytes)))
        .collect();
    let stored: BTreeMap<String, String> = manifest
        .files
        .iter()
        .map(|file| (file.name.clone(), file.sha256.clone()))
        .collect();
    let mut names: Vec<&String> = stored.keys().chain(recomputed.keys()).collect();
    names.sort();
    names.dedup();
    let differing: Vec<(String, String, String)> = names
        .into_iter()
        .filter(|name| stored.get(*name) != recomputed.get(*name))
        .map(|name| {
            let side =
                |map: &BTreeMap<String, String>| map.get(name).cloned().unwrap_or("-".into());
            (name.clone(), side(&stored), side(&recomputed))
        })
        .collect();
    if differing.is_empty() {
        Audit::Same { seconds }
    } else {
        Audit::Differs(differing)
    }
}

/// One line of `verify --recompute`.
pub(super) fn audit_line(id: &InstanceId, audit: &Audit) -> String {
    let what = match audit {
        Audit::Same { seconds } => format!("same bytes (recomputed in {seconds:.2} s)"),
        Audit::Differs(files) => format!(
            "SAME KEY, DIFFERENT BYTES: {}",
            files
                .iter()
                .map(|(name, stored, now)| format!(
                    "{name} (stored {}, recomputed {})",
                    &stored[..stored.len().min(12)],
                    &now[..now.len().min(12)]
                ))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        Audit::NotFresh(reason) => format!("not checked: {reason}; run first"),
    };
    format!("{:<24} {what}", id.to_string())
}
