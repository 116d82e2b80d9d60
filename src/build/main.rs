//! Build script: fingerprints the code every stage runs (`code.rs`) and
//! writes the table `src/pipeline/code.rs` includes, so that a stage's key
//! changes exactly when the source its computation reaches changes.

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
