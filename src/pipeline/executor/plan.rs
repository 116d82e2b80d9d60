//! Checking a plan before anything runs: ids unique, inputs before their
//! consumers, stage names that exist (with the nearest one for a typo), and
//! the expected cost of every instance.

use std::collections::{BTreeMap, BTreeSet};

use super::*;
use crate::pipeline::{Cost, InstanceId, Stage};

/// Checks that ids are unique, inputs precede their consumers, and stage names
/// in `names` exist.
pub fn check_plan(stages: &[Box<dyn Stage>], names: &[String]) -> Result<(), ExecError> {
    let mut seen: BTreeSet<InstanceId> = BTreeSet::new();
    for stage in stages {
        let id = stage.id();
        if seen.contains(&id) {
            return Err(ExecError::Plan(format!("{id} is defined twice")));
        }
        if let Some(input) = stage
            .inputs()
            .into_iter()
            .find(|input| !seen.contains(input))
        {
            return Err(ExecError::Plan(format!(
                "{id} reads {input}, which is not defined before it"
            )));
        }
        seen.insert(id);
    }
    check_stage_names(stages, names).map_err(ExecError::Plan)
}

/// Checks that every name in `names` is a stage of `stages`; otherwise says
/// which is not, listing the stages and suggesting the nearest.
pub fn check_stage_names(stages: &[Box<dyn Stage>], names: &[String]) -> Result<(), String> {
    let ids: Vec<InstanceId> = stages.iter().map(|stage| stage.id()).collect();
    match names
        .iter()
        .find(|name| !ids.iter().any(|id| &id.stage == *name))
    {
        Some(name) => Err(unknown_stage(name, &ids)),
        None => Ok(()),
    }
}

/// Why `name` names no stage of `ids`: each stage once, in order of first
/// appearance, and the nearest one when `name` looks like a typo of it.
fn unknown_stage(name: &str, ids: &[InstanceId]) -> String {
    let names = stage_names(ids);
    let hint =
        nearest(name, &names).map_or(String::new(), |near| format!("; did you mean `{near}`?"));
    format!(
        "unknown stage `{name}`{hint} (stages are: {})",
        names.join(", ")
    )
}

/// The stages of `ids`, each once, in order of first appearance.
fn stage_names(ids: &[InstanceId]) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for id in ids {
        if !names.contains(&id.stage.as_str()) {
            names.push(&id.stage);
        }
    }
    names
}

/// The candidate closest to `typed` by edit distance, when at most a third
/// of the typed characters (at least one) must change to reach it: further
/// away, a suggestion is a guess.
fn nearest<'a>(typed: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let allowed = (typed.chars().count() / 3).max(1);
    candidates
        .iter()
        .map(|&candidate| (edit_distance(typed, candidate), candidate))
        .filter(|&(distance, _)| distance <= allowed)
        .min_by_key(|&(distance, _)| distance)
        .map(|(_, candidate)| candidate)
}

/// Levenshtein distance: the fewest insertions, deletions and substitutions
/// of characters that turn `a` into `b`.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    // `row[j]`: distance from the prefix of `a` read so far to `b[..j]`.
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, a_char) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &b_char) in b.iter().enumerate() {
            let substitution = diagonal + usize::from(a_char != b_char);
            diagonal = row[j + 1];
            row[j + 1] = substitution.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}

/// The expected cost of every instance of `stages` (in topological order),
/// each from its inputs' costs.
pub fn estimate(stages: &[Box<dyn Stage>]) -> Vec<(InstanceId, Cost)> {
    let mut costs: BTreeMap<InstanceId, Cost> = BTreeMap::new();
    let mut out = Vec::with_capacity(stages.len());
    for stage in stages {
        let inputs: Vec<Cost> = stage
            .inputs()
            .iter()
            .map(|id| costs.get(id).copied().unwrap_or_default())
            .collect();
        let cost = stage.cost(&inputs);
        costs.insert(stage.id(), cost);
        out.push((stage.id(), cost));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An unknown stage's error names each stage once, in the plan's order,
    /// however many instances it has.
    #[test]
    fn stage_names_are_listed_once() {
        let ids = [
            InstanceId::new("scan", "ipp-6"),
            InstanceId::new("kernel", "a"),
            InstanceId::new("scan", "ipp-8"),
            InstanceId::new("kernel", "b"),
        ];
        assert_eq!(stage_names(&ids), ["scan", "kernel"]);
    }

    /// A typo one or two characters off a stage name is answered with that
    /// name; a word far from every stage gets no guess.
    #[test]
    fn a_mistyped_stage_gets_the_nearest_name() {
        let ids = [
            InstanceId::new("collisions", "ipp-6"),
            InstanceId::new("kernel", "ipp-6"),
            InstanceId::new("figures", "ipp-6_kernels"),
        ];
        assert_eq!(edit_distance("kernl", "kernel"), 1);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(
            unknown_stage("kernl", &ids),
            "unknown stage `kernl`; did you mean `kernel`? (stages are: collisions, kernel, figures)"
        );
        assert!(unknown_stage("colisons", &ids).contains("did you mean `collisions`?"));
        assert!(!unknown_stage("paper", &ids).contains("did you mean"));
    }
}
