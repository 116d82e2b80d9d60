//! The `pipeline.toml` reference (docs/configuration.md) against the schema:
//! every key of the schema has a row, every row names a key of the schema,
//! and every default the reference shows equals the schema's.

use std::collections::{BTreeMap, BTreeSet};

use serde_json::Value;
use ternary::config::{Config, Study};
use ternary::physics::potential::{FAMILIES, Potential};

/// A study that sets every optional table once (overrides, per-potential
/// points, launch pairs, rings, gases), so that every key appears.
const EVERY_KEY: &str = r#"
[potentials]
inverse_power = [6]

[scan]
offset_min = -3.0
offset_max = 3.0
points = 5

[[scan.launch]]
name = "a"
u2 = 1.0
u3 = -1.0

[scan.overrides."<id>"]
offset_min = -1.0
offset_max = 1.0
points = 3

[engine.tolerance_per_potential]
"<id>" = 1e-10

[collisions.points_per_potential]
"<id>" = 64

[collisions.method_per_potential]
"<id>" = "sampled"

[collisions.strata_per_potential]
"<id>" = { opposite = 64, same_side = 32 }

[collisions.slow_launch_per_potential]
"<id>" = { share = 0.25, speed = 0.5 }

[evolve]
gas = "g"
times_ns = [1.0]

[[md.system]]
name = "r"
gas = "g"
final_time_ns = 1.0
runs = 2

[[gas]]
name = "g"
potential = "ipp-6"
l0_um = 1.0
eps_ev = 1.0
kt_ev = 0.1
mass_electron = 1.0
mass_amu = 1.0
density_per_um = 1.0
ring_particles = 3
ring_radius_um = 1.0

[sweep]
points_share = 0.5

[publication]
date = "2026-01-01"

[[publication.authors]]
given_names = "A"
family_names = "B"
name = "C"
orcid = "0000-0000-0000-0000"
affiliation = "D"
"#;

/// Only the required keys: everything else at its default.
const DEFAULTS: &str = r#"
[potentials]

[scan]
offset_min = -3.0
offset_max = 3.0
points = 5
launch = []
"#;

/// The schema's leaf keys of a parsed (not validated) configuration, with
/// their values; array indices are dropped (`scan.launch.name`) and the map
/// key `<id>` stands for any potential id (removed: `collisions.points_per_potential`).
fn leaves(text: &str) -> BTreeMap<String, Value> {
    let config: Config = toml::from_str(text).expect("the sample parses");
    let mut found = BTreeMap::new();
    walk(
        &serde_json::to_value(&config).unwrap(),
        String::new(),
        &mut found,
    );
    found
}

fn walk(value: &Value, path: String, found: &mut BTreeMap<String, Value>) {
    let child = |name: &str| match (path.is_empty(), name) {
        (_, "<id>") => path.clone(),
        (true, _) => name.to_string(),
        (false, _) => format!("{path}.{name}"),
    };
    match value {
        Value::Object(map) if !map.is_empty() => {
            for (name, item) in map {
                walk(item, child(name), found);
            }
        }
        Value::Array(items) if items.iter().any(Value::is_object) => {
            for item in items {
                walk(item, path.clone(), found);
            }
        }
        _ => {
            found.insert(path, value.clone());
        }
    }
}

/// One row of a reference key table: its keys and the defaults it shows.
struct Row {
    keys: Vec<String>,
    defaults: Vec<Value>,
}

/// The backticked tokens of a table cell.
fn ticked(cell: &str) -> Vec<String> {
    cell.split('`')
        .skip(1)
        .step_by(2)
        .map(ToString::to_string)
        .collect()
}

/// A token as a TOML value (`"data"`, `1e-12`, `[0]`, `0.5, 0.7`), if it is one.
fn toml_value(token: &str) -> Option<Vec<Value>> {
    let parse = |text: &str| -> Option<Value> {
        let table: toml::Table = toml::from_str(&format!("v = {text}")).ok()?;
        serde_json::to_value(&table["v"]).ok()
    };
    if token.contains(',') && !token.starts_with('[') {
        return token.split(',').map(|part| parse(part.trim())).collect();
    }
    parse(token).map(|value| vec![value])
}

/// The key tables of docs/configuration.md.
fn reference_rows() -> Vec<Row> {
    let reference = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/docs/configuration.md"
    ))
    .expect("docs/configuration.md");
    let mut rows = Vec::new();
    let mut table_prefix = String::new();
    for line in reference.lines() {
        let cells: Vec<&str> = line.split(" | ").collect();
        if !line.starts_with("| ") || cells.len() < 3 || line.starts_with("|---") {
            continue;
        }
        if cells[0] == "| key" {
            // The `[[gas]]` table names its keys without a prefix.
            table_prefix = if cells[1] == "type" {
                "gas".into()
            } else {
                String::new()
            };
            continue;
        }
        rows.push(row(cells[0], cells[1], &table_prefix));
    }
    rows
}

/// The keys of a first cell: absolute (`sweep.points`), relative to a
/// bracketed table (`[[scan.launch]]` `name`) or to the previous key's table
/// (`md.system[k].name`, `.gas`), with `[k]` and `<id>` parts removed.
fn row(key_cell: &str, type_cell: &str, table_prefix: &str) -> Row {
    let mut prefix = table_prefix.to_string();
    let mut keys = Vec::new();
    for token in ticked(key_cell) {
        let token = token.replace("[k]", "").replace(".<id>", "");
        if let Some(table) = token.strip_prefix('[') {
            prefix = table.trim_matches(|c| c == '[' || c == ']').to_string();
        } else if let Some(relative) = token.strip_prefix('.') {
            keys.push(format!("{prefix}.{relative}"));
        } else if token.contains('.') {
            prefix = token.rsplit_once('.').unwrap().0.to_string();
            keys.push(token);
        } else if prefix.is_empty() {
            keys.push(token);
        } else {
            keys.push(format!("{prefix}.{token}"));
        }
    }
    let defaults = ticked(type_cell)
        .iter()
        .filter_map(|token| toml_value(token))
        .flatten()
        .collect();
    Row { keys, defaults }
}

/// Equal as documented values: numbers to 1e-12 relative, lists elementwise.
fn same(documented: &Value, schema: &Value) -> bool {
    match (documented, schema) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
        }
        (Value::Array(a), Value::Array(b)) => {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same(x, y))
        }
        (a, b) => a == b,
    }
}

#[test]
fn every_key_has_a_reference_row_and_every_row_a_key() {
    let mut schema: BTreeSet<String> = leaves(EVERY_KEY).into_keys().collect();
    // `[potentials]` holds one list per family, whichever the sample lists.
    schema.extend(FAMILIES.iter().map(|f| format!("potentials.{}", f.key)));
    let documented: BTreeSet<String> = reference_rows().into_iter().flat_map(|r| r.keys).collect();
    let undocumented: Vec<&String> = schema.difference(&documented).collect();
    let unknown: Vec<&String> = documented.difference(&schema).collect();
    assert!(
        undocumented.is_empty() && unknown.is_empty(),
        "keys without a row in docs/configuration.md: {undocumented:?}; rows naming no key: {unknown:?}"
    );
}

#[test]
fn reference_defaults_are_the_schema_defaults() {
    let defaults = leaves(DEFAULTS);
    let mut compared = 0;
    for row in reference_rows() {
        let pairs: Vec<(&String, &Value)> = if row.defaults.len() == row.keys.len() {
            row.keys.iter().zip(&row.defaults).collect()
        } else if row.keys.len() == 1 && !row.defaults.is_empty() {
            vec![(&row.keys[0], &row.defaults[0])]
        } else {
            Vec::new()
        };
        for (key, shown) in pairs {
            let Some(default) = defaults.get(key) else {
                continue;
            };
            assert!(
                same(shown, default),
                "docs/configuration.md shows `{key}` = {shown} but the default is {default}"
            );
            compared += 1;
        }
    }
    assert!(compared >= 60, "only {compared} defaults compared");
}

/// A valid study with every section enabled: the base of the range tests.
const STUDY: &str = r#"
[store]
path = "data"

[potentials]
inverse_power = [2, 6]
lennard_jones = [0.1]

[engine]
method = "dprkn12"
tolerance = 1e-12
max_steps = 100000

[scan]
launch_length = 90.0
offset_min = -3.0
offset_max = 3.0
points = 9

[[scan.launch]]
name = "symmetric"
u2 = 1.0
u3 = -1.0

[scan.overrides.ipp-6]
points = 11

[collisions]
method = "sampled"
randomizations = 4
points = 256
same_side_fraction = 0.15
pilot_points = 64
launch_shift = 0.0
launch_spread = 0.0

[collisions.proposal]
core_weight = 0.5
core_width = 0.7
tail_weight = 0.45
tail_width = 1.0
uniform_weight = 0.05
uniform_range = 40.0

[collisions.quadrature]
coarse_step = 0.5
half_range = 3.3
halvings = 3

[collisions.points_per_potential]
"lj-0.1" = 512

[kernel]
u_prime = [0.0, 0.5]
density = [0.0, 1e-3]
window = 0.2
bin_width = 5e-5
launch_length = 90.0
kick_floor = 1e-10
fit_range = [2e-4, 0.05]

[sweep]
u_prime_min = -3.0
u_prime_max = 3.0
points = 5
balance_separations = [0.02, 0.05]
balance_bin_width = 0.005
launch_spread = 2.0

[convergence]
enabled = true
inverse_power = 6
densities = [1e-3]
offset_bounds = [3.0, 30.0]
tolerances = [1e-10]
bin_widths = [2e-4, 1e-3]

[evolve]
enabled = true
potential = "ipp-6"
u_prime = 0.0
times = [0.1, 1.0]
early_times = [1e-3]
early_bin_width = 1.05e-3
early_range = 0.3
velocity_range = 2.0
grid_step = 0.1
gas = "ring"
times_ns = [100.0]

[md]
enabled = true
runs = 4
neighbours = 3
tolerance = 1e-10
window = 0.2
bin_width = 0.01
samples = 3
sample_spread = 0.02
start_band = 0.1

[[md.system]]
name = "ring"
gas = "ring"
u_prime = 0.0
final_time_ns = 100.0
runs = 8

[[gas]]
name = "ring"
potential = "ipp-6"
l0_um = 1.0
eps_ev = 1.0
kt_ev = 0.1
mass_electron = 1.0
ring_particles = 21
ring_radius_um = 1600.0

[[gas]]
name = "lj"
potential = "lj-0.1"
l0_um = 1.0
eps_ev = 1.0
kt_ev = 0.1
mass_amu = 4.0
density_per_um = 5e-4

[slurm]
shards = 16
cpus_per_task = 4
mem = "8G"
account = "physics"
partition = "normal,long"
qos = "high"
time = "1:00:00"
merge_time = "4:00:00"
max_parallel = 8
sbatch_args = ["--exclusive", "--constraint=avx2"]
"#;

/// Each `(from, to, key)`: replacing `from` by `to` in [`STUDY`] is rejected
/// with an error naming `key` and a line inside `to`.
fn rejects(cases: &[(&str, &str, &str)]) {
    let path = std::path::Path::new("pipeline.toml");
    Study::parse(path, STUDY).expect("the base study is valid");
    for &(from, to, key) in cases {
        assert_eq!(STUDY.matches(from).count(), 1, "`{from}` is not unique");
        let text = STUDY.replace(from, to);
        let error = Study::parse(path, &text).expect_err(&format!("{to}: accepted"));
        assert_eq!(error.key, key, "{to}: {error}");
        let first = STUDY[..STUDY.find(from).unwrap()].matches('\n').count() + 1;
        let last = first + to.matches('\n').count();
        let line = error
            .line
            .unwrap_or_else(|| panic!("{to}: no line in {error}"));
        assert!(
            (first..=last).contains(&line),
            "{to}: line {line} in {error}"
        );
    }
}

#[test]
fn store_section_rejects_bad_values() {
    rejects(&[("path = \"data\"", "path = 5", "store.path")]);
}

#[test]
fn potentials_section_rejects_bad_values() {
    rejects(&[
        (
            "inverse_power = [2, 6]",
            "inverse_power = [2, 1]",
            "potentials.inverse_power[1]",
        ),
        (
            "inverse_power = [2, 6]",
            "inverse_power = [2, 101]",
            "potentials.inverse_power[1]",
        ),
        (
            "inverse_power = [2, 6]",
            "inverse_power = [2, 2]",
            "potentials.inverse_power[1]",
        ),
        (
            "lennard_jones = [0.1]",
            "lennard_jones = [0.0]",
            "potentials.lennard_jones[0]",
        ),
        (
            "lennard_jones = [0.1]",
            "lennard_jones = [1e4]",
            "potentials.lennard_jones[0]",
        ),
        (
            "inverse_power = [2, 6]",
            "inverse_power = [2, 6]\nbogus = 1",
            "potentials.bogus",
        ),
        (
            "inverse_power = [2, 6]",
            "inverse_power = [2, 6]\nmorse_like = [1.0]",
            "potentials.morse_like",
        ),
        (
            "inverse_power = [2, 6]",
            "inverse_power = [2, \"six\"]",
            "potentials.inverse_power[1]",
        ),
        (
            "inverse_power = [2, 6]",
            "inverse_power = [2, 6]\nmorse = [{ theta = 1.0, x0 = 2.0 }]",
            "potentials.morse[0]",
        ),
        (
            "inverse_power = [2, 6]",
            "inverse_power = [2, 6]\nmorse = [{ theta = 1.0, d0 = 4.0 }]",
            "potentials.morse[0]",
        ),
    ]);
}

#[test]
fn engine_section_rejects_bad_values() {
    rejects(&[
        ("method = \"dprkn12\"", "method = \"rk4\"", "engine.method"),
        (
            "tolerance = 1e-12\nmax",
            "tolerance = 0.01\nmax",
            "engine.tolerance",
        ),
        (
            "tolerance = 1e-12\nmax",
            "tolerance = 0.0\nmax",
            "engine.tolerance",
        ),
        ("max_steps = 100000", "max_steps = 0", "engine.max_steps"),
        (
            "[collisions]",
            "[engine.tolerance_per_potential]\n\"ipp-7\" = 1e-10\n\n[collisions]",
            "engine.tolerance_per_potential.ipp-7",
        ),
        (
            "[collisions]",
            "[engine.tolerance_per_potential]\n\"ipp-6\" = 0.01\n\n[collisions]",
            "engine.tolerance_per_potential.ipp-6",
        ),
    ]);
}

/// The test study with `table` inserted before `anchor`, and the study as it is.
fn with_and_without(anchor: &str, table: &str) -> (Study, Study) {
    let changed = STUDY.replace(anchor, &format!("{table}\n\n{anchor}"));
    assert_ne!(changed, STUDY);
    let path = std::path::Path::new("pipeline.toml");
    (
        Study::parse(path, &changed).expect("valid"),
        Study::parse(path, STUDY).expect("valid"),
    )
}

/// `engine.tolerance_per_potential` sets the tolerance of every scene of
/// one potential (its main and sweep sets, its scans, its dissociation) and
/// of nothing else: the other potentials keep `engine.tolerance`, and the
/// convergence study varies its own tolerances around the potential's.
#[test]
fn tolerance_per_potential_sets_every_scene_of_that_potential() {
    let (study, global) = with_and_without(
        "[collisions]",
        "[engine.tolerance_per_potential]\n\"lj-0.1\" = 1e-9",
    );
    let own = Potential::lennard_jones(0.1);
    let wide = |study: &Study, potential| ternary::plan::wide_collisions(study, potential).1;
    let tolerances = |study: &Study, potential| {
        [
            study.collisions_params(potential).engine.tolerance,
            wide(study, potential)
                .expect("a sweep set")
                .engine
                .tolerance,
            study.scan_params(potential).engine.tolerance,
            study
                .dissociation_params(potential)
                .map_or(0.0, |d| d.engine.tolerance),
        ]
    };
    assert_eq!(tolerances(&study, own), [1e-9; 4]);
    assert_ne!(global.collisions_params(own).engine.tolerance, 1e-9);
    for other in study.potentials().into_iter().filter(|p| *p != own) {
        assert_eq!(
            tolerances(&study, other),
            tolerances(&global, other),
            "{}",
            other.id()
        );
    }
}

#[test]
fn scan_section_rejects_bad_values() {
    rejects(&[
        (
            "launch_length = 90.0\noffset",
            "launch_length = 0.0\noffset",
            "scan.launch_length",
        ),
        ("offset_min = -3.0", "offset_min = nan", "scan.offset_min"),
        ("offset_max = 3.0", "offset_max = inf", "scan.offset_max"),
        ("offset_max = 3.0", "offset_max = -4.0", "scan.offset_max"),
        ("points = 9", "points = 2", "scan.points"),
        ("points = 9", "points = 1048577", "scan.points"),
        ("u2 = 1.0", "u2 = 0.0", "scan.launch[0].u2"),
        ("u3 = -1.0", "u3 = 1.0", "scan.launch[0].u3"),
        ("name = \"symmetric\"", "name = \"\"", "scan.launch[0].name"),
        (
            "u3 = -1.0\n",
            "u3 = -1.0\n\n[[scan.launch]]\nname = \"symmetric\"\nu2 = 1.0\nu3 = -2.0\n",
            "scan.launch[1].name",
        ),
        (
            "[scan.overrides.ipp-6]",
            "[scan.overrides.ipp-7]",
            "scan.overrides.ipp-7",
        ),
        ("points = 11", "points = 2", "scan.overrides.ipp-6.points"),
    ]);
}

#[test]
fn collisions_section_rejects_bad_values() {
    rejects(&[
        (
            "randomizations = 4",
            "randomizations = 1",
            "collisions.randomizations",
        ),
        (
            "randomizations = 4",
            "randomizations = 1025",
            "collisions.randomizations",
        ),
        ("points = 256", "points = 1", "collisions.points"),
        ("points = 256", "points = 16777216", "collisions.points"),
        (
            "same_side_fraction = 0.15",
            "same_side_fraction = 1.0",
            "collisions.same_side_fraction",
        ),
        (
            "pilot_points = 64",
            "pilot_points = 5",
            "collisions.pilot_points",
        ),
        (
            "pilot_points = 64",
            "pilot_points = 1048577",
            "collisions.pilot_points",
        ),
        (
            "launch_shift = 0.0",
            "launch_shift = 4.0",
            "collisions.launch_shift",
        ),
        (
            "launch_spread = 0.0\n",
            "launch_spread = -1.0\n",
            "collisions.launch_spread",
        ),
        (
            "core_weight = 0.5",
            "core_weight = -0.5",
            "collisions.proposal.core_weight",
        ),
        (
            "tail_weight = 0.45",
            "tail_weight = 0.0",
            "collisions.proposal.tail_weight",
        ),
        (
            "core_width = 0.7",
            "core_width = 0.0",
            "collisions.proposal.core_width",
        ),
        (
            "uniform_range = 40.0",
            "uniform_range = inf",
            "collisions.proposal.uniform_range",
        ),
        (
            "method = \"sampled\"",
            "method = \"gauss\"",
            "collisions.method",
        ),
        (
            "coarse_step = 0.5",
            "coarse_step = 0.0",
            "collisions.quadrature.coarse_step",
        ),
        (
            "half_range = 3.3",
            "half_range = 20.0",
            "collisions.quadrature.half_range",
        ),
        (
            "halvings = 3",
            "halvings = 3\nend_kick = 0.0",
            "collisions.quadrature.end_kick",
        ),
        (
            "halvings = 3",
            "halvings = 3\nend_kick = 0.01",
            "collisions.quadrature.end_kick",
        ),
        (
            "halvings = 3",
            "halvings = 9",
            "collisions.quadrature.halvings",
        ),
        (
            "halvings = 3",
            "halvings = 0",
            "collisions.quadrature.halvings",
        ),
        (
            "\"lj-0.1\" = 512",
            "\"lj-0.1\" = 1",
            "collisions.points_per_potential.lj-0.1",
        ),
        (
            "\"lj-0.1\" = 512",
            "\"lj-0.2\" = 512",
            "collisions.points_per_potential.lj-0.2",
        ),
        (
            "\"lj-0.1\" = 512",
            "\"lj-0.1\" = 512\n\n[collisions.method_per_potential]\n\"ipp-5\" = \"sampled\"",
            "collisions.method_per_potential.ipp-5",
        ),
    ]);
}

/// `method = "quadrature"` with the Lennard-Jones potential kept sampled: the
/// inverse power law's plan integrates offsets, the Lennard-Jones one samples them.
#[test]
fn methods_can_differ_per_potential() {
    let text = STUDY
        .replace("method = \"sampled\"", "method = \"quadrature\"")
        .replace(
            "\"lj-0.1\" = 512",
            "\"lj-0.1\" = 512\n\n[collisions.method_per_potential]\n\"lj-0.1\" = \"sampled\"",
        );
    let study = Study::parse(std::path::Path::new("pipeline.toml"), &text).expect("valid");
    for potential in &study.potentials() {
        let engine = study.engine(*potential);
        let plan = study.config.collisions.params(*potential, engine).sampling;
        let sampled = potential.family().has_well();
        assert_eq!(plan.offsets.is_sampled(), sampled, "{}", potential.id());
    }
}

/// The studies the repository ships (the default, the publication study and
/// those docs/ runs: `docs/studies/*.toml`) load and validate, so `ternary
/// run` on them cannot stop at the configuration.
#[test]
fn shipped_studies_are_valid() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("pipeline.toml"), root.join("publication.toml")];
    let studies = std::fs::read_dir(root.join("docs/studies")).expect("docs/studies");
    files.extend(
        studies
            .map(|entry| entry.expect("entry").path())
            .filter(|path| path.extension().is_some_and(|e| e == "toml")),
    );
    assert!(files.len() >= 4, "{files:?}");
    for path in files {
        Study::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    }
}

/// `publication.toml` integrates every potential's offsets by quadrature
/// (the inverse power laws and, wells and all, Lennard-Jones), and it gives
/// every estimate at least 3x smaller errors than `pipeline.toml`: 9x the
/// launch pairs (errors falling as `N^-1/2`), or for an inverse power law,
/// whose quasi-random errors per randomization fall as `N^-1` (`n = 6`'s
/// main set doubled: 2.7x, docs/benchmarks.md), the pairs per
/// randomization times the root of the randomizations at least 3x; 9x the
/// simulated MD time (runs times duration).
#[test]
fn the_publication_study_integrates_every_potential_by_quadrature() {
    use ternary::physics::sampling::OffsetIntegration;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let publication = Study::load(&root.join("publication.toml")).expect("valid");
    let default = Study::load(&root.join("pipeline.toml")).expect("valid");
    for potential in publication.potentials() {
        let id = potential.id();
        let params = publication.collisions_params(potential);
        let base = default.collisions_params(potential);
        let points = f64::from(params.points) / f64::from(base.points);
        let randomizations =
            f64::from(params.sampling.randomizations) / f64::from(base.sampling.randomizations);
        let error_ratio = if potential.family().has_well() {
            (points * randomizations).sqrt()
        } else {
            points * randomizations.sqrt()
        };
        assert!(error_ratio >= 3.0, "{id}: errors {error_ratio:.2}x smaller");
        for (study, p) in [("publication", &params), ("default", &base)] {
            assert!(
                matches!(p.sampling.offsets, OffsetIntegration::Quadrature(_)),
                "{id} is sampled in the {study} study"
            );
        }
    }
    for potential in publication.potentials() {
        if let Some(params) = publication.dissociation_params(potential) {
            let base = default.dissociation_params(potential).expect("lj in both");
            let scenes = |p: &ternary::config::DissociationParams| p.points * p.randomizations;
            assert!(scenes(&params) >= 9 * scenes(&base), "{}", potential.id());
        }
    }
    let simulated = |ring: &ternary::config::MdParams| f64::from(ring.runs) * ring.final_time_ns;
    for (ring, base) in publication.md_params().iter().zip(default.md_params()) {
        assert_eq!(ring.name, base.name);
        assert!(simulated(ring) >= 9.0 * simulated(&base), "{}", ring.name);
    }
}

/// `sweep.points_share` sizes the sweep's own scene set and leaves the
/// kernel's (256 points, the same-side share rounded to a power of two).
#[test]
fn sweep_points_share_sizes_only_the_sweep_set() {
    let text = STUDY.replace(
        "launch_spread = 2.0",
        "launch_spread = 2.0\npoints_share = 0.25",
    );
    let study = Study::parse(std::path::Path::new("pipeline.toml"), &text).expect("valid");
    let potential = Potential::inverse_power(6.0);
    let (_, wide) = ternary::plan::wide_collisions(&study, potential);
    let wide = wide.expect("the sweep has its own scene set");
    assert_eq!(wide.points, 64);
    assert_eq!(wide.sampling.launch.spread, 2.0);
    assert!(wide.sampling.opposite_points + wide.sampling.same_side_points <= 96);
    let kernel = study.collisions_params(potential);
    assert_eq!(kernel.points, 256);
    assert!(kernel.sampling.opposite_points >= 128);
    // A per-potential count is shared the same way.
    let lennard_jones = Potential::lennard_jones(0.1);
    let (_, wide) = ternary::plan::wide_collisions(&study, lennard_jones);
    assert_eq!(wide.expect("own set").points, 128);
}

/// `collisions.strata_per_potential` fixes the split of the potential's main
/// set (no pilot) and of nothing else: the sweep's own set and the sets tuned
/// to one `u'` keep the pilot and their points.
#[test]
fn strata_per_potential_fix_only_the_main_set() {
    let (study, piloted) = with_and_without(
        "[collisions.proposal]",
        "[collisions.strata_per_potential]\n\"ipp-6\" = { opposite = 128, same_side = 64 }",
    );
    let potential = Potential::inverse_power(6.0);
    let main = study.collisions_params(potential);
    assert_eq!(
        (
            main.sampling.opposite_points,
            main.sampling.same_side_points
        ),
        (128, 64)
    );
    assert_eq!((main.points, main.pilot_points), (192, 0));
    assert_eq!(main.launches().pilot_points, 0);
    assert!(piloted.collisions_params(potential).pilot_points > 0);
    let wide = |study: &Study| ternary::plan::wide_collisions(study, potential).1;
    assert_eq!(wide(&study), wide(&piloted));
    assert!(wide(&study).expect("own set").pilot_points > 0);
    // Another potential keeps the pilot.
    let other = Potential::lennard_jones(0.1);
    assert_eq!(
        study.collisions_params(other),
        piloted.collisions_params(other)
    );
}

/// `collisions.slow_launch_per_potential` sets the slow stratum of the
/// potential's main set and of nothing else: its sweep set and the other
/// potentials keep the global one.
#[test]
fn slow_launch_per_potential_sets_only_the_main_set() {
    let (study, global) = with_and_without(
        "[collisions.proposal]",
        "[collisions.slow_launch_per_potential]\n\"ipp-6\" = { share = 0.25, speed = 0.5 }",
    );
    let potential = Potential::inverse_power(6.0);
    let launch = study.collisions_params(potential).sampling.launch;
    assert_eq!((launch.slow_share, launch.slow_speed), (0.25, 0.5));
    let global_launch = global.collisions_params(potential).sampling.launch;
    assert_ne!(global_launch.slow_speed, 0.5);
    let wide = |study: &Study| ternary::plan::wide_collisions(study, potential).1;
    assert_eq!(wide(&study), wide(&global));
    let other = Potential::lennard_jones(0.1);
    assert_eq!(
        study.collisions_params(other),
        global.collisions_params(other)
    );
}

/// `sweep.randomizations` splits only the sweep's own scene set, and the
/// sweep's quadrature takes one halving more than the kernel's.
#[test]
fn sweep_randomizations_and_halvings_set_only_the_sweep_set() {
    use ternary::physics::sampling::OffsetIntegration;
    let text = STUDY
        .replace(
            "launch_spread = 2.0",
            "launch_spread = 2.0\nrandomizations = 12",
        )
        .replace(
            "[collisions.points_per_potential]",
            "[collisions.method_per_potential]\n\"ipp-6\" = \"quadrature\"\n\n[collisions.points_per_potential]",
        );
    let study = Study::parse(std::path::Path::new("pipeline.toml"), &text).expect("valid");
    let potential = Potential::inverse_power(6.0);
    let wide = ternary::plan::wide_collisions(&study, potential)
        .1
        .expect("own set");
    let kernel = study.collisions_params(potential);
    assert_eq!(wide.sampling.randomizations, 12);
    assert_eq!(kernel.sampling.randomizations, 4);
    let halvings = |offsets: &OffsetIntegration| match offsets {
        OffsetIntegration::Quadrature(rule) => rule.halvings,
        _ => panic!("ipp-6 is integrated by quadrature"),
    };
    assert_eq!(halvings(&kernel.sampling.offsets), 3);
    assert_eq!(halvings(&wide.sampling.offsets), 4);
}

#[test]
fn kernel_section_rejects_bad_values() {
    rejects(&[
        ("u_prime = [0.0, 0.5]", "u_prime = []", "kernel.u_prime"),
        (
            "u_prime = [0.0, 0.5]",
            "u_prime = [0.0, 3.5]",
            "kernel.u_prime[1]",
        ),
        (
            "density = [0.0, 1e-3]",
            "density = [0.0, 0.2]",
            "kernel.density[1]",
        ),
        ("bin_width = 5e-5", "bin_width = 0.0", "kernel.bin_width"),
        ("bin_width = 5e-5", "bin_width = 1e-8", "kernel.bin_width"),
        (
            "window = 0.2\nbin_width = 5e-5",
            "window = 1e-4\nbin_width = 5e-5",
            "kernel.bin_width",
        ),
        // Blamed on kernel.window, without a line (issue 54).
        ("bin_width = 5e-5", "bin_width = 1e300", "kernel.bin_width"),
        (
            "launch_length = 90.0\nkick",
            "launch_length = 0.0\nkick",
            "kernel.launch_length",
        ),
        (
            "kick_floor = 1e-10",
            "kick_floor = 1e-4",
            "kernel.kick_floor",
        ),
        (
            "fit_range = [2e-4, 0.05]",
            "fit_range = [0.05, 2e-4]",
            "kernel.fit_range",
        ),
        // A third value was silently dropped; a huge window named bin_width
        // (not written) and had no line.
        (
            "fit_range = [2e-4, 0.05]",
            "fit_range = [2e-4, 0.05, 1]",
            "kernel.fit_range",
        ),
        (
            "window = 0.2\nbin_width = 5e-5",
            "window = 1e300\nbin_width = 5e-5",
            "kernel.window",
        ),
    ]);
}

/// Accepted before and wrong: a licence that is no SPDX id, launch speeds
/// and offsets for which every scene fails; numbers in messages print in
/// exponent form, not as 301 digits.
#[test]
fn unbounded_or_unknown_values_are_refused_with_short_numbers() {
    let licence =
        |id: &str| format!("density_per_um = 5e-4\n\n[publication]\nlicense = \"{id}\"\n");
    rejects(&[
        (
            "density_per_um = 5e-4\n",
            &licence("NOT-A-LICENSE"),
            "publication.license",
        ),
        ("u2 = 1.0", "u2 = 1e300", "scan.launch[0].u2"),
        ("offset_max = 3.0", "offset_max = 1e300", "scan.offset_max"),
        (
            "offset_min = -3.0",
            "offset_min = -2000.0",
            "scan.offset_min",
        ),
    ]);
    let path = std::path::Path::new("pipeline.toml");
    for text in [
        STUDY.replace("u2 = 1.0", "u2 = 1e300"),
        STUDY.replace("window = 0.2", "window = 1e300"),
    ] {
        let message = Study::parse(path, &text).unwrap_err().to_string();
        assert!(
            message.contains("1e300") && !message.contains("0000000000"),
            "{message}"
        );
    }
    for id in ["CC0-1.0", "cc-by-sa-4.0", "ODbL-1.0", "MIT"] {
        let text = STUDY.replace("density_per_um = 5e-4\n", &licence(id));
        Study::parse(path, &text).unwrap_or_else(|e| panic!("{id}: {e}"));
    }
}

#[test]
fn sweep_section_rejects_bad_values() {
    rejects(&[
        (
            "u_prime_max = 3.0",
            "u_prime_max = -4.0",
            "sweep.u_prime_max",
        ),
        (
            "u_prime_min = -3.0",
            "u_prime_min = -6.0",
            "sweep.u_prime_min",
        ),
        ("points = 5\nbalance", "points = 2\nbalance", "sweep.points"),
        (
            "points = 5\nbalance",
            "points = 1002\nbalance",
            "sweep.points",
        ),
        (
            "launch_spread = 2.0",
            "launch_spread = 4.0",
            "sweep.launch_spread",
        ),
        (
            "launch_spread = 2.0",
            "launch_spread = 2.0\npoints_share = 0.0",
            "sweep.points_share",
        ),
        (
            "launch_spread = 2.0",
            "launch_spread = 2.0\npoints_share = 1.5",
            "sweep.points_share",
        ),
        (
            "launch_spread = 2.0",
            "launch_spread = 2.0\nrandomizations = 1",
            "sweep.randomizations",
        ),
        (
            "launch_spread = 2.0",
            "launch_spread = 0.0\nrandomizations = 32",
            "sweep.randomizations",
        ),
        (
            "balance_bin_width = 0.005",
            "balance_bin_width = 0.0",
            "sweep.balance_bin_width",
        ),
        (
            "balance_separations = [0.02, 0.05]",
            "balance_separations = []",
            "sweep.balance_separations",
        ),
        (
            "balance_separations = [0.02, 0.05]",
            "balance_separations = [0.02, 0.6]",
            "sweep.balance_separations[1]",
        ),
    ]);
}

#[test]
fn convergence_section_rejects_bad_values() {
    rejects(&[
        (
            "inverse_power = 6",
            "inverse_power = 8",
            "convergence.inverse_power",
        ),
        (
            "densities = [1e-3]",
            "densities = [0.2]",
            "convergence.densities[0]",
        ),
        (
            "offset_bounds = [3.0, 30.0]",
            "offset_bounds = [0.0, 30.0]",
            "convergence.offset_bounds[0]",
        ),
        (
            "tolerances = [1e-10]",
            "tolerances = [1e-2]",
            "convergence.tolerances[0]",
        ),
        (
            "tolerances = [1e-10]",
            "tolerances = [1e-10, 1e-10]",
            "convergence.tolerances[1]",
        ),
        (
            "tolerances = [1e-10]",
            "tolerances = [1e-10]\ntolerance_share = 1.5",
            "convergence.tolerance_share",
        ),
        (
            "bin_widths = [2e-4, 1e-3]",
            "bin_widths = [2e-4, 0.2]",
            "convergence.bin_widths[1]",
        ),
    ]);
}

#[test]
fn evolve_section_rejects_bad_values() {
    rejects(&[
        (
            "potential = \"ipp-6\"\nu_prime",
            "potential = \"ipp-7\"\nu_prime",
            "evolve.potential",
        ),
        ("grid_step = 0.1", "grid_step = 0.0", "evolve.grid_step"),
        ("grid_step = 0.1", "grid_step = 1e-3", "evolve.grid_step"),
        (
            "velocity_range = 2.0",
            "velocity_range = 0.1",
            "evolve.velocity_range",
        ),
        (
            "velocity_range = 2.0",
            "velocity_range = 6.0",
            "evolve.velocity_range",
        ),
        (
            "u_prime = 0.0\ntimes",
            "u_prime = 0.05\ntimes",
            "evolve.u_prime",
        ),
        (
            "early_bin_width = 1.05e-3",
            "early_bin_width = 1e-3",
            "evolve.early_bin_width",
        ),
        (
            "early_bin_width = 1.05e-3",
            "early_bin_width = 1.5e-7",
            "evolve.early_bin_width",
        ),
        (
            "times = [0.1, 1.0]",
            "times = [0.1, -1.0]",
            "evolve.times[1]",
        ),
        (
            "early_times = [1e-3]",
            "early_times = [0.0]",
            "evolve.early_times[0]",
        ),
        (
            "gas = \"ring\"\ntimes_ns",
            "gas = \"lj\"\ntimes_ns",
            "evolve.gas",
        ),
        (
            "times_ns = [100.0]",
            "times_ns = [-1.0]",
            "evolve.times_ns[0]",
        ),
    ]);
}

/// Whatever `slurm submit` writes into `#SBATCH` lines is in Slurm's
/// syntax (no newline, space or shell character), and counts are in range.
#[test]
fn slurm_section_rejects_bad_values() {
    rejects(&[
        ("shards = 16", "shards = 1", "slurm.shards"),
        ("shards = 16", "shards = 4097", "slurm.shards"),
        (
            "cpus_per_task = 4",
            "cpus_per_task = 0",
            "slurm.cpus_per_task",
        ),
        ("mem = \"8G\"", "mem = \"8 GB\"", "slurm.mem"),
        (
            "account = \"physics\"",
            "account = \"a\\necho x\"",
            "slurm.account",
        ),
        (
            "partition = \"normal,long\"",
            "partition = \"normal,\"",
            "slurm.partition",
        ),
        ("qos = \"high\"", "qos = \"$(id)\"", "slurm.qos"),
        ("time = \"1:00:00\"", "time = \"1h\"", "slurm.time"),
        (
            "merge_time = \"4:00:00\"",
            "merge_time = \"4 hours\"",
            "slurm.merge_time",
        ),
        ("max_parallel = 8", "max_parallel = 0", "slurm.max_parallel"),
        (
            "sbatch_args = [\"--exclusive\", \"--constraint=avx2\"]",
            "sbatch_args = [\"--exclusive\", \"--constraint=avx2;rm\"]",
            "slurm.sbatch_args[1]",
        ),
    ]);
}

#[test]
fn md_section_rejects_bad_values() {
    rejects(&[
        ("runs = 4", "runs = 1", "md.runs"),
        ("runs = 4", "runs = 65537", "md.runs"),
        ("neighbours = 3", "neighbours = 65", "md.neighbours"),
        (
            "tolerance = 1e-10\nwindow",
            "tolerance = 1e-5\nwindow",
            "md.tolerance",
        ),
        ("bin_width = 0.01", "bin_width = 0.5", "md.bin_width"),
        ("samples = 3", "samples = 0", "md.samples"),
        (
            "sample_spread = 0.02",
            "sample_spread = 0.5",
            "md.sample_spread",
        ),
        ("start_band = 0.1", "start_band = 0.0", "md.start_band"),
        (
            "gas = \"ring\"\nu_prime",
            "gas = \"lj\"\nu_prime",
            "md.system[0].gas",
        ),
        (
            "final_time_ns = 100.0",
            "final_time_ns = 0.0",
            "md.system[0].final_time_ns",
        ),
        (
            "final_time_ns = 100.0",
            "final_time_ns = 1e12",
            "md.system[0].final_time_ns",
        ),
        (
            "u_prime = 0.0\nfinal",
            "u_prime = nan\nfinal",
            "md.system[0].u_prime",
        ),
        ("runs = 8", "runs = 1", "md.system[0].runs"),
    ]);
}

#[test]
fn gas_section_rejects_bad_values() {
    rejects(&[
        ("name = \"lj\"", "name = \"\"", "gas[1].name"),
        (
            "potential = \"lj-0.1\"\nl0",
            "potential = \"lj-1\"\nl0",
            "gas[1].potential",
        ),
        (
            "kt_ev = 0.1\nmass_amu",
            "kt_ev = 0.2\nmass_amu",
            "gas[1].kt_ev",
        ),
        (
            "mass_amu = 4.0",
            "mass_amu = 4.0\nmass_electron = 1.0",
            "gas[1].mass_electron",
        ),
        (
            "density_per_um = 5e-4",
            "density_per_um = 0.0",
            "gas[1].density_per_um",
        ),
        (
            "density_per_um = 5e-4",
            "density_per_um = 1e3",
            "gas[1].density_per_um",
        ),
        (
            "ring_particles = 21",
            "ring_particles = 2",
            "gas[0].ring_particles",
        ),
        (
            "ring_radius_um = 1600.0",
            "ring_radius_um = 0.0",
            "gas[0].ring_radius_um",
        ),
        (
            "ring_radius_um = 1600.0",
            "ring_radius_um = 1e-3",
            "gas[0].ring_radius_um",
        ),
        ("name = \"lj\"", "name = \"ring\"", "gas[1].name"),
    ]);
}

/// Every table with documented defaults accepts any one of its keys alone:
/// the study of the required keys plus one key, at its default, in its own
/// table (today `[collisions.quadrature]` with only `halvings` and `[store]`
/// with only `path` were refused: "missing field").
#[test]
fn every_table_with_defaults_accepts_any_one_of_its_keys() {
    let base = DEFAULTS
        .replace("[potentials]\n", "[potentials]\ninverse_power = [6]\n")
        .replace("launch = []\n", "");
    let base = format!("{base}\n[[scan.launch]]\nname = \"a\"\nu2 = 1.0\nu3 = -1.0\n");
    let path = std::path::Path::new("pipeline.toml");
    Study::parse(path, &base).expect("the base study is valid");
    let mut tables = BTreeSet::new();
    for (key, value) in leaves(DEFAULTS) {
        // Top-level arrays of tables (`[[gas]]`) have no defaults.
        let Some((table, name)) = key.rsplit_once('.') else {
            continue;
        };
        if ["potentials", "scan"].contains(&table) || value.is_null() {
            continue;
        }
        let value = toml::Value::try_from(&value).expect("a TOML value");
        let text = format!("{base}\n[{table}]\n{name} = {value}\n");
        if let Err(error) = Study::parse(path, &text) {
            panic!("[{table}] with only `{name} = {value}`: {error}");
        }
        tables.insert(table.to_string());
    }
    for table in [
        "store",
        "collisions.quadrature",
        "collisions.proposal",
        "md",
        "evolve",
    ] {
        assert!(tables.contains(table), "{table} not covered: {tables:?}");
    }
}

/// A name from the configuration became a path: `[[md.system]] name =
/// "../../../notes"` made `run --only md` replace the user's `notes.json`,
/// an absolute name wrote anywhere, `a/b` created folders, and a 300-character
/// name failed after the compute (issue 54, item 1). Every name that becomes
/// part of a path is refused at load by one rule, with its key and line.
#[test]
fn names_that_could_be_paths_are_refused_at_load() {
    let long = "a".repeat(300);
    let bad = [
        "../../../notes",
        "/dir/precious",
        "a/b",
        ".hidden",
        "..",
        "tab\\there",
        "new\\nline",
        "sp ace",
        long.as_str(),
    ];
    for name in bad {
        rejects(&[
            (
                "name = \"symmetric\"",
                &format!("name = \"{name}\""),
                "scan.launch[0].name",
            ),
            (
                "[[md.system]]\nname = \"ring\"",
                &format!("[[md.system]]\nname = \"{name}\""),
                "md.system[0].name",
            ),
            (
                "[[gas]]\nname = \"lj\"",
                &format!("[[gas]]\nname = \"{name}\""),
                "gas[1].name",
            ),
        ]);
    }
    let path = std::path::Path::new("pipeline.toml");
    let error = Study::parse(
        path,
        &STUDY.replace(
            "[[md.system]]\nname = \"ring\"",
            "[[md.system]]\nname = \"a/../x\"",
        ),
    )
    .unwrap_err();
    assert!(error.message.contains("`/`"), "{error}");
    for good in ["N41_R1600", "ring-2.5+x", "He.4"] {
        let text = STUDY.replace(
            "[[md.system]]\nname = \"ring\"",
            &format!("[[md.system]]\nname = \"{good}\""),
        );
        Study::parse(path, &text).unwrap_or_else(|e| panic!("{good}: {e}"));
    }
}

/// Planning grew faster than linearly with the number of potentials
/// (`status` took 100 s with 4,000): a study lists at most 128.
#[test]
fn the_number_of_potentials_is_bounded() {
    let many: Vec<String> = (0..200)
        .map(|k| format!("{}", 3.0 + 0.01 * k as f64))
        .collect();
    let text = STUDY.replacen(
        "inverse_power = [",
        &format!("inverse_power = [{}, ", many.join(", ")),
        1,
    );
    let error = Study::parse(std::path::Path::new("pipeline.toml"), &text).unwrap_err();
    assert_eq!(error.key, "potentials", "{error}");
    assert!(error.message.contains("more than 128"), "{error}");
    // The default study with 128 potentials is planned in well under a
    // second (0.14 s measured; 1,000 took 5.9 s before the bound).
    let default_study = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("pipeline.toml"),
    )
    .unwrap();
    let listed = "inverse_power = [2, 4, 6, 8, 10, 12]";
    assert_eq!(default_study.matches(listed).count(), 1);
    let extra: Vec<String> = (0..109)
        .map(|k| format!("{}", 12.5 + 0.1 * k as f64))
        .collect();
    let widest = default_study.replace(
        listed,
        &format!("inverse_power = [2, 4, 6, 8, 10, 12, {}]", extra.join(", ")),
    );
    let dir = std::env::temp_dir().join(format!("ternary-widest-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let config = dir.join("pipeline.toml");
    std::fs::write(&config, widest).unwrap();
    let started = std::time::Instant::now();
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_ternary"))
        .arg("--config")
        .arg(&config)
        .arg("status")
        .output()
        .unwrap();
    let elapsed = started.elapsed();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    assert!(
        elapsed < std::time::Duration::from_secs(5),
        "status took {elapsed:?}"
    );
}

/// Values that loaded and then panicked, hung or failed late with an
/// internal message (issue 54, items 5-8): each is refused at load, naming
/// its key and line.
#[test]
fn values_that_panicked_or_hung_are_refused_at_load() {
    rejects(&[
        // "capacity overflow" (exit 101), and a 1.6 GB allocation at 1e-9.
        ("bin_width = 0.01", "bin_width = 1e-300", "md.bin_width"),
        ("bin_width = 0.01", "bin_width = 1e-9", "md.bin_width"),
        // Blamed on md.bin_width.
        (
            "window = 0.2\nbin_width = 0.01",
            "window = -0.2\nbin_width = 0.01",
            "md.window",
        ),
        // Ran past 90 s: the estimate ignored u'.
        (
            "u_prime = 0.0\nfinal",
            "u_prime = 1e300\nfinal",
            "md.system[0].u_prime",
        ),
        (
            "u_prime = 0.0\nfinal",
            "u_prime = 1e6\nfinal",
            "md.system[0].u_prime",
        ),
        // "Column 'h_tagged' is declared as non-nullable".
        (
            "times = [0.1, 1.0]",
            "times = [0.1, 1e300]",
            "evolve.times[1]",
        ),
        (
            "early_times = [1e-3]",
            "early_times = [1e300]",
            "evolve.early_times[0]",
        ),
        (
            "times_ns = [100.0]",
            "times_ns = [1e300]",
            "evolve.times_ns",
        ),
        // Every scan scene failed with exit 0; "launch_delay holds an infinite value".
        ("u3 = -1.0", "u3 = -1e-300", "scan.launch[0].u3"),
        ("u3 = -1.0", "u3 = -5e-324", "scan.launch[0].u3"),
        // "figure table: empty fit table".
        (
            "tolerance = 1e-12",
            "tolerance = 5e-324",
            "engine.tolerance",
        ),
    ]);
}

/// The values the fuzz test puts in place of each key's value: wrong types,
/// zero, negatives, tiny and huge numbers, non-numbers, huge strings and
/// names that are paths.
fn mutations() -> Vec<toml::Value> {
    use toml::Value as V;
    vec![
        V::String("x".into()),
        V::Boolean(true),
        V::Integer(0),
        V::Integer(-1),
        V::Integer(i64::MAX),
        V::Float(-0.5),
        V::Float(1e-300),
        V::Float(1e300),
        V::Float(f64::NAN),
        V::Float(f64::INFINITY),
        V::String("a".repeat(100_000)),
        V::String("../../../notes".into()),
        V::String("/dir/precious".into()),
        V::String("a\u{1}b".into()),
        V::Array(vec![]),
        V::Array(vec![V::Float(1e300)]),
        V::Array(vec![V::String("../x".into())]),
    ]
}

/// Every leaf of `value` as a path of keys and indices, with a setter.
fn leaf_paths(value: &toml::Value, path: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    match value {
        toml::Value::Table(table) if !table.is_empty() => {
            for (name, item) in table {
                path.push(name.clone());
                leaf_paths(item, path, out);
                path.pop();
            }
        }
        toml::Value::Array(items) if items.iter().any(toml::Value::is_table) => {
            for (k, item) in items.iter().enumerate() {
                path.push(format!("[{k}]"));
                leaf_paths(item, path, out);
                path.pop();
            }
        }
        _ => out.push(path.clone()),
    }
}

/// The value at `path` inside `root`.
fn value_at<'a>(root: &'a mut toml::Value, path: &[String]) -> &'a mut toml::Value {
    path.iter()
        .fold(root, |value, part| match part.strip_prefix('[') {
            Some(index) => &mut value[index.trim_end_matches(']').parse::<usize>().unwrap()],
            None => &mut value[part.as_str()],
        })
}

/// The dotted key path the configuration names (`scan.launch[0].u2`).
fn dotted(path: &[String]) -> String {
    let mut out = String::new();
    for part in path {
        if !part.starts_with('[') && !out.is_empty() {
            out.push('.');
        }
        out.push_str(part);
    }
    out
}

/// A configuration fuzz test (issue 54): every key of [`STUDY`] (every
/// section enabled) takes every value of [`mutations`] in turn. Loading
/// never panics and never takes long; a refusal names a key on the mutated
/// key's path (or the key it is checked against) and its line; a study that
/// loads is planned by `ternary status` within a time bound, without a
/// panic and without writing anything. Fixed seed, bounded time.
#[test]
fn mutated_configurations_are_refused_by_key_or_planned() {
    let base: toml::Value = toml::from_str(STUDY).unwrap();
    let mut paths = Vec::new();
    leaf_paths(&base, &mut Vec::new(), &mut paths);
    assert!(paths.len() >= 80, "only {} keys", paths.len());
    let file = std::path::Path::new("pipeline.toml");
    let mut loaded = Vec::new();
    let mut refused = 0;
    let mut wrong = Vec::new();
    let started = std::time::Instant::now();
    for path in &paths {
        let key = dotted(path);
        for mutation in mutations() {
            let mut study = base.clone();
            *value_at(&mut study, path) = mutation.clone();
            let Ok(text) = toml::to_string(&study) else {
                continue; // NaN and inf have TOML forms; nothing else fails here
            };
            let what = format!(
                "{key} = {}",
                mutation.to_string().chars().take(40).collect::<String>()
            );
            let parsed = std::panic::catch_unwind(|| Study::parse(file, &text))
                .unwrap_or_else(|_| panic!("{what}: loading panicked"));
            match parsed {
                Ok(_) => loaded.push((what, text)),
                Err(error) => {
                    refused += 1;
                    // The error's key lies on the mutated key's path, or its
                    // message names the mutated key (a check across keys).
                    let section = key.split(['.', '[']).next().unwrap();
                    let unindexed: String = dotted(
                        &path
                            .iter()
                            .filter(|p| !p.starts_with('['))
                            .cloned()
                            .collect::<Vec<_>>(),
                    );
                    let names_it = error.message.contains(&key)
                        || error.message.contains(&unindexed)
                        || error.message.contains(&format!("[{section}]"));
                    let on_path = !error.key.is_empty()
                        && (error.key.starts_with(section) || key.starts_with(&error.key));
                    let shown: String = error.to_string().chars().take(400).collect();
                    if !(on_path || names_it) {
                        wrong.push(format!("{what}: blamed on `{}`: {shown}", error.key));
                    } else if error.line.is_none() && !names_it {
                        wrong.push(format!("{what}: no line: {shown}"));
                    } else if error.message.len() > 2000 {
                        wrong.push(format!("{what}: a long message: {shown}"));
                    }
                }
            }
        }
    }
    assert!(
        started.elapsed() < std::time::Duration::from_secs(60),
        "loading {} mutations took {:?}",
        refused + loaded.len(),
        started.elapsed()
    );
    assert!(
        wrong.is_empty(),
        "{} refusals:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
    assert!(refused >= 500, "only {refused} refusals");
    // Plan a fixed-seed sample of the studies that load, each in a fresh
    // folder that must stay empty but for the configuration.
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1);
        (state >> 33) as usize
    };
    let dir = std::env::temp_dir().join(format!("ternary-fuzz-{}", std::process::id()));
    for _ in 0..loaded.len().min(24) {
        let (what, text) = &loaded[next() % loaded.len()];
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let config = dir.join("pipeline.toml");
        std::fs::write(&config, text).unwrap();
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_ternary"))
            .arg("--config")
            .arg(&config)
            .arg("status")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let begun = std::time::Instant::now();
        let status = loop {
            if let Some(status) = child.try_wait().unwrap() {
                break status;
            }
            if begun.elapsed() > std::time::Duration::from_secs(20) {
                let _ = child.kill();
                panic!("{what}: `status` ran past 20 s");
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        };
        assert_ne!(status.code(), Some(101), "{what}: `status` panicked");
        let entries: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(
            entries.len(),
            1,
            "{what}: `status` wrote into {}",
            dir.display()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
