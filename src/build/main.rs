//! Build script: fingerprints the code every stage runs (`code.rs`) and
//! writes the table `src/pipeline/code.rs` includes, so that a stage's key
//! changes exactly when the source its computation reaches changes; lists
//! the figure kinds (`src/figures/catalogue.rs` includes the list), so that a
//! figure is its file; and lists the stages' printouts
//! (`src/contract/tables/mod.rs` includes the list), so that what a table
//! prints is declared beside it and nowhere else.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

#[path = "code.rs"]
mod code;

fn main() {
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=Cargo.lock");
    let mut files = BTreeMap::new();
    read_tree(Path::new("src"), &mut files);
    let lock = std::fs::read_to_string("Cargo.lock").expect("Cargo.lock");
    let env = |name: &str| std::env::var(name).ok();
    let sources = code::Sources {
        files: &files,
        lock: &lock,
        env: &env,
    };
    let fingerprints = code::fingerprints(&sources, code::STAGE_TRAIT, &code::SHARED_ROOTS)
        .unwrap_or_else(|error| panic!("code fingerprints: {error}"));
    let out = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("stage_code.rs");
    std::fs::write(&out, table(&fingerprints)).expect("writing the stage code table");
    let plans = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("figure_plans.rs");
    std::fs::write(&plans, figure_plans(&files)).expect("writing the figure plans");
    let details = Path::new(&std::env::var("OUT_DIR").expect("OUT_DIR")).join("details.rs");
    std::fs::write(&details, detail_printouts(&files)).expect("writing the printouts");
}

/// The Rust source of `PLANS` (`src/figures/catalogue.rs`): `<Kind>::planned`
/// of every `impl FigureKind for <Kind>` in a file of `src/figures/`, in file
/// order, so that a figure kind is its file and nothing lists it by hand.
fn figure_plans(files: &BTreeMap<String, Vec<u8>>) -> String {
    let mut out = String::from(
        "/// Every figure kind's plan, one per file of `src/figures/` (generated).\n\
         pub const PLANS: &[Plan] = &[\n",
    );
    for (stem, file) in modules_in(files, "src/figures/") {
        for item in file.items {
            let syn::Item::Impl(imp) = item else {
                continue;
            };
            let figure = imp.trait_.as_ref().is_some_and(|(_, path, _)| {
                path.segments
                    .last()
                    .is_some_and(|s| s.ident == "FigureKind")
            });
            if let (true, syn::Type::Path(kind)) = (figure, &*imp.self_ty)
                && let Some(kind) = kind.path.segments.last()
            {
                let _ = writeln!(out, "    super::{stem}::{}::planned,", kind.ident);
            }
        }
    }
    out.push_str("];\n");
    out
}

/// The Rust source of `DETAILS` (`src/contract/tables/mod.rs`): every
/// `const PRINTOUT` of a file of `src/contract/tables/`, at its top level or
/// in one of its inline modules, in file order and within a file in order,
/// so that a stage's printout is declared beside its table and nothing lists
/// it by hand.
fn detail_printouts(files: &BTreeMap<String, Vec<u8>>) -> String {
    let mut out = String::from(
        "/// Every stage table's `PRINTOUT`, in file order (generated).\n\
         pub const DETAILS: &[&Printout] = &[\n",
    );
    for (stem, file) in modules_in(files, "src/contract/tables/") {
        for item in &file.items {
            if is_printout(item) {
                let _ = writeln!(out, "    &{stem}::PRINTOUT,");
            } else if let syn::Item::Mod(m) = item
                && m.content
                    .iter()
                    .flat_map(|(_, items)| items)
                    .any(is_printout)
            {
                let _ = writeln!(out, "    &{stem}::{}::PRINTOUT,", m.ident);
            }
        }
    }
    out.push_str("];\n");
    out
}

/// Whether `item` is a `const PRINTOUT`.
fn is_printout(item: &syn::Item) -> bool {
    matches!(item, syn::Item::Const(c) if c.ident == "PRINTOUT")
}

/// Every file directly in `dir` but `mod.rs`, by its stem, parsed.
fn modules_in<'a>(
    files: &'a BTreeMap<String, Vec<u8>>,
    dir: &'a str,
) -> impl Iterator<Item = (&'a str, syn::File)> + 'a {
    files.iter().filter_map(move |(path, bytes)| {
        let stem = path
            .strip_prefix(dir)
            .and_then(|p| p.strip_suffix(".rs"))
            .filter(|stem| !stem.contains('/') && *stem != "mod")?;
        let text = String::from_utf8_lossy(bytes);
        let file = syn::parse_file(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
        Some((stem, file))
    })
}

/// Every file under `dir` by its path relative to the package.
fn read_tree(dir: &Path, files: &mut BTreeMap<String, Vec<u8>>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            read_tree(&path, files);
        } else {
            let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            files.insert(path.to_string_lossy().replace('\\', "/"), bytes);
        }
    }
}

/// The Rust source of the table: `STAGE_CODE`, one [`Code`] per stage file.
fn table(fingerprints: &[code::Fingerprint]) -> String {
    let mut out =
        String::from("/// The code of every stage, by the file of its impl (generated).\n");
    out.push_str("pub const STAGE_CODE: &[Code] = &[\n");
    for fingerprint in fingerprints {
        let _ = writeln!(
            out,
            "    Code {{ root: {:?}, fingerprint: {:?}, parts: &[",
            fingerprint.root, fingerprint.digest
        );
        for (name, digest) in &fingerprint.parts {
            let _ = writeln!(
                out,
                "        Part {{ name: {name:?}, digest: {digest:?} }},"
            );
        }
        out.push_str("    ] },\n");
    }
    out.push_str("];\n");
    out
}
