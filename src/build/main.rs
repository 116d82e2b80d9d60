//! Build script: fingerprints the code every stage runs (`code.rs`) and
//! writes the table `src/pipeline/code.rs` includes, so that a stage's key
//! changes exactly when the source its computation reaches changes; and
//! lists the figure kinds (`src/figures/catalogue.rs` includes the list), so
//! that a figure is its file.

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
}

/// The Rust source of `PLANS` (`src/figures/catalogue.rs`): `<Kind>::planned`
/// of every `impl FigureKind for <Kind>` in a file of `src/figures/`, in file
/// order, so that a figure kind is its file and nothing lists it by hand.
fn figure_plans(files: &BTreeMap<String, Vec<u8>>) -> String {
    let mut out = String::from(
        "/// Every figure kind's plan, one per file of `src/figures/` (generated).\n\
         pub const PLANS: &[Plan] = &[\n",
    );
    for (path, bytes) in files {
        let Some(stem) = path
            .strip_prefix("src/figures/")
            .and_then(|p| p.strip_suffix(".rs"))
            .filter(|stem| !stem.contains('/'))
        else {
            continue;
        };
        let text = String::from_utf8_lossy(bytes);
        let file = syn::parse_file(&text).unwrap_or_else(|e| panic!("{path}: {e}"));
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
