//! Code fingerprints (`src/build/code.rs`, which the build script runs): a
//! comment or formatting edit changes no fingerprint; an edit in a function
//! body changes the fingerprint of exactly the stages that reach it, on a
//! tiny crate built here and on this crate's own source.

use std::collections::BTreeMap;
use std::path::Path;

#[path = "../src/build/code.rs"]
mod code;

use code::{Fingerprint, Sources};

const LOCK: &str = r#"
version = 4

[[package]]
name = "tiny"
version = "0.1.0"
dependencies = ["rustfft"]

[[package]]
name = "rustfft"
version = "6.4.1"
source = "registry+https://github.com/rust-lang/crates.io-index"
checksum = "aa"
dependencies = ["num-complex"]

[[package]]
name = "num-complex"
version = "0.4.6"
source = "registry+https://github.com/rust-lang/crates.io-index"
checksum = "bb"
"#;

/// A tiny crate: a `Stage` trait, a shared module, three stages and an
/// unrelated report; `encode` is the shared root.
fn tiny() -> BTreeMap<String, String> {
    let files = [
        (
            "src/lib.rs",
            "pub mod pipeline;\npub mod shared;\npub mod stages;\npub mod report;\n",
        ),
        (
            "src/pipeline.rs",
            "pub trait Stage { fn run(&self) -> f64; fn cost(&self) -> f64 { 1.0 } }\n\
             pub fn encode(x: f64) -> Vec<u8> { x.to_le_bytes().to_vec() }\n",
        ),
        (
            "src/shared.rs",
            "use rustfft::FftPlanner;\n\
             pub const SCALE: f64 = 2.0;\n\
             /// Doubles.\n\
             pub fn double(x: f64) -> f64 { SCALE * x }\n\
             pub fn spectrum(x: f64) -> f64 { let _ = FftPlanner::<f64>::new(); x }\n\
             pub struct Grid { pub step: f64 }\n\
             impl Grid {\n\
                 pub fn width(&self) -> f64 { self.step * 10.0 }\n\
                 pub fn unused(&self) -> f64 { self.step }\n\
             }\n\
             impl Default for Grid { fn default() -> Grid { Grid { step: 0.5 } } }\n\
             #[cfg(test)]\n\
             mod tests { #[test] fn t() { assert_eq!(super::double(1.0), 2.0); } }\n",
        ),
        ("src/stages/mod.rs", "pub mod a;\npub mod b;\npub mod c;\n"),
        (
            "src/stages/a.rs",
            "use crate::pipeline::Stage;\nuse crate::shared::{double, Grid};\n\
             pub struct A;\n\
             const CPU_PER_NODE: f64 = 1e-3;\n\
             impl Stage for A {\n\
                 fn run(&self) -> f64 { double(Grid::default().width()) }\n\
                 fn cost(&self) -> f64 { CPU_PER_NODE * 40.0 }\n\
             }\n",
        ),
        (
            "src/stages/b.rs",
            "use crate::pipeline::Stage;\nuse crate::shared;\n\
             pub struct B;\n\
             impl Stage for B { fn run(&self) -> f64 { shared::spectrum(1.0) } }\n",
        ),
        (
            "src/stages/c.rs",
            "use crate::pipeline::*;\n\
             pub struct C;\n\
             impl Stage for C { fn run(&self) -> f64 { format!(\"{}\", 1).len() as f64 } }\n",
        ),
        (
            "src/report.rs",
            "pub fn summary() -> String { crate::shared::double(3.0).to_string() }\n",
        ),
    ];
    files
        .into_iter()
        .map(|(path, text)| (path.to_string(), text.to_string()))
        .collect()
}

/// Fingerprints of a crate given as texts, with `lock`.
fn fingerprints_of(
    files: &BTreeMap<String, String>,
    lock: &str,
    shared: &[&str],
) -> Vec<Fingerprint> {
    let bytes: BTreeMap<String, Vec<u8>> = files
        .iter()
        .map(|(path, text)| (path.clone(), text.clone().into_bytes()))
        .collect();
    let env = |_: &str| None;
    let sources = Sources {
        files: &bytes,
        lock,
        env: &env,
    };
    code::fingerprints(&sources, code::STAGE_TRAIT, shared).expect("fingerprints")
}

fn tiny_fingerprints(files: &BTreeMap<String, String>) -> BTreeMap<String, String> {
    fingerprints_of(files, LOCK, &["crate::pipeline::encode"])
        .into_iter()
        .map(|f| (f.root, f.digest))
        .collect()
}

/// The roots whose fingerprints differ between two maps.
fn changed(before: &BTreeMap<String, String>, after: &BTreeMap<String, String>) -> Vec<String> {
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>()
    );
    before
        .iter()
        .filter(|(root, digest)| after[*root] != **digest)
        .map(|(root, _)| root.clone())
        .collect()
}

/// `files` with `old` replaced by `new` in `path` (which must contain it).
fn edited(
    files: &BTreeMap<String, String>,
    path: &str,
    old: &str,
    new: &str,
) -> BTreeMap<String, String> {
    let mut files = files.clone();
    let text = files.get_mut(path).expect(path);
    assert!(text.contains(old), "{path} lacks `{old}`");
    *text = text.replacen(old, new, 1);
    files
}

#[test]
fn comment_and_formatting_edits_leave_every_fingerprint_unchanged() {
    let files = tiny();
    let base = tiny_fingerprints(&files);
    assert_eq!(base.len(), 3, "one fingerprint per stage file: {base:?}");
    let commented = edited(
        &files,
        "src/shared.rs",
        "/// Doubles.\n",
        "/// Doubles its argument (a new doc comment).\n// a comment\n/* a block\n comment */\n",
    );
    let reformatted = edited(
        &commented,
        "src/shared.rs",
        "pub fn double(x: f64) -> f64 { SCALE * x }",
        "pub fn double(\n    x: f64\n) -> f64 {\n    SCALE   *   x // twice\n}",
    );
    assert!(changed(&base, &tiny_fingerprints(&reformatted)).is_empty());
    // Test code computes nothing a stage writes.
    let tested = edited(&files, "src/shared.rs", "2.0); }", "2.0, \"more\"); }");
    assert!(changed(&base, &tiny_fingerprints(&tested)).is_empty());
}

#[test]
fn a_function_body_edit_changes_exactly_the_stages_that_reach_it() {
    let files = tiny();
    let base = tiny_fingerprints(&files);
    let (a, b, c) = ("src/stages/a.rs", "src/stages/b.rs", "src/stages/c.rs");
    // `double` is reached by `a` (and by the report, which is no stage).
    let body = edited(&files, "src/shared.rs", "SCALE * x", "x * SCALE");
    assert_eq!(changed(&base, &tiny_fingerprints(&body)), [a]);
    // A constant `double` reads.
    let constant = edited(
        &files,
        "src/shared.rs",
        "SCALE: f64 = 2.0",
        "SCALE: f64 = 2.5",
    );
    assert_eq!(changed(&base, &tiny_fingerprints(&constant)), [a]);
    // A method `a` calls (by name, on a type it reaches), and a trait impl
    // of that type (`Grid::default()`).
    let method = edited(
        &files,
        "src/shared.rs",
        "self.step * 10.0",
        "self.step * 11.0",
    );
    assert_eq!(changed(&base, &tiny_fingerprints(&method)), [a]);
    let default = edited(&files, "src/shared.rs", "step: 0.5", "step: 0.25");
    assert_eq!(changed(&base, &tiny_fingerprints(&default)), [a]);
    // A method nobody calls, and code only the report runs.
    let unused = edited(&files, "src/shared.rs", "{ self.step }", "{ -self.step }");
    assert!(changed(&base, &tiny_fingerprints(&unused)).is_empty());
    let report = edited(&files, "src/report.rs", "3.0", "4.0");
    assert!(changed(&base, &tiny_fingerprints(&report)).is_empty());
    // The shared root is in every stage's code, and so is the stage trait.
    let encode = edited(&files, "src/pipeline.rs", "to_le_bytes", "to_be_bytes");
    assert_eq!(changed(&base, &tiny_fingerprints(&encode)), [a, b, c]);
    // Through a module path (`shared::spectrum`) and only there.
    let spectrum = edited(&files, "src/shared.rs", "; x }", "; -x }");
    assert_eq!(changed(&base, &tiny_fingerprints(&spectrum)), [b]);
    // Each stage's own file.
    let own = edited(&files, "src/stages/c.rs", "1).len()", "2).len()");
    assert_eq!(changed(&base, &tiny_fingerprints(&own)), [c]);
}

#[test]
fn the_cost_estimate_is_no_stage_code() {
    let files = tiny();
    let base = tiny_fingerprints(&files);
    let a = "src/stages/a.rs";
    // An impl's estimate, the constant only it reads, the trait's default.
    let body = edited(&files, a, "CPU_PER_NODE * 40.0", "CPU_PER_NODE * 80.0");
    let constant = edited(&files, a, "1e-3", "2e-3");
    let default = edited(&files, "src/pipeline.rs", "{ 1.0 }", "{ 2.0 }");
    for calibrated in [body, constant, default] {
        assert!(changed(&base, &tiny_fingerprints(&calibrated)).is_empty());
    }
    // The stage's computation beside it still counts.
    let run = edited(
        &files,
        a,
        "Grid::default().width()",
        "Grid::default().width() + 1.0",
    );
    assert_eq!(changed(&base, &tiny_fingerprints(&run)), [a]);
}

#[test]
fn a_locked_crate_counts_for_the_stages_that_name_it() {
    let files = tiny();
    let base = tiny_fingerprints(&files);
    let bumped = LOCK.replace("\"0.4.6\"", "\"0.4.7\"");
    let after: BTreeMap<String, String> =
        fingerprints_of(&files, &bumped, &["crate::pipeline::encode"])
            .into_iter()
            .map(|f| (f.root, f.digest))
            .collect();
    // num-complex is a dependency of rustfft, which only `b` names.
    assert_eq!(changed(&base, &after), ["src/stages/b.rs"]);
    let parts = fingerprints_of(&files, LOCK, &["crate::pipeline::encode"]);
    let b = parts.iter().find(|f| f.root == "src/stages/b.rs").unwrap();
    let names: Vec<&str> = b.parts.iter().map(|(name, _)| name.as_str()).collect();
    assert_eq!(
        names,
        [
            "crate rustfft 6.4.1",
            "src/pipeline.rs",
            "src/shared.rs",
            "src/stages/b.rs"
        ]
    );
}

/// A call through `dyn Trait` may run any impl of the trait: a stage that
/// holds a trait object reaches every impl, even of a type only code outside
/// the stage names (as the `figures` stage holds `Box<dyn FigureKind>` and
/// only the plan names the figure kinds).
#[test]
fn a_trait_object_reaches_every_impl_of_its_trait() {
    let mut files = edited(
        &tiny(),
        "src/shared.rs",
        "pub const SCALE",
        "pub trait Shape { fn area(&self) -> f64; }\n\
         pub fn total(shapes: &[Box<dyn Shape>]) -> f64 { shapes.iter().map(|s| s.area()).sum() }\n\
         pub const SCALE",
    );
    files = edited(
        &files,
        "src/stages/b.rs",
        "shared::spectrum(1.0)",
        "shared::spectrum(1.0) + shared::total(&[])",
    );
    files = edited(
        &files,
        "src/lib.rs",
        "pub mod report;",
        "pub mod report;\npub mod shapes;",
    );
    files.insert(
        "src/shapes.rs".into(),
        "pub struct Square;\n\
         impl crate::shared::Shape for Square { fn area(&self) -> f64 { 4.0 } }\n\
         pub fn all() -> Vec<Box<dyn crate::shared::Shape>> { vec![Box::new(Square)] }\n"
            .into(),
    );
    let base = tiny_fingerprints(&files);
    let area = edited(&files, "src/shapes.rs", "4.0", "9.0");
    assert_eq!(
        changed(&base, &tiny_fingerprints(&area)),
        ["src/stages/b.rs"]
    );
    // The list that builds the objects is not code the stage runs.
    let list = edited(
        &files,
        "src/shapes.rs",
        "vec![Box::new(Square)]",
        "Vec::new()",
    );
    assert!(changed(&base, &tiny_fingerprints(&list)).is_empty());
}

/// This crate's source as the build script reads it.
fn real_source() -> BTreeMap<String, Vec<u8>> {
    fn walk(dir: &Path, root: &Path, files: &mut BTreeMap<String, Vec<u8>>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, root, files);
            } else {
                let name = path
                    .strip_prefix(root)
                    .unwrap()
                    .to_string_lossy()
                    .replace('\\', "/");
                files.insert(name, std::fs::read(&path).unwrap());
            }
        }
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = BTreeMap::new();
    walk(&root.join("src"), root, &mut files);
    files
}

fn real_fingerprints(files: &BTreeMap<String, Vec<u8>>) -> Vec<Fingerprint> {
    let lock =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("Cargo.lock")).unwrap();
    let env = |name: &str| std::env::var(name).ok();
    let sources = Sources {
        files,
        lock: &lock,
        env: &env,
    };
    code::fingerprints(&sources, code::STAGE_TRAIT, &code::SHARED_ROOTS).expect("fingerprints")
}

/// The stage names whose fingerprints differ after `edit` of `path`.
fn stages_changed_by(path: &str, old: &str, new: &str) -> Vec<String> {
    let files = real_source();
    let before = real_fingerprints(&files);
    let mut edited = files.clone();
    let text = String::from_utf8(edited[path].clone()).unwrap();
    assert!(text.contains(old), "{path} lacks `{old}`");
    edited.insert(path.to_string(), text.replacen(old, new, 1).into_bytes());
    let after = real_fingerprints(&edited);
    before
        .iter()
        .zip(&after)
        .filter(|(b, a)| b.digest != a.digest)
        .map(|(b, _)| {
            b.root
                .trim_start_matches("src/stages/")
                .trim_end_matches(".rs")
                .to_string()
        })
        .collect()
}

/// The issue's example: one constant of the laying of quadrature nodes.
/// Every stage that histograms nodes through `kernel::segments` changes; the
/// scenes, their launches, the scans and the rings do not.
#[test]
fn the_laying_constant_rekeys_the_histogramming_stages_only() {
    let changed = stages_changed_by(
        "src/kernel/segments.rs",
        "pub const CORE_KICK: f64 = 2e-3;",
        "pub const CORE_KICK: f64 = 2.5e-3;",
    );
    for stage in [
        "kernel",
        "evolve",
        "compare",
        "convergence",
        "sweep",
        "paper",
    ] {
        assert!(
            changed.iter().any(|s| s == stage),
            "{stage} not in {changed:?}"
        );
    }
    for stage in [
        "scan",
        "launches",
        "collisions",
        "md",
        "table",
        "fit",
        "figures",
        "gases",
    ] {
        assert!(
            !changed.iter().any(|s| s == stage),
            "{stage} in {changed:?}"
        );
    }
}

#[test]
fn comments_in_the_real_source_change_nothing_and_the_report_is_no_stage_code() {
    assert!(
        stages_changed_by(
            "src/kernel/segments.rs",
            "pub const CORE_KICK: f64 = 2e-3;",
            "/// A comment.\npub const CORE_KICK: f64 =\n    2e-3; // same value",
        )
        .is_empty()
    );
    // What a table's printout shows, declared beside its columns, is in
    // no stage's key.
    assert!(
        stages_changed_by(
            "src/contract/tables/convergence.rs",
            "Shown::Fixed(SHIFT_OVER_ERROR, 3)",
            "Shown::Fixed(SHIFT_OVER_ERROR, 4)",
        )
        .is_empty()
    );
    assert!(
        stages_changed_by(
            "src/report/printout.rs",
            "format!(\"{:.3}%\", 100.0 * r)",
            "format!(\"{:.4}%\", 100.0 * r)",
        )
        .is_empty()
    );
}

/// The table compiled into the library is what the analysis gives for this
/// source (the build script reran on every change).
#[test]
fn the_library_carries_the_fingerprints_of_its_own_source() {
    let computed = real_fingerprints(&real_source());
    let compiled = ternary::pipeline::code::STAGE_CODE;
    assert_eq!(computed.len(), compiled.len());
    for (computed, compiled) in computed.iter().zip(compiled) {
        assert_eq!(computed.root, compiled.root);
        assert_eq!(computed.digest, compiled.fingerprint, "{}", computed.root);
        let parts: Vec<(String, String)> = compiled
            .parts
            .iter()
            .map(|p| (p.name.to_string(), p.digest.to_string()))
            .collect();
        assert_eq!(computed.parts, parts);
    }
}

/// Stages are adapters (decode, call the library, encode): a stage file
/// names other stages only through the contract (their tables, readers and
/// instance names), never by importing one, so that a stage's code reaches
/// no other stage's code.
#[test]
fn no_stage_imports_another_stage() {
    let files = real_source();
    let stage_files: Vec<(&String, String)> = files
        .iter()
        .filter(|(path, _)| path.starts_with("src/stages/") && !path.ends_with("/mod.rs"))
        .map(|(path, bytes)| (path, String::from_utf8_lossy(bytes).into_owned()))
        .collect();
    assert!(stage_files.len() >= 15, "{} stage files", stage_files.len());
    for (path, text) in stage_files {
        for line in text.lines() {
            let line = line.trim();
            assert!(
                !(line.contains("use super::") || line.contains("crate::stages::")),
                "{path} imports a stage: `{line}`"
            );
        }
    }
}

/// Longest function in src/, in lines (issue 33 for stage files: a stage
/// decodes, calls the library and encodes; more than this is science or
/// planning that belongs in a library module). Elsewhere the longer ones are
/// listed in [`LONG_FUNCTIONS`] with the reason.
const LONGEST_FUNCTION: usize = 60;

/// Longest source file, in lines (tests included); the longer ones are
/// listed in [`LONG_FILES`] with the reason.
const LONGEST_FILE: usize = 900;

/// Functions of src/ (outside src/stages/, which has none) longer than
/// [`LONGEST_FUNCTION`]: `(file, function, why)`. An entry that no longer
/// names a long function fails the test, so the list only shrinks.
const LONG_FUNCTIONS: [(&str, &str, &str); 30] = [
    (
        "src/figures/draw.rs",
        "chart",
        "plotters' calls for one chart: axes, grid, legend, in drawing order",
    ),
    (
        "src/figures/draw.rs",
        "draw_series",
        "one arm per series style, each a plotters call",
    ),
    (
        "src/bench/kernel.rs",
        "kernel",
        "a benchmark: the variants run in one process and tabulated",
    ),
    (
        "src/bench/md.rs",
        "md",
        "a benchmark: the variants run in one process and tabulated",
    ),
    (
        "src/bench/balance.rs",
        "balance",
        "a benchmark: the variants run in one process and tabulated",
    ),
    (
        "src/bench/integrators.rs",
        "integrators",
        "a benchmark: the variants run in one process and tabulated",
    ),
    (
        "src/bench/quadrature.rs",
        "inner_rule_convergence",
        "a benchmark: the variants run in one process and tabulated",
    ),
    (
        "src/config/collisions.rs",
        "validate",
        "a range check per key of the section, in the section's order",
    ),
    (
        "src/config/kernel.rs",
        "validate",
        "a range check per key of the section, in the section's order",
    ),
    (
        "src/config/sweep.rs",
        "validate",
        "a range check per key of the section, in the section's order",
    ),
    (
        "src/config/evolve.rs",
        "validate",
        "a range check per key of the section, in the section's order",
    ),
    (
        "src/config/md.rs",
        "ring",
        "a ring's parameters resolved key by key, each with its error",
    ),
    (
        "src/config/gas.rs",
        "resolve",
        "a gas's units resolved key by key, each with its error",
    ),
    (
        "src/report/html.rs",
        "stage_list",
        "the report's stage table, a column per line (issue 57 item 2)",
    ),
    (
        "src/report/html.rs",
        "page",
        "the report page's sections in order",
    ),
    (
        "src/report/pairs.rs",
        "pairs_text",
        "a printer, a line per measured rate",
    ),
    (
        "src/report/store.rs",
        "verify",
        "one check per kind of damage, in the order verify reports them",
    ),
    (
        "src/cli/commands.rs",
        "pairs",
        "the command's steps: load, ring, prediction, print",
    ),
    (
        "src/export/mod.rs",
        "selected_entries",
        "the bundle's entries by kind, in the bundle's order",
    ),
    (
        "src/build/code/resolve.rs",
        "resolve_all",
        "Rust's name rules, an arm per reference kind",
    ),
    (
        "src/build/code/graph.rs",
        "add_item",
        "an arm per item kind of syn",
    ),
    (
        "src/build/code/graph.rs",
        "add_impl",
        "trait and inherent impls, each member its node",
    ),
    (
        "src/pipeline/executor/recompute.rs",
        "recompute",
        "the audit's loop: resolve, recompute, compare, report",
    ),
    (
        "src/pipeline/executor/status.rs",
        "status",
        "freshness with its reasons, and shard progress",
    ),
    (
        "src/rates.rs",
        "interpolate",
        "a gas's rates from the table's columns, each interpolated with its error",
    ),
    (
        "src/physics/md.rs",
        "sample",
        "a ring run's measurements at each sampling time, in one pass",
    ),
    (
        "src/physics/md.rs",
        "goodness_p_values_are_uniform_under_the_reference",
        "a test: its fixture and assertions",
    ),
    (
        "src/physics/pair_kinetics.rs",
        "pair_relaxation",
        "the pair-population fit and its error in one pass",
    ),
    (
        "src/kernel/mod.rs",
        "pilot_same_side_fraction",
        "the pilot's Neyman split, with its bounds",
    ),
    (
        "src/slurm.rs",
        "submit",
        "the job script's directives in order",
    ),
];

/// Source files longer than [`LONGEST_FILE`]: `(file, why)`.
const LONG_FILES: [(&str, &str); 3] = [
    (
        "src/stats.rs",
        "estimates, jackknife, chi-square and their tests; to split by topic",
    ),
    (
        "src/physics/clusters.rs",
        "the ring's cluster stepping and its tests; to split",
    ),
    (
        "src/figures/draw.rs",
        "the drawing primitives; to split with issue 57 item 1",
    ),
];

/// Every function of `text` (rustfmt-formatted): `(line, name, lines
/// spanned)`, from its `fn` line to its closing brace at the same
/// indentation; one-line functions are left out.
fn functions(path: &str, text: &str) -> Vec<(usize, String, usize)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (start, line) in lines.iter().enumerate() {
        let indent = line.len() - line.trim_start().len();
        let head = line.trim_start();
        let head = match head.strip_prefix("pub") {
            Some(rest) => rest.split_once(' ').map_or(rest, |(_, fun)| fun),
            None => head,
        };
        let one_line = line.trim_end().ends_with(';') || line.trim_end().ends_with('}');
        let Some(signature) = head.strip_prefix("fn ").filter(|_| !one_line) else {
            continue;
        };
        let name: String = signature
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let closing = format!("{}}}", " ".repeat(indent));
        let end = lines[start..]
            .iter()
            .position(|l| *l == closing)
            .unwrap_or_else(|| panic!("{path}:{}: no closing brace", start + 1));
        found.push((start + 1, name, end));
    }
    found
}

/// Every function in src/ spans at most [`LONGEST_FUNCTION`] lines but those
/// [`LONG_FUNCTIONS`] names with a reason; none in src/stages/.
#[test]
fn no_function_is_longer_than_sixty_lines_but_the_listed() {
    let files = real_source();
    let mut listed_and_long = std::collections::BTreeSet::new();
    let mut checked = 0;
    for (path, bytes) in files.iter().filter(|(p, _)| p.ends_with(".rs")) {
        for (line, name, span) in functions(path, &String::from_utf8_lossy(bytes)) {
            checked += 1;
            if span <= LONGEST_FUNCTION {
                continue;
            }
            let listed = LONG_FUNCTIONS
                .iter()
                .any(|(file, function, _)| file == path && *function == name);
            assert!(
                listed && !path.starts_with("src/stages/"),
                "{path}:{line}: `{name}` spans {span} lines (at most {LONGEST_FUNCTION}, or listed in LONG_FUNCTIONS with the reason)"
            );
            listed_and_long.insert((path.as_str(), name));
        }
    }
    assert!(checked > 1000, "only {checked} functions found");
    for (file, function, _) in LONG_FUNCTIONS {
        assert!(
            listed_and_long.contains(&(file, function.to_string())),
            "LONG_FUNCTIONS lists `{function}` of {file}, which is no longer a function over {LONGEST_FUNCTION} lines: remove it"
        );
    }
}

/// Every source file has at most [`LONGEST_FILE`] lines but those
/// [`LONG_FILES`] names with a reason.
#[test]
fn no_source_file_is_longer_than_nine_hundred_lines_but_the_listed() {
    let files = real_source();
    for (path, bytes) in files.iter().filter(|(p, _)| p.ends_with(".rs")) {
        let lines = String::from_utf8_lossy(bytes).lines().count();
        let listed = LONG_FILES.iter().any(|(file, _)| file == path);
        assert!(
            lines <= LONGEST_FILE || listed,
            "{path}: {lines} lines (at most {LONGEST_FILE}, or listed in LONG_FILES with the reason)"
        );
        assert!(
            lines > LONGEST_FILE || !listed,
            "LONG_FILES lists {path}, which has {lines} lines now: remove it"
        );
    }
}
