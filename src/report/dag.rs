//! The DAG of a study as `ternary dag` prints it: per stage instance or per
//! stage (one node per stage, with its instance count), as text, as a
//! Graphviz `digraph` or as a Mermaid flowchart. Only the plan is read,
//! never the store.

use std::fmt::Write as _;

use crate::pipeline::Stage;

/// The form `ternary dag` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DagFormat {
    /// One line per node with its inputs.
    Text,
    /// Graphviz: `dot -Tsvg` draws it.
    Dot,
    /// A Mermaid flowchart (renders in Markdown on GitHub and GitLab).
    Mermaid,
}

/// One node of the drawn graph and the nodes it reads.
struct Node {
    /// Unique name: the instance id or the stage.
    name: String,
    /// What the node shows.
    label: String,
    /// Names of the nodes it reads, each once.
    inputs: Vec<String>,
}

/// The DAG of `stages` in `format`, per stage when `by_stage`, else per
/// instance; nodes in topological order.
pub fn dag(stages: &[Box<dyn Stage>], by_stage: bool, format: DagFormat) -> String {
    let nodes = if by_stage {
        stage_nodes(stages)
    } else {
        instance_nodes(stages)
    };
    match format {
        DagFormat::Text => text(&nodes),
        DagFormat::Dot => dot(&nodes),
        DagFormat::Mermaid => mermaid(&nodes),
    }
}

/// One node per stage instance.
fn instance_nodes(stages: &[Box<dyn Stage>]) -> Vec<Node> {
    stages
        .iter()
        .map(|stage| Node {
            name: stage.id().to_string(),
            label: stage.id().to_string(),
            inputs: stage.inputs().iter().map(ToString::to_string).collect(),
        })
        .collect()
}

/// One node per stage, labelled with its instance count, reading every stage
/// one of its instances reads; in order of each stage's first instance.
fn stage_nodes(stages: &[Box<dyn Stage>]) -> Vec<Node> {
    let mut nodes: Vec<(Node, usize)> = Vec::new();
    for stage in stages {
        let name = stage.id().stage;
        let index = match nodes.iter().position(|(node, _)| node.name == name) {
            Some(index) => index,
            None => {
                let node = Node {
                    name,
                    label: String::new(),
                    inputs: Vec::new(),
                };
                nodes.push((node, 0));
                nodes.len() - 1
            }
        };
        let (node, count) = &mut nodes[index];
        *count += 1;
        for input in stage.inputs() {
            if !node.inputs.contains(&input.stage) {
                node.inputs.push(input.stage);
            }
        }
    }
    nodes
        .into_iter()
        .map(|(node, count)| Node {
            label: format!("{} ({count})", node.name),
            ..node
        })
        .collect()
}

/// One line per node: its label, then `<- inputs` or `(source)`.
fn text(nodes: &[Node]) -> String {
    let width = nodes
        .iter()
        .map(|node| node.label.chars().count())
        .max()
        .unwrap_or(0);
    let mut out = String::new();
    for node in nodes {
        let from = if node.inputs.is_empty() {
            "(source)".to_string()
        } else {
            format!("<- {}", node.inputs.join(", "))
        };
        let _ = writeln!(out, "{:<width$}  {from}", node.label);
    }
    out
}

/// A Graphviz `digraph`: every node declared with its label, then one edge
/// per input, left to right.
fn dot(nodes: &[Node]) -> String {
    let quoted = |text: &str| format!("\"{}\"", text.replace('\\', "\\\\").replace('"', "\\\""));
    let mut out = String::from("digraph ternary {\n  rankdir=LR;\n  node [shape=box];\n");
    for node in nodes {
        let _ = writeln!(
            out,
            "  {} [label={}];",
            quoted(&node.name),
            quoted(&node.label)
        );
    }
    for node in nodes {
        for input in &node.inputs {
            let _ = writeln!(out, "  {} -> {};", quoted(input), quoted(&node.name));
        }
    }
    out.push_str("}\n");
    out
}

/// A Mermaid flowchart: nodes `n0`, `n1`, ... (Mermaid ids cannot hold
/// brackets) with quoted labels, then one edge per input.
fn mermaid(nodes: &[Node]) -> String {
    let id = |name: &str| {
        nodes
            .iter()
            .position(|node| node.name == name)
            .map_or_else(|| name.to_string(), |index| format!("n{index}"))
    };
    let mut out = String::from("flowchart LR\n");
    for (index, node) in nodes.iter().enumerate() {
        let _ = writeln!(out, "  n{index}[\"{}\"]", node.label.replace('"', "#quot;"));
    }
    for node in nodes {
        for input in &node.inputs {
            let _ = writeln!(out, "  {} --> {}", id(input), id(&node.name));
        }
    }
    out
}
