//! Name resolution: each node's references resolved to nodes, modules or
//! external crates by Rust's rules, simplified conservatively (a name that
//! may mean several items reaches all of them).

use std::collections::{BTreeMap, BTreeSet, HashSet};

use super::{Graph, Kind, PATH_KEYWORDS, Target};

/// Where a path is resolved: a module plus the `use` statements inside the
/// item (block scope flattened onto the item).
pub(super) struct Scope<'a> {
    pub(super) module: usize,
    pub(super) imports: &'a [(String, Vec<String>)],
    pub(super) globs: &'a [Vec<String>],
}

impl Graph {
    /// Resolves every node's references once (they do not depend on the root).
    pub(super) fn resolve_all(&mut self) {
        let mut edges = Vec::with_capacity(self.nodes.len());
        let mut macro_edges = Vec::with_capacity(self.nodes.len());
        let mut self_types = Vec::with_capacity(self.nodes.len());
        let mut traits = Vec::with_capacity(self.nodes.len());
        let mut dyn_traits = Vec::with_capacity(self.nodes.len());
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
            dyn_traits.push(
                node.scan
                    .dyn_paths
                    .iter()
                    .flat_map(|p| nodes_of(&Some(p.clone())))
                    .collect(),
            );
        }
        self.edges = edges;
        self.macro_edges = macro_edges;
        self.self_types = self_types;
        self.traits = traits;
        self.dyn_traits = dyn_traits;
    }

    /// The targets of `path` as written in `scope`.
    pub(super) fn resolve_path(&self, scope: &Scope, path: &[String]) -> Vec<Target> {
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

    pub(super) fn resolve_first(&self, scope: &Scope, name: &str) -> Vec<Target> {
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
    pub(super) fn resolve_in(
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
    pub(super) fn resolve_imported(
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
    pub(super) fn named_path(&self, path: &str) -> Vec<usize> {
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
}
