//! Building the item graph: every module, item, impl member and trait impl
//! of the crate's source as a node, with its digest and the references its
//! tokens hold (resolved later, [`super::resolve`]).

use proc_macro2::TokenStream;
use quote::ToTokens;
use sha2::{Digest, Sha256};

use super::lock::Lock;
use super::syntax::{
    attributes, flatten_use, hex, is_test, normalize, parse, scan_tokens, text, type_path,
    without_docs, without_estimates,
};
use super::{Graph, Kind, Module, Node, Scan, Sources};

impl Graph {
    pub(super) fn build(sources: &Sources, root_trait: &str) -> Result<Graph, String> {
        let mut graph = Graph {
            root_trait: root_trait.to_string(),
            modules: Vec::new(),
            nodes: Vec::new(),
            externs: Lock::parse(sources.lock)?.root_dependencies(),
            edges: Vec::new(),
            macro_edges: Vec::new(),
            self_types: Vec::new(),
            traits: Vec::new(),
            dyn_traits: Vec::new(),
        };
        let items = parse(sources, "src/lib.rs")?;
        graph.add_module(sources, "crate".into(), "src/lib.rs", "src", None, items)?;
        graph.resolve_all();
        Ok(graph)
    }

    /// Adds a module and its items; out-of-line children are read from
    /// `dir/<name>.rs` or `dir/<name>/mod.rs`.
    pub(super) fn add_module(
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

    pub(super) fn add_item(
        &mut self,
        sources: &Sources,
        module: usize,
        dir: &str,
        item: syn::Item,
    ) -> Result<(), String> {
        use syn::Item;
        let named = |ident: &syn::Ident| ident.to_string();
        let item = without_estimates(item, &self.root_trait);
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
    pub(super) fn add_impl(&mut self, sources: &Sources, module: usize, imp: syn::ItemImpl) {
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

    pub(super) fn add_node(
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
}
