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
//!   generic ones, of a reached trait), except impls of the root trait
//!   itself, which the executor calls only for their own stage;
//! * every inherent method or associated item of a reached type whose name a
//!   reached item uses (method calls are not resolved by type);
//! * the files `include_bytes!`/`include_str!` read, the `CARGO_PKG_*`
//!   values `env!` reads, and the external crates the items name, with
//!   their locked versions and dependencies (from `Cargo.lock`).
//!
//! Test items (`#[cfg(test)]`, `#[test]`) are left out: they compute nothing
//! a stage writes.

use std::collections::{BTreeMap, BTreeSet, HashSet};

use proc_macro2::{Delimiter, Spacing, TokenStream, TokenTree};
use quote::ToTokens;
use sha2::{Digest, Sha256};

/// The trait whose impls are this crate's roots: one per stage.
pub const STAGE_TRAIT: &str = "Stage";

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
    let graph = Graph::build(sources)?;
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
    macros: BTreeSet<String>,
    names: BTreeSet<String>,
    local_imports: Vec<(String, Vec<String>)>,
    local_globs: Vec<Vec<String>>,
    includes: Vec<String>,
    env: Vec<String>,
}

/// The item graph of a crate, with every node's references resolved.
struct Graph {
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
    fn build(sources: &Sources) -> Result<Graph, String> {
        let mut graph = Graph {
            modules: Vec::new(),
            nodes: Vec::new(),
            externs: Lock::parse(sources.lock)?.root_dependencies(),
            edges: Vec::new(),
            macro_edges: Vec::new(),
            self_types: Vec::new(),
            traits: Vec::new(),
        };
        let items = parse(sources, "src/lib.rs")?;
        graph.add_module(sources, "crate".into(), "src/lib.rs", "src", None, items)?;
        graph.resolve_all();
        Ok(graph)
    }

    /// Adds a module and its items; out-of-line children are read from
    /// `dir/<name>.rs` or `dir/<name>/mod.rs`.
    fn add_module(
        &mut self,
        sources: &Sources,
        path: String,
        file: &str,
        dir: &str,
        parent: Option<usize>,
        items: Vec<syn::Item>,
    ) -> Result<usize, String> {
        let index = self.modules.len();
        self.modules.push(Module {
            path,
            file: file.to_string(),
            parent,
            ..Module::default()
        });
        for item in items.into_iter().filter(|item| !is_test(attributes(item))) {
            self.add_item(sources, index, dir, item)?;
        }
        Ok(index)
    }

    fn add_item(
        &mut self,
        sources: &Sources,
        module: usize,
        dir: &str,
        item: syn::Item,
    ) -> Result<(), String> {
        use syn::Item;
        let named = |ident: &syn::Ident| ident.to_string();
        match item {
            Item::Mod(m) => {
                let name = named(&m.ident);
                let path = format!("{}::{name}", self.modules[module].path);
                let (file, items) = match m.content {
                    Some((_, items)) => (self.modules[module].file.clone(), items),
                    None => {
                        let flat = format!("{dir}/{name}.rs");
                        let file = if sources.files.contains_key(&flat) {
                            flat
                        } else {
                            format!("{dir}/{name}/mod.rs")
                        };
                        let items = parse(sources, &file)?;
                        (file, items)
                    }
                };
                let child_dir = format!("{dir}/{name}");
                let child =
                    self.add_module(sources, path, &file, &child_dir, Some(module), items)?;
                self.modules[module].children.insert(name, child);
            }
            Item::Use(u) => {
                let mut imports = Vec::new();
                let mut globs = Vec::new();
                flatten_use(&u.tree, Vec::new(), &mut imports, &mut globs);
                let entry = &mut self.modules[module];
                for (name, path) in imports {
                    entry.imports.entry(name).or_default().push(path);
                }
                entry.globs.extend(globs);
            }
            Item::Impl(imp) => self.add_impl(sources, module, imp),
            Item::Fn(ref f) if is_test(&f.attrs) => {}
            Item::Macro(ref m) => {
                let Some(ident) = &m.ident else {
                    return Ok(());
                };
                let name = named(ident);
                let tokens = item.to_token_stream();
                self.add_node(sources, module, name.clone(), Kind::Macro { name }, tokens);
            }
            other => {
                let name = match &other {
                    Item::Fn(f) => named(&f.sig.ident),
                    Item::Const(c) => named(&c.ident),
                    Item::Static(s) => named(&s.ident),
                    Item::Struct(s) => named(&s.ident),
                    Item::Enum(e) => named(&e.ident),
                    Item::Union(u) => named(&u.ident),
                    Item::Type(t) => named(&t.ident),
                    Item::Trait(t) => named(&t.ident),
                    Item::TraitAlias(t) => named(&t.ident),
                    _ => return Ok(()),
                };
                let tokens = other.to_token_stream();
                let node = self.add_node(sources, module, name.clone(), Kind::Named, tokens);
                self.modules[module]
                    .items
                    .entry(name)
                    .or_default()
                    .push(node);
            }
        }
        Ok(())
    }

    /// A trait impl as one node; an inherent impl as one node per item, each
    /// hashed with the impl's header.
    fn add_impl(&mut self, sources: &Sources, module: usize, imp: syn::ItemImpl) {
        if is_test(&imp.attrs) {
            return;
        }
        let self_type = type_path(&imp.self_ty);
        let self_text = text(imp.self_ty.to_token_stream());
        if let Some((_, trait_path, _)) = &imp.trait_ {
            let trait_segments: Vec<String> = trait_path
                .segments
                .iter()
                .map(|s| s.ident.to_string())
                .collect();
            let label = format!(
                "impl {} for {self_text}",
                text(trait_path.to_token_stream())
            );
            let mut names = Scan::default();
            scan_tokens(trait_path.to_token_stream(), &mut names);
            let tokens = imp.to_token_stream();
            self.add_node(
                sources,
                module,
                label,
                Kind::TraitImpl {
                    self_type,
                    trait_path: trait_segments,
                    trait_names: names.paths,
                },
                tokens,
            );
            return;
        }
        let Some(self_type) = self_type else {
            return;
        };
        let mut header = imp.generics.to_token_stream();
        imp.self_ty.to_tokens(&mut header);
        if let Some(clause) = &imp.generics.where_clause {
            clause.to_tokens(&mut header);
        }
        for member in imp.items {
            let (name, attrs) = match &member {
                syn::ImplItem::Fn(f) => (f.sig.ident.to_string(), &f.attrs),
                syn::ImplItem::Const(c) => (c.ident.to_string(), &c.attrs),
                syn::ImplItem::Type(t) => (t.ident.to_string(), &t.attrs),
                _ => continue,
            };
            if is_test(attrs) {
                continue;
            }
            let mut tokens = header.clone();
            member.to_tokens(&mut tokens);
            self.add_node(
                sources,
                module,
                format!("{self_text}::{name}"),
                Kind::Member {
                    self_type: self_type.clone(),
                    name,
                },
                tokens,
            );
        }
    }

    fn add_node(
        &mut self,
        sources: &Sources,
        module: usize,
        label: String,
        kind: Kind,
        tokens: TokenStream,
    ) -> usize {
        let tokens = without_docs(tokens);
        let mut scan = Scan::default();
        scan_tokens(tokens.clone(), &mut scan);
        let base = format!("{}::{label}", self.modules[module].path);
        let numbered = format!("{base}#");
        let count = self
            .nodes
            .iter()
            .filter(|n| n.label == base || n.label.starts_with(&numbered))
            .count();
        let label = if count == 0 {
            base
        } else {
            format!("{base}#{}", count + 1)
        };
        let mut hasher = Sha256::new();
        hasher.update(label.as_bytes());
        hasher.update(b"\n");
        hasher.update(text(tokens).as_bytes());
        let mut included = Vec::new();
        let file = &self.modules[module].file;
        let dir = file.rsplit_once('/').map_or("", |(dir, _)| dir);
        for include in &scan.includes {
            let path = normalize(&format!("{dir}/{include}"));
            let bytes = sources
                .files
                .get(&path)
                .map_or(&b"(missing)"[..], Vec::as_slice);
            let digest = hex(&Sha256::digest(bytes));
            hasher.update(format!("\ninclude {path} {digest}").as_bytes());
            included.push((path, digest));
        }
        for name in &scan.env {
            let value = name
                .starts_with("CARGO_PKG_")
                .then(|| (sources.env)(name))
                .flatten()
                .unwrap_or_default();
            hasher.update(format!("\nenv {name}={value}").as_bytes());
        }
        self.nodes.push(Node {
            module,
            label,
            kind,
            digest: hasher.finalize().into(),
            scan,
            included,
        });
        self.nodes.len() - 1
    }

    /// Resolves every node's references once (they do not depend on the root).
    fn resolve_all(&mut self) {
        let mut edges = Vec::with_capacity(self.nodes.len());
        let mut macro_edges = Vec::with_capacity(self.nodes.len());
        let mut self_types = Vec::with_capacity(self.nodes.len());
        let mut traits = Vec::with_capacity(self.nodes.len());
        let mut macros: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
        for (index, node) in self.nodes.iter().enumerate() {
            if let Kind::Macro { name } = &node.kind {
                macros.entry(name).or_default().push(index);
            }
        }
        for node in &self.nodes {
            let scope = Scope {
                module: node.module,
                imports: &node.scan.local_imports,
                globs: &node.scan.local_globs,
            };
            let mut targets = BTreeSet::new();
            for path in &node.scan.paths {
                let found = self.resolve_path(&scope, path);
                let bare_module =
                    path.len() == 1 && found.iter().all(|t| matches!(t, Target::Module(_)));
                if !bare_module {
                    targets.extend(found);
                }
            }
            // Names a glob imports from an external crate are not resolved
            // one by one: the crate counts for every item of the scope.
            let module_globs = &self.modules[node.module].globs;
            for glob in module_globs.iter().chain(&node.scan.local_globs) {
                if let Some(first) = glob.first()
                    && self.externs.contains(first)
                {
                    targets.insert(Target::External(first.clone()));
                }
            }
            edges.push(targets);
            macro_edges.push(
                node.scan
                    .macros
                    .iter()
                    .flat_map(|name| macros.get(name.as_str()).into_iter().flatten().copied())
                    .collect(),
            );
            let module_scope = Scope {
                module: node.module,
                imports: &[],
                globs: &[],
            };
            let nodes_of = |path: &Option<Vec<String>>| -> Vec<usize> {
                path.as_ref()
                    .map(|p| self.resolve_path(&module_scope, p))
                    .unwrap_or_default()
                    .into_iter()
                    .filter_map(|t| match t {
                        Target::Node(n) => Some(n),
                        _ => None,
                    })
                    .collect()
            };
            let (own, trait_nodes) = match &node.kind {
                Kind::Member { self_type, .. } => (nodes_of(&Some(self_type.clone())), Vec::new()),
                Kind::TraitImpl {
                    self_type,
                    trait_names,
                    ..
                } => (
                    nodes_of(self_type),
                    trait_names
                        .iter()
                        .flat_map(|p| nodes_of(&Some(p.clone())))
                        .collect(),
                ),
                _ => (Vec::new(), Vec::new()),
            };
            self_types.push(own);
            traits.push(trait_nodes);
        }
        self.edges = edges;
        self.macro_edges = macro_edges;
        self.self_types = self_types;
        self.traits = traits;
    }

    /// The targets of `path` as written in `scope`.
    fn resolve_path(&self, scope: &Scope, path: &[String]) -> Vec<Target> {
        let Some((first, rest)) = path.split_first() else {
            return Vec::new();
        };
        let mut current = self.resolve_first(scope, first);
        for segment in rest {
            let mut next = Vec::new();
            for target in &current {
                match target {
                    Target::Module(m) => {
                        next.extend(self.resolve_in(*m, segment, &mut HashSet::new()))
                    }
                    // An associated item, variant or method of a type: the
                    // type's members are reached by name.
                    Target::Node(_) | Target::External(_) => next.push(target.clone()),
                }
            }
            if next.is_empty() {
                return Vec::new();
            }
            current = next;
        }
        current.sort();
        current.dedup();
        current
    }

    fn resolve_first(&self, scope: &Scope, name: &str) -> Vec<Target> {
        match name {
            "crate" | "$crate" => return vec![Target::Module(0)],
            "self" => return vec![Target::Module(scope.module)],
            "super" => {
                return self.modules[scope.module]
                    .parent
                    .map(Target::Module)
                    .into_iter()
                    .collect();
            }
            "Self" | "std" | "core" | "alloc" => return Vec::new(),
            _ => {}
        }
        let module_scope = Scope {
            module: scope.module,
            imports: &[],
            globs: &[],
        };
        let mut found: Vec<Target> = scope
            .imports
            .iter()
            .filter(|(alias, _)| alias == name)
            .flat_map(|(_, path)| self.resolve_path(&module_scope, path))
            .collect();
        found.extend(self.resolve_in(scope.module, name, &mut HashSet::new()));
        if found.is_empty() {
            for glob in scope.globs {
                for target in self.resolve_path(&module_scope, glob) {
                    if let Target::Module(m) = target {
                        found.extend(self.resolve_in(m, name, &mut HashSet::new()));
                    }
                }
            }
        }
        if found.is_empty() && self.externs.contains(name) {
            found.push(Target::External(name.to_string()));
        }
        found
    }

    /// `name` inside module `m`: its items, child modules and imports, else
    /// its glob imports.
    fn resolve_in(
        &self,
        m: usize,
        name: &str,
        visited: &mut HashSet<(usize, String)>,
    ) -> Vec<Target> {
        if !visited.insert((m, name.to_string())) {
            return Vec::new();
        }
        let module = &self.modules[m];
        let mut found: Vec<Target> = module
            .items
            .get(name)
            .into_iter()
            .flatten()
            .map(|&n| Target::Node(n))
            .collect();
        if let Some(&child) = module.children.get(name) {
            found.push(Target::Module(child));
        }
        let scope = Scope {
            module: m,
            imports: &[],
            globs: &[],
        };
        for path in module.imports.get(name).into_iter().flatten() {
            found.extend(self.resolve_imported(&scope, path, visited));
        }
        if found.is_empty() {
            for glob in &module.globs {
                for target in self.resolve_imported(&scope, glob, visited) {
                    if let Target::Module(g) = target {
                        found.extend(self.resolve_in(g, name, visited));
                    }
                }
            }
        }
        found
    }

    /// A `use` path of module `scope.module` (uniform paths: the first
    /// segment is a keyword, a name in the module, or an external crate).
    fn resolve_imported(
        &self,
        scope: &Scope,
        path: &[String],
        visited: &mut HashSet<(usize, String)>,
    ) -> Vec<Target> {
        let Some((first, rest)) = path.split_first() else {
            return Vec::new();
        };
        let mut current = if PATH_KEYWORDS.contains(&first.as_str()) {
            self.resolve_first(scope, first)
        } else {
            let mut found = self.resolve_in(scope.module, first, visited);
            if found.is_empty() && self.externs.contains(first) {
                found.push(Target::External(first.clone()));
            }
            found
        };
        for segment in rest {
            let mut next = Vec::new();
            for target in &current {
                match target {
                    Target::Module(m) => next.extend(self.resolve_in(*m, segment, visited)),
                    other => next.push(other.clone()),
                }
            }
            current = next;
        }
        current
    }

    /// The nodes a root-relative path names: an item, or `Type::member`.
    fn named_path(&self, path: &str) -> Vec<usize> {
        let segments: Vec<String> = path.split("::").map(str::to_string).collect();
        let scope = Scope {
            module: 0,
            imports: &[],
            globs: &[],
        };
        let direct: Vec<usize> = self
            .resolve_path(&scope, &segments)
            .into_iter()
            .filter_map(|t| match t {
                Target::Node(n) => Some(n),
                _ => None,
            })
            .collect();
        let Some((member, owner)) = segments.split_last() else {
            return Vec::new();
        };
        let owners: Vec<usize> = self
            .resolve_path(&scope, owner)
            .into_iter()
            .filter_map(|t| match t {
                Target::Node(n) => Some(n),
                _ => None,
            })
            .collect();
        let members: Vec<usize> = (0..self.nodes.len())
            .filter(|&n| {
                matches!(&self.nodes[n].kind, Kind::Member { name, .. } if name == member)
                    && self.self_types[n].iter().any(|t| owners.contains(t))
            })
            .collect();
        if members.is_empty() { direct } else { members }
    }

    /// Whether `node` is an `impl <root_trait> for T` block.
    fn implements(&self, node: &Node, root_trait: &str) -> bool {
        matches!(&node.kind, Kind::TraitImpl { trait_path, .. }
            if trait_path.last().is_some_and(|t| t == root_trait))
    }

    /// Every node `start` reaches (the module docs give the rules).
    fn closure(&self, start: &[usize], root_trait: &str) -> BTreeSet<usize> {
        let mut reached: BTreeSet<usize> = BTreeSet::new();
        let mut names: BTreeSet<&str> = BTreeSet::new();
        let mut work: Vec<usize> = start.to_vec();
        loop {
            while let Some(n) = work.pop() {
                if !reached.insert(n) {
                    continue;
                }
                names.extend(self.nodes[n].scan.names.iter().map(String::as_str));
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

/// Where a path is resolved: a module plus the `use` statements inside the
/// item (block scope flattened onto the item).
struct Scope<'a> {
    module: usize,
    imports: &'a [(String, Vec<String>)],
    globs: &'a [Vec<String>],
}

/// The locked packages: name, version, checksum and dependencies.
struct Lock {
    packages: Vec<LockedPackage>,
}

struct LockedPackage {
    name: String,
    version: String,
    checksum: String,
    dependencies: Vec<String>,
    local: bool,
}

impl Lock {
    fn parse(text: &str) -> Result<Lock, String> {
        let value: toml::Table = toml::from_str(text).map_err(|e| format!("Cargo.lock: {e}"))?;
        let packages = value
            .get("package")
            .and_then(toml::Value::as_array)
            .ok_or("Cargo.lock: no [[package]]")?
            .iter()
            .map(|package| {
                let field = |name: &str| {
                    package
                        .get(name)
                        .and_then(toml::Value::as_str)
                        .unwrap_or_default()
                        .to_string()
                };
                LockedPackage {
                    name: field("name"),
                    version: field("version"),
                    checksum: field("checksum"),
                    dependencies: package
                        .get("dependencies")
                        .and_then(toml::Value::as_array)
                        .into_iter()
                        .flatten()
                        .filter_map(|d| d.as_str().map(str::to_string))
                        .collect(),
                    local: package.get("source").is_none(),
                }
            })
            .collect();
        Ok(Lock { packages })
    }

    /// The crate names (as Rust code spells them) the local package depends on.
    fn root_dependencies(&self) -> BTreeSet<String> {
        self.packages
            .iter()
            .filter(|p| p.local)
            .flat_map(|p| &p.dependencies)
            .map(|d| d.split(' ').next().unwrap_or_default().replace('-', "_"))
            .collect()
    }

    /// The package a dependency entry (`name` or `name version ...`) means.
    fn package(&self, entry: &str) -> Option<&LockedPackage> {
        let mut words = entry.split(' ');
        let name = words.next()?;
        let version = words.next();
        self.packages
            .iter()
            .find(|p| p.name == name && version.is_none_or(|v| v == p.version))
    }

    /// The part of the crate `rust_name` the local package depends on:
    /// `("crate <name> <version>", hex SHA-256 of the name, version and
    /// checksum of it and of everything it depends on)`.
    fn part(&self, rust_name: &str) -> Option<(String, String)> {
        let local = self.packages.iter().find(|p| p.local)?;
        let direct = local
            .dependencies
            .iter()
            .find(|d| d.split(' ').next().unwrap_or_default().replace('-', "_") == rust_name)?;
        let package = self.package(direct)?;
        let mut closure = BTreeSet::new();
        let mut work = vec![direct.as_str()];
        while let Some(entry) = work.pop() {
            let Some(dependency) = self.package(entry) else {
                continue;
            };
            let line = format!(
                "{} {} {}\n",
                dependency.name, dependency.version, dependency.checksum
            );
            if closure.insert(line) {
                work.extend(dependency.dependencies.iter().map(String::as_str));
            }
        }
        let digest = hex(&Sha256::digest(closure.into_iter().collect::<String>()));
        Some((
            format!("crate {} {}", package.name, package.version),
            digest,
        ))
    }
}

fn parse(sources: &Sources, file: &str) -> Result<Vec<syn::Item>, String> {
    let bytes = sources
        .files
        .get(file)
        .ok_or_else(|| format!("{file}: named by a `mod` declaration but not found"))?;
    let text = std::str::from_utf8(bytes).map_err(|e| format!("{file}: {e}"))?;
    syn::parse_file(text)
        .map(|f| f.items)
        .map_err(|e| format!("{file}: {e}"))
}

fn attributes(item: &syn::Item) -> &[syn::Attribute] {
    use syn::Item;
    match item {
        Item::Const(i) => &i.attrs,
        Item::Enum(i) => &i.attrs,
        Item::ExternCrate(i) => &i.attrs,
        Item::Fn(i) => &i.attrs,
        Item::ForeignMod(i) => &i.attrs,
        Item::Impl(i) => &i.attrs,
        Item::Macro(i) => &i.attrs,
        Item::Mod(i) => &i.attrs,
        Item::Static(i) => &i.attrs,
        Item::Struct(i) => &i.attrs,
        Item::Trait(i) => &i.attrs,
        Item::TraitAlias(i) => &i.attrs,
        Item::Type(i) => &i.attrs,
        Item::Union(i) => &i.attrs,
        Item::Use(i) => &i.attrs,
        _ => &[],
    }
}

/// `#[cfg(test)]` (or a `cfg` naming `test` outside `not(...)`) and `#[test]`.
fn is_test(attrs: &[syn::Attribute]) -> bool {
    attrs.iter().any(|attr| {
        if attr.path().is_ident("test") {
            return true;
        }
        if !attr.path().is_ident("cfg") {
            return false;
        }
        let syn::Meta::List(list) = &attr.meta else {
            return false;
        };
        let words = text(list.tokens.clone());
        words
            .split(|c: char| !c.is_alphanumeric() && c != '_')
            .any(|w| w == "test")
            && !words.contains("not")
    })
}

/// The path of a type's last named segment chain, through references and
/// parentheses (`&'a Foo<T>` -> `Foo`); `None` for tuples, arrays, slices.
fn type_path(ty: &syn::Type) -> Option<Vec<String>> {
    match ty {
        syn::Type::Path(p) if p.qself.is_none() => Some(
            p.path
                .segments
                .iter()
                .map(|s| s.ident.to_string())
                .collect(),
        ),
        syn::Type::Reference(r) => type_path(&r.elem),
        syn::Type::Paren(p) => type_path(&p.elem),
        syn::Type::Group(g) => type_path(&g.elem),
        _ => None,
    }
}

/// Every `use` tree leaf as `(visible name, path)` and every glob's path.
fn flatten_use(
    tree: &syn::UseTree,
    prefix: Vec<String>,
    imports: &mut Vec<(String, Vec<String>)>,
    globs: &mut Vec<Vec<String>>,
) {
    use syn::UseTree;
    match tree {
        UseTree::Path(p) => {
            let mut prefix = prefix;
            prefix.push(p.ident.to_string());
            flatten_use(&p.tree, prefix, imports, globs);
        }
        UseTree::Name(n) if n.ident == "self" => {
            if let Some(last) = prefix.last() {
                imports.push((last.clone(), prefix.clone()));
            }
        }
        UseTree::Name(n) => {
            let mut path = prefix;
            path.push(n.ident.to_string());
            imports.push((n.ident.to_string(), path));
        }
        UseTree::Rename(r) => {
            let mut path = prefix;
            if r.ident != "self" {
                path.push(r.ident.to_string());
            }
            imports.push((r.rename.to_string(), path));
        }
        UseTree::Glob(_) => globs.push(prefix),
        UseTree::Group(g) => {
            for item in &g.items {
                flatten_use(item, prefix.clone(), imports, globs);
            }
        }
    }
}

/// The tokens without `#[doc = ...]` and `#![doc = ...]` attributes, at
/// every depth (doc comments become those; other comments are not tokens).
fn without_docs(tokens: TokenStream) -> TokenStream {
    let trees: Vec<TokenTree> = tokens.into_iter().collect();
    let mut out = Vec::with_capacity(trees.len());
    let mut i = 0;
    while i < trees.len() {
        if let TokenTree::Punct(p) = &trees[i]
            && p.as_char() == '#'
        {
            let bang = matches!(trees.get(i + 1), Some(TokenTree::Punct(q)) if q.as_char() == '!');
            let at = if bang { i + 2 } else { i + 1 };
            if let Some(TokenTree::Group(g)) = trees.get(at)
                && g.delimiter() == Delimiter::Bracket
                && matches!(g.stream().into_iter().next(), Some(TokenTree::Ident(id)) if id == "doc")
            {
                i = at + 1;
                continue;
            }
        }
        out.push(match &trees[i] {
            TokenTree::Group(g) => TokenTree::Group(proc_macro2::Group::new(
                g.delimiter(),
                without_docs(g.stream()),
            )),
            other => other.clone(),
        });
        i += 1;
    }
    out.into_iter().collect()
}

/// Records the paths, macro invocations, names, `use` statements, included
/// files and `env!` variables of a token stream.
fn scan_tokens(tokens: TokenStream, scan: &mut Scan) {
    let trees: Vec<TokenTree> = tokens.into_iter().collect();
    let punct =
        |i: usize, c: char| matches!(trees.get(i), Some(TokenTree::Punct(p)) if p.as_char() == c);
    let joint_colons = |i: usize| {
        matches!(trees.get(i), Some(TokenTree::Punct(p)) if p.as_char() == ':' && p.spacing() == Spacing::Joint)
            && punct(i + 1, ':')
    };
    let mut i = 0;
    while i < trees.len() {
        match &trees[i] {
            TokenTree::Group(g) => {
                scan_tokens(g.stream(), scan);
                i += 1;
            }
            TokenTree::Literal(literal) => {
                format_names(&literal.to_string(), scan);
                i += 1;
            }
            TokenTree::Punct(p) if p.as_char() == '$' => match trees.get(i + 1) {
                Some(TokenTree::Ident(id)) if id == "crate" => {
                    i = scan_path(&trees, i + 1, "$crate".to_string(), scan, &joint_colons);
                }
                // A macro's metavariable (`$name`) names nothing.
                Some(TokenTree::Ident(_)) => i += 2,
                _ => i += 1,
            },
            TokenTree::Ident(ident) => {
                let name = ident.to_string().trim_start_matches("r#").to_string();
                scan.names.insert(name.clone());
                let after_dot = i > 0 && punct(i - 1, '.') && !(i > 1 && punct(i - 2, '.'));
                let after_colons = i > 1 && punct(i - 1, ':') && punct(i - 2, ':');
                let lifetime = i > 0 && punct(i - 1, '\'');
                if name == "use" {
                    i = scan_use(&trees, i + 1, scan);
                } else if punct(i + 1, '!') && matches!(trees.get(i + 2), Some(TokenTree::Group(_)))
                {
                    if let Some(TokenTree::Group(g)) = trees.get(i + 2) {
                        macro_argument(&name, g.stream(), scan);
                    }
                    scan.macros.insert(name);
                    i += 2;
                } else if after_dot
                    || after_colons
                    || lifetime
                    || (KEYWORDS.contains(&name.as_str())
                        && !PATH_KEYWORDS.contains(&name.as_str()))
                {
                    i += 1;
                } else {
                    i = scan_path(&trees, i, name, scan, &joint_colons);
                }
            }
            TokenTree::Punct(_) => i += 1,
        }
    }
}

/// The path starting at `trees[start]` (`a::b::c`, stopping before a
/// turbofish); returns the index after it.
fn scan_path(
    trees: &[TokenTree],
    start: usize,
    first: String,
    scan: &mut Scan,
    joint_colons: &dyn Fn(usize) -> bool,
) -> usize {
    let mut path = vec![first];
    let mut i = start + 1;
    while joint_colons(i) {
        match trees.get(i + 2) {
            Some(TokenTree::Ident(next)) => {
                let name = next.to_string().trim_start_matches("r#").to_string();
                scan.names.insert(name.clone());
                path.push(name);
                i += 3;
            }
            _ => break,
        }
    }
    scan.paths.push(path);
    i
}

/// A `use` statement inside an item: its tree up to `;` joins the item's
/// scope. Returns the index after the `;`.
fn scan_use(trees: &[TokenTree], start: usize, scan: &mut Scan) -> usize {
    let end = (start..trees.len())
        .find(|&i| matches!(&trees[i], TokenTree::Punct(p) if p.as_char() == ';'))
        .unwrap_or(trees.len());
    let tokens: TokenStream = trees[start..end].iter().cloned().collect();
    if let Ok(tree) = syn::parse2::<syn::UseTree>(tokens.clone()) {
        let mut imports = Vec::new();
        let mut globs = Vec::new();
        flatten_use(&tree, Vec::new(), &mut imports, &mut globs);
        for (alias, path) in &imports {
            scan.names.insert(alias.clone());
            scan.names.extend(path.iter().cloned());
        }
        scan.local_imports.extend(imports);
        scan.local_globs.extend(globs);
    } else {
        // Not a use declaration (e.g. inside a macro): scan it as tokens.
        scan_tokens(tokens, scan);
    }
    end + 1
}

/// The file of `include_bytes!`/`include_str!` and the variable of `env!`.
fn macro_argument(name: &str, arguments: TokenStream, scan: &mut Scan) {
    let first = arguments.into_iter().next();
    let Some(TokenTree::Literal(literal)) = first else {
        return;
    };
    let value = literal.to_string();
    let Some(value) = value.strip_prefix('"').and_then(|v| v.strip_suffix('"')) else {
        return;
    };
    match name {
        "include_bytes" | "include_str" => scan.includes.push(value.to_string()),
        "env" => scan.env.push(value.to_string()),
        _ => {}
    }
}

/// Names a format string captures (`"{MAX_BINS}"`, `"{x:.3}"`).
fn format_names(literal: &str, scan: &mut Scan) {
    if !literal.starts_with('"') {
        return;
    }
    for piece in literal.split('{').skip(1) {
        let name: String = piece
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let closes = piece[name.len()..].starts_with(['}', ':']);
        if closes && name.starts_with(|c: char| c.is_alphabetic() || c == '_') {
            scan.names.insert(name.clone());
            scan.paths.push(vec![name]);
        }
    }
}

/// `a/./b/../c` -> `a/c`.
fn normalize(path: &str) -> String {
    let mut parts: Vec<&str> = Vec::new();
    for part in path.split('/') {
        match part {
            "." | "" => {}
            ".." => {
                parts.pop();
            }
            other => parts.push(other),
        }
    }
    parts.join("/")
}

/// Tokens as text: one form for any formatting of the same tokens.
fn text(tokens: TokenStream) -> String {
    tokens.to_string()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
