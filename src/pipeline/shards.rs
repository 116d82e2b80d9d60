//! Shards: a stage that can split its work into independent units
//! ([`Stage::shard_units`]: randomizations, runs) is computed as `N`
//! contiguous unit ranges, each an artifact of its own (stage
//! `<stage>.shard`, keyed by the whole artifact's key and its range), then
//! merged by concatenating each table's rows in unit order into exactly the
//! artifact an unsharded run writes (same key, same bytes). A shard is
//! committed like any artifact, so a killed or cancelled shard leaves nothing
//! that a merge would use.

use std::ops::Range;

use serde_json::{Value, json};

use super::key::stage_key;
use super::store::{InstanceRef, Manifest};
use super::table::TableError;
use super::{Stage, Table};

/// How a run splits shardable stages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sharding {
    /// Shards per shardable instance (1: unsharded).
    pub shards: u32,
    /// Compute only this shard of every shardable instance (a Slurm array
    /// task), nothing else; `None`: compute what is missing and merge.
    pub task: Option<u32>,
}

impl Default for Sharding {
    fn default() -> Sharding {
        Sharding {
            shards: 1,
            task: None,
        }
    }
}

/// Shard `index` of `shards` over `units` units: `[index U / N, (index + 1) U / N)`.
pub fn range(units: u32, shards: u32, index: u32) -> Range<u32> {
    let bound = |k: u32| (u64::from(k) * u64::from(units) / u64::from(shards.max(1))) as u32;
    bound(index)..bound(index + 1)
}

/// The non-empty shards of `units` units split `shards` ways, with their indices.
pub fn ranges(units: u32, shards: u32) -> Vec<(u32, Range<u32>)> {
    (0..shards)
        .map(|index| (index, range(units, shards, index)))
        .filter(|(_, range)| !range.is_empty())
        .collect()
}

/// Store stage name of the shards of `stage`.
pub fn shard_stage(stage: &str) -> String {
    format!("{stage}.shard")
}

/// Instance name of one shard: `<instance>.<start>-<end>`.
pub fn shard_instance(instance: &str, units: &Range<u32>) -> String {
    format!("{instance}.{}-{}", units.start, units.end)
}

/// What one shard's key hashes: the whole artifact's key and the unit range
/// (with the whole artifact's inputs, which the shard reads).
pub fn shard_entry(stage: &dyn Stage, whole: &InstanceRef, units: &Range<u32>) -> InstanceRef {
    let params = json!({ "of": whole.key, "units": [units.start, units.end] });
    let stage_name = shard_stage(&stage.id().stage);
    InstanceRef {
        key: stage_key(
            &stage_name,
            stage.code().fingerprint,
            &params,
            &whole.inputs,
        ),
        code: stage.code().into(),
        params,
        inputs: whole.inputs.clone(),
    }
}

/// Each of `names`' tables from the shards' tables, rows concatenated in
/// shard order: the default [`Stage::merge`].
pub fn concatenate(names: &[&str], shards: Vec<Vec<Table>>) -> Result<Vec<Table>, TableError> {
    let mut by_name: Vec<Vec<Table>> = names.iter().map(|_| Vec::new()).collect();
    for table in shards.into_iter().flatten() {
        if let Some(k) = names.iter().position(|name| *name == table.name) {
            by_name[k].push(table);
        }
    }
    by_name.into_iter().map(Table::concatenate).collect()
}

/// The whole artifact a shard belongs to: `(stage, key)`, or `None` when the
/// manifest is not a shard's.
pub fn whole_of(manifest: &Manifest) -> Option<(String, String)> {
    let stage = manifest.stage.strip_suffix(".shard")?;
    let key = manifest.params.get("of").and_then(Value::as_str)?;
    Some((stage.to_string(), key.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_unit_once_in_order() {
        for (units, shards) in [(16, 4), (16, 5), (3, 8), (1, 1), (7, 7)] {
            let covered: Vec<u32> = ranges(units, shards)
                .into_iter()
                .flat_map(|(_, range)| range)
                .collect();
            assert_eq!(
                covered,
                (0..units).collect::<Vec<_>>(),
                "{units} / {shards}"
            );
        }
        assert_eq!(ranges(3, 8).len(), 3);
        assert_eq!(range(16, 5, 4), 12..16);
    }
}
