//! Reading the syntax: parsing files, attributes and `use` trees, and
//! scanning an item's tokens (docs removed) for the paths, macros, names,
//! includes and `env!` values it refers to.

use proc_macro2::{Delimiter, Spacing, TokenStream, TokenTree};

use super::{KEYWORDS, PATH_KEYWORDS, Scan, Sources};

pub(super) fn parse(sources: &Sources, file: &str) -> Result<Vec<syn::Item>, String> {
    let bytes = sources
        .files
        .get(file)
        .ok_or_else(|| format!("{file}: named by a `mod` declaration but not found"))?;
    let text = std::str::from_utf8(bytes).map_err(|e| format!("{file}: {e}"))?;
    syn::parse_file(text)
        .map(|f| f.items)
        .map_err(|e| format!("{file}: {e}"))
}

pub(super) fn attributes(item: &syn::Item) -> &[syn::Attribute] {
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
pub(super) fn is_test(attrs: &[syn::Attribute]) -> bool {
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
/// `item` without the [`ESTIMATES`](super::ESTIMATES) methods when it is
/// the trait `root_trait` or an impl of it; any other item as it is.
pub(super) fn without_estimates(item: syn::Item, root_trait: &str) -> syn::Item {
    use syn::Item;
    let estimate = |ident: &syn::Ident| super::ESTIMATES.iter().any(|name| ident == name);
    match item {
        Item::Trait(mut t) if t.ident == root_trait => {
            t.items.retain(
                |member| !matches!(member, syn::TraitItem::Fn(f) if estimate(&f.sig.ident)),
            );
            Item::Trait(t)
        }
        Item::Impl(mut imp)
            if imp.trait_.as_ref().is_some_and(|(_, path, _)| {
                path.segments.last().is_some_and(|s| s.ident == root_trait)
            }) =>
        {
            imp.items
                .retain(|member| !matches!(member, syn::ImplItem::Fn(f) if estimate(&f.sig.ident)));
            Item::Impl(imp)
        }
        other => other,
    }
}

pub(super) fn type_path(ty: &syn::Type) -> Option<Vec<String>> {
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
pub(super) fn flatten_use(
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
pub(super) fn without_docs(tokens: TokenStream) -> TokenStream {
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
pub(super) fn scan_tokens(tokens: TokenStream, scan: &mut Scan) {
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
                } else if name == "dyn" && matches!(trees.get(i + 1), Some(TokenTree::Ident(_))) {
                    i = scan_object(&trees, i + 1, scan, &joint_colons);
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

/// The trait path after `dyn` at `trees[start]` (an identifier): a path, and
/// a trait whose impls a call through the object may run. Returns the index
/// after it.
fn scan_object(
    trees: &[TokenTree],
    start: usize,
    scan: &mut Scan,
    joint_colons: &dyn Fn(usize) -> bool,
) -> usize {
    let first = trees[start].to_string();
    scan.names.insert(first.clone());
    let end = scan_path(trees, start, first, scan, joint_colons);
    scan.dyn_paths.extend(scan.paths.last().cloned());
    end
}

/// The path starting at `trees[start]` (`a::b::c`, stopping before a
/// turbofish); returns the index after it.
pub(super) fn scan_path(
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
pub(super) fn scan_use(trees: &[TokenTree], start: usize, scan: &mut Scan) -> usize {
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
pub(super) fn macro_argument(name: &str, arguments: TokenStream, scan: &mut Scan) {
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
pub(super) fn format_names(literal: &str, scan: &mut Scan) {
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
pub(super) fn normalize(path: &str) -> String {
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
pub(super) fn text(tokens: TokenStream) -> String {
    tokens.to_string()
}

pub(super) fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
