//! Which instance a run starts next: the first in plan order whose inputs
//! have all been dealt with, so that independent instances can be computed
//! at once (as `make -j` does) while each still sees its inputs resolved.

use std::collections::{BTreeMap, BTreeSet};

use crate::pipeline::{InstanceId, Stage};

/// The instances of a plan (by their index in it) not yet started, and what
/// each still waits for.
#[derive(Debug)]
pub(super) struct Schedule {
    /// Inputs in the plan not yet dealt with, per instance.
    waiting: Vec<usize>,
    /// The instances that read each instance.
    readers: Vec<Vec<usize>>,
    /// Instances whose inputs have all been dealt with, not yet started.
    ready: BTreeSet<usize>,
}

impl Schedule {
    /// The schedule of `stages`, a plan in topological order: an input that
    /// is not in the plan is not waited for (the instance will find it
    /// unavailable).
    pub(super) fn new(stages: &[Box<dyn Stage>]) -> Schedule {
        let index: BTreeMap<InstanceId, usize> = stages
            .iter()
            .enumerate()
            .map(|(at, stage)| (stage.id(), at))
            .collect();
        let mut waiting = vec![0; stages.len()];
        let mut readers = vec![Vec::new(); stages.len()];
        for (reader, stage) in stages.iter().enumerate() {
            for input in stage.inputs() {
                if let Some(&at) = index.get(&input) {
                    waiting[reader] += 1;
                    readers[at].push(reader);
                }
            }
        }
        let ready = (0..stages.len()).filter(|&at| waiting[at] == 0).collect();
        Schedule {
            waiting,
            readers,
            ready,
        }
    }

    /// The first instance in plan order that may start, taken off the list.
    pub(super) fn next(&mut self) -> Option<usize> {
        self.ready.pop_first()
    }

    /// Instance `at` has been dealt with: its readers no longer wait for it.
    pub(super) fn done(&mut self, at: usize) {
        for &reader in &self.readers[at] {
            self.waiting[reader] -= 1;
            if self.waiting[reader] == 0 {
                self.ready.insert(reader);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::code::Code;
    use crate::pipeline::{Input, Progress, StageError, Table};

    static TEST_CODE: Code = Code {
        root: "src/pipeline/executor/schedule.rs",
        fingerprint: "test",
        parts: &[],
    };

    /// An instance `name` reading `inputs`.
    struct Node {
        name: &'static str,
        inputs: &'static [&'static str],
    }

    impl Stage for Node {
        fn id(&self) -> InstanceId {
            InstanceId::new(self.name, "a")
        }
        fn code(&self) -> &'static Code {
            &TEST_CODE
        }
        fn params(&self) -> serde_json::Value {
            serde_json::Value::Null
        }
        fn tables(&self) -> &'static [&'static str] {
            &[]
        }
        fn inputs(&self) -> Vec<InstanceId> {
            self.inputs
                .iter()
                .map(|name| InstanceId::new(name, "a"))
                .collect()
        }
        fn work_units(&self) -> u64 {
            1
        }
        fn run(&self, _: &[Input], _: &Progress) -> Result<Vec<Table>, StageError> {
            Ok(Vec::new())
        }
    }

    /// Two sources, a reader of the first, a reader of both, and a stage
    /// reading one outside the plan.
    fn plan() -> Vec<Box<dyn Stage>> {
        let node = |name, inputs| Box::new(Node { name, inputs }) as Box<dyn Stage>;
        vec![
            node("a", &[]),
            node("b", &[]),
            node("c", &["a"]),
            node("d", &["a", "b"]),
            node("e", &["elsewhere"]),
        ]
    }

    #[test]
    fn an_instance_starts_once_all_its_inputs_are_done() {
        let mut schedule = Schedule::new(&plan());
        assert_eq!(schedule.next(), Some(0));
        assert_eq!(schedule.next(), Some(1));
        // An input outside the plan is not waited for.
        assert_eq!(schedule.next(), Some(4));
        assert_eq!(schedule.next(), None);
        schedule.done(1);
        assert_eq!(schedule.next(), None, "d still waits for a");
        schedule.done(0);
        assert_eq!(schedule.next(), Some(2));
        assert_eq!(schedule.next(), Some(3));
        assert_eq!(schedule.next(), None);
    }

    #[test]
    fn one_at_a_time_the_schedule_is_the_plan_order() {
        let mut schedule = Schedule::new(&plan());
        let mut order = Vec::new();
        while let Some(at) = schedule.next() {
            order.push(at);
            schedule.done(at);
        }
        assert_eq!(order, [0, 1, 2, 3, 4]);
    }
}
