//! Code fingerprints: the source a stage's computation reaches, found from
//! the code itself and hashed insensitive to comments and formatting.
//!
//! Compiled by the build script (`src/build/main.rs`), which writes the
//! fingerprint of every stage into the library, and by `tests/code.rs`; not
//! part of the library (it needs `syn`, the library does not).
//!
//! The unit is the item: a function, constant, type, trait, macro, a trait
//! impl block, or one method of an inherent impl. Each item's tokens (doc
//! attributes removed: comments never reach the token stream) are hashed with
//! its path, and its references are resolved by Rust's name rules, simplified
//! conservatively: a name that may mean several items reaches all of them.
//! What a root reaches is the closure of
//!
//! * the items its tokens name (paths through `use` imports, globs and
//!   re-exports; macros by name; names inside format strings);
//! * every trait impl of a reached type (and, for types outside the crate or
//!   generic ones, of a reached trait; for a trait reached as `dyn Trait`,
//!   every impl of it, since a call through the object may run any), except
//!   impls of the root trait itself, which the executor calls only for their
//!   own stage;
//! * every inherent method or associated item of a reached type whose name a
//!   reached item uses (method calls are not resolved by type);
//! * the files `include_bytes!`/`include_str!` read, the `CARGO_PKG_*`
//!   values `env!` reads, and the external crates the items name, with
//!   their locked versions and dependencies (from `Cargo.lock`).
//!
//! Test items (`#[cfg(test)]`, `#[test]`) are left out: they compute nothing
//! a stage writes; so are the root trait's [`ESTIMATES`] methods.

// By path: this file is itself included by path, from the build script and
// from tests/code.rs, and its parts live in `code/`.
#[path = "code/graph.rs"]
mod graph;
#[path = "code/lock.rs"]
mod lock;
#[path = "code/resolve.rs"]
mod resolve;
#[path = "code/syntax.rs"]
mod syntax;

use std::collections::{BTreeMap, BTreeSet};

use sha2::{Digest, Sha256};

use lock::Lock;
use syntax::hex;

/// The trait whose impls are this crate's roots: one per stage.
pub const STAGE_TRAIT: &str = "Stage";

/// Methods of the root trait that only estimate (the expected cost `status`
/// and the limits read): left out of the trait and of every impl of it, so
/// of every fingerprint, since nothing they compute enters an artifact;
/// calibrating an estimate re-keys nothing.
pub const ESTIMATES: [&str; 1] = ["cost"];

/// What the executor runs on every stage's tables before they become bytes
/// (Parquet encoding, provenance metadata): part of every stage's code.
pub const SHARED_ROOTS: [&str; 1] = ["crate::pipeline::executor::encoded_tables"];

/// What the analysis reads besides the Rust files' text.
pub struct Sources<'a> {
    /// Every file under the package by path relative to it (`src/lib.rs`,
    /// `src/figures/fonts/DejaVuSans.ttf`).
    pub files: &'a BTreeMap<String, Vec<u8>>,
    /// `Cargo.lock`.
    pub lock: &'a str,
    /// Values of `CARGO_PKG_*` variables (`env!` reads them at compile time).
    pub env: &'a dyn Fn(&str) -> Option<String>,
}

/// The fingerprint of one root: a stage (by the file of its impl) with the
/// shared roots every stage runs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Fingerprint {
    /// The file holding the root's impl, e.g. `src/stages/kernel.rs`.
    pub root: String,
    /// Hex SHA-256 of `parts`.
    pub digest: String,
    /// `(part, hex SHA-256)`, sorted: each source file with the items reached
    /// in it, and each external crate as `crate <name> <version>`.
    pub parts: Vec<(String, String)>,
}

/// The fingerprint of every `impl <root_trait> for T` in the crate rooted at
/// `src/lib.rs`, each joined by the `shared` roots (paths such as
/// `crate::pipeline::executor::encoded_tables` or `crate::a::Type::method`).
/// Fails on a file the module tree names but the sources lack, two root
/// impls in one file, or a shared root that does not resolve.
pub fn fingerprints(
    sources: &Sources,
    root_trait: &str,
    shared: &[&str],
) -> Result<Vec<Fingerprint>, String> {
    let graph = Graph::build(sources, root_trait)?;
    let mut shared_nodes = Vec::new();
    for path in shared {
        let nodes = graph.named_path(path);
        if nodes.is_empty() {
            return Err(format!("shared root `{path}` names no item"));
        }
        shared_nodes.extend(nodes);
    }
    let mut roots: BTreeMap<String, usize> = BTreeMap::new();
    for (index, node) in graph.nodes.iter().enumerate() {
        if graph.implements(node, root_trait) {
            let file = graph.modules[node.module].file.clone();
            if roots.insert(file.clone(), index).is_some() {
                return Err(format!(
                    "{file}: two `impl {root_trait}` blocks in one file"
                ));
            }
        }
    }
    let lock = Lock::parse(sources.lock)?;
    Ok(roots
        .into_iter()
        .map(|(file, root)| {
            let mut start = vec![root];
            start.extend(&shared_nodes);
            let reached = graph.closure(&start, root_trait);
            graph.fingerprint(file, &reached, &lock)
        })
        .collect())
}

/// A resolved reference.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum Target {
    Node(usize),
    Module(usize),
    External(String),
}

/// A module: its file and namespace.
#[derive(Default)]
struct Module {
    /// `crate::a::b`.
    path: String,
    file: String,
    parent: Option<usize>,
    children: BTreeMap<String, usize>,
    /// Named items (nodes) by name; a name may have a type and a value.
    items: BTreeMap<String, Vec<usize>>,
    /// `use` imports: visible name -> path as written.
    imports: BTreeMap<String, Vec<Vec<String>>>,
    /// `use path::*`.
    globs: Vec<Vec<String>>,
}

/// What kind of item a node is, for the impl rules.
enum Kind {
    /// A named item: function, constant, static, type, trait.
    Named,
    /// A macro_rules macro.
    Macro { name: String },
    /// One item of an inherent impl.
    Member {
        self_type: Vec<String>,
        name: String,
    },
    /// A trait impl block.
    TraitImpl {
        self_type: Option<Vec<String>>,
        trait_path: Vec<String>,
        /// Paths in the trait path, generic arguments included
        /// (`From<Table>` names `Table`).
        trait_names: Vec<Vec<String>>,
    },
}

/// One item of the crate.
struct Node {
    module: usize,
    label: String,
    kind: Kind,
    digest: [u8; 32],
    scan: Scan,
    /// `(path, hex SHA-256)` of the files it includes (also in `digest`).
    included: Vec<(String, String)>,
}

/// The references found in a node's tokens.
#[derive(Default)]
struct Scan {
    paths: Vec<Vec<String>>,
    /// Paths written after `dyn`: traits called through an object, so any
    /// of their impls may run.
    dyn_paths: Vec<Vec<String>>,
    macros: BTreeSet<String>,
    names: BTreeSet<String>,
    local_imports: Vec<(String, Vec<String>)>,
    local_globs: Vec<Vec<String>>,
    includes: Vec<String>,
    env: Vec<String>,
}

/// The item graph of a crate, with every node's references resolved.
struct Graph {
    /// The trait whose impls are roots, which lose their [`ESTIMATES`].
    root_trait: String,
    modules: Vec<Module>,
    nodes: Vec<Node>,
    externs: BTreeSet<String>,
    /// Resolved targets of each node's references.
    edges: Vec<BTreeSet<Target>>,
    /// Nodes reached by each node's macro invocations.
    macro_edges: Vec<Vec<usize>>,
    /// Node(s) of each member's and trait impl's self type, and each trait
    /// impl's trait.
    self_types: Vec<Vec<usize>>,
    traits: Vec<Vec<usize>>,
    /// Trait nodes each node names after `dyn`.
    dyn_traits: Vec<Vec<usize>>,
}

const PATH_KEYWORDS: [&str; 4] = ["crate", "self", "super", "Self"];

const KEYWORDS: [&str; 38] = [
    "as",
    "async",
    "await",
    "break",
    "const",
    "continue",
    "dyn",
    "else",
    "enum",
    "extern",
    "false",
    "fn",
    "for",
    "if",
    "impl",
    "in",
    "let",
    "loop",
    "match",
    "mod",
    "move",
    "mut",
    "pub",
    "ref",
    "return",
    "static",
    "struct",
    "trait",
    "true",
    "type",
    "unsafe",
    "use",
    "where",
    "while",
    "union",
    "macro_rules",
    "yield",
    "box",
];

impl Graph {
    /// Whether `node` is an `impl <root_trait> for T` block.
    fn implements(&self, node: &Node, root_trait: &str) -> bool {
        matches!(&node.kind, Kind::TraitImpl { trait_path, .. }
            if trait_path.last().is_some_and(|t| t == root_trait))
    }

    /// Every node `start` reaches (the module docs give the rules).
    fn closure(&self, start: &[usize], root_trait: &str) -> BTreeSet<usize> {
        let mut reached: BTreeSet<usize> = BTreeSet::new();
        let mut names: BTreeSet<&str> = BTreeSet::new();
        let mut dynamic: BTreeSet<usize> = BTreeSet::new();
        let mut work: Vec<usize> = start.to_vec();
        loop {
            while let Some(n) = work.pop() {
                if !reached.insert(n) {
                    continue;
                }
                names.extend(self.nodes[n].scan.names.iter().map(String::as_str));
                dynamic.extend(&self.dyn_traits[n]);
                for target in &self.edges[n] {
                    match target {
                        Target::Node(m) => work.push(*m),
                        Target::Module(m) => work.extend(self.module_nodes(*m)),
                        Target::External(_) => {}
                    }
                }
                work.extend(&self.macro_edges[n]);
            }
            for (index, node) in self.nodes.iter().enumerate() {
                if reached.contains(&index) {
                    continue;
                }
                let own_type_reached = self.self_types[index].iter().any(|t| reached.contains(t));
                let joins = match &node.kind {
                    Kind::Member { name, .. } => own_type_reached && names.contains(name.as_str()),
                    Kind::TraitImpl { .. } if self.implements(node, root_trait) => false,
                    Kind::TraitImpl { .. } => {
                        own_type_reached
                            || self.traits[index].iter().any(|t| dynamic.contains(t))
                            || (self.self_types[index].is_empty()
                                && self.traits[index].iter().any(|t| reached.contains(t)))
                    }
                    _ => false,
                };
                if joins {
                    work.push(index);
                }
            }
            if work.is_empty() {
                return reached;
            }
        }
    }

    fn module_nodes(&self, m: usize) -> Vec<usize> {
        (0..self.nodes.len())
            .filter(|&n| self.nodes[n].module == m)
            .collect()
    }

    /// The fingerprint of the nodes `reached` for the root in `file`.
    fn fingerprint(&self, file: String, reached: &BTreeSet<usize>, lock: &Lock) -> Fingerprint {
        let mut per_file: BTreeMap<String, Vec<(&str, [u8; 32])>> = BTreeMap::new();
        let mut crates: BTreeSet<&str> = BTreeSet::new();
        let mut included: BTreeSet<(String, String)> = BTreeSet::new();
        for &n in reached {
            let node = &self.nodes[n];
            per_file
                .entry(self.modules[node.module].file.clone())
                .or_default()
                .push((&node.label, node.digest));
            for target in &self.edges[n] {
                if let Target::External(name) = target {
                    crates.insert(name);
                }
            }
            included.extend(node.included.iter().cloned());
        }
        let mut parts: Vec<(String, String)> = per_file
            .into_iter()
            .map(|(file, mut nodes)| {
                nodes.sort();
                let mut hasher = Sha256::new();
                for (label, digest) in nodes {
                    hasher.update(label.as_bytes());
                    hasher.update(digest);
                }
                (file, hex(&hasher.finalize()))
            })
            .collect();
        parts.extend(included);
        parts.extend(crates.into_iter().filter_map(|name| lock.part(name)));
        parts.sort();
        let mut hasher = Sha256::new();
        for (part, digest) in &parts {
            hasher.update(format!("{part} {digest}\n").as_bytes());
        }
        Fingerprint {
            root: file,
            digest: hex(&hasher.finalize()),
            parts,
        }
    }
}
