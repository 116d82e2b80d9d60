//! `ternary report`: the study as one static HTML page, as `snakemake
//! --report` writes one: the `a_n` and paper tables, every figure with its
//! caption, every stage's tables, what each stage computed (instances, keys,
//! times) and the provenance (configuration, code fingerprints, versions).
//!
//! Everything is local: one HTML file with inline CSS, no script and no
//! external address, with the figures copied into `figures/` next to it. The
//! page depends only on the configuration and the store (its date is the
//! newest artifact's, not the clock's), so an unchanged store gives the same
//! bytes. The store is only read; an incomplete one gives a page that says
//! which instances are not fresh and leaves their tables and figures out.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::fs;
use std::path::Path;
use std::time::UNIX_EPOCH;

use anyhow::{Context, Result};

use super::describe;
use super::folder::ReportFolder;
use super::layout::{Align, Cell, Columns, Sink};
use super::printout::print;
use super::summary::stage_tables;
use crate::config::Study;
use crate::contract;
use crate::contract::pulls;
use crate::pipeline::Stage;
use crate::pipeline::executor::{
    self, Action, Freshness, InstanceReport, StatusLine, tool_version,
};
use crate::pipeline::store::{Depth, Manifest, Store};
use crate::pipeline::table::read_parquet_footer;

/// The page's file name in the report's directory.
pub const PAGE: &str = "index.html";

/// The folder of the figures, next to the page.
pub const FIGURES: &str = "figures";

/// Suffix of the figure file the page shows: the screen-sized PNG, drawn to
/// the pixel as the `figures` stage rendered it (SVG text would depend on
/// the viewer's fonts).
const SCREEN_PNG: &str = "_screen.png";

/// Metadata key of a table's description: a figure's caption.
const DESCRIPTION: &str = "ternary.description";

/// Characters of a key or fingerprint shown (the full one is its tooltip).
const SHORT: usize = 12;

/// A stage instance of the plan with its manifest when it is fresh.
struct Instance<'a> {
    line: &'a StatusLine,
    manifest: Option<Manifest>,
}

/// A figure as the page shows it.
struct Figure {
    /// The figure's name (its instance).
    name: String,
    /// Its file, relative to the page.
    href: String,
    /// What it shows.
    caption: String,
    /// Pixel size of the PNG.
    width: u32,
    height: u32,
}

/// The page's mark: a directory whose page carries it holds an earlier
/// report, which a new one replaces.
const GENERATOR: &str = "<meta name=\"generator\" content=\"ternary report\">";

/// Writes the report of `study` into `dir` (created when missing; else
/// empty or holding an earlier report): the page and its figures. Returns a
/// one-line summary.
pub fn write(study: &Study, store: &Store, plan: &[Box<dyn Stage>], dir: &Path) -> Result<String> {
    let is_earlier_page =
        |page: &Path| fs::read_to_string(page).is_ok_and(|text| text.contains(GENERATOR));
    let mut folder = ReportFolder::open(dir, store.root(), is_earlier_page, PAGE)?;
    let lines = executor::status(store, plan, 1)?;
    let instances: Vec<Instance> = lines
        .iter()
        .map(|line| Instance {
            line,
            manifest: fresh_manifest(store, line),
        })
        .collect();
    folder.subfolder(FIGURES)?;
    let figures = copy_figures(store, &instances, &mut folder)?;
    let page = page(study, store, &instances, &figures)?;
    folder.write(PAGE, page.as_bytes())?;
    folder.finish()?;
    let path = dir.join(PAGE);
    let fresh = instances.iter().filter(|i| i.manifest.is_some()).count();
    Ok(format!(
        "report: {} figures, {fresh} of {} instances fresh, in {}\n",
        figures.len(),
        instances.len(),
        path.display()
    ))
}

/// The manifest of a fresh instance's artifact (`None` for any other).
fn fresh_manifest(store: &Store, line: &StatusLine) -> Option<Manifest> {
    let key = line.key.as_ref()?;
    (line.freshness == Freshness::Fresh)
        .then(|| store.inspect(&line.id.stage, key, None, Depth::Sizes).ok())
        .flatten()
}

/// Copies the screen PNG of every fresh figure into the report's figures
/// folder and reads its caption and size. Removes nothing: the folder may
/// hold files that are not ternary's.
fn copy_figures(
    store: &Store,
    instances: &[Instance],
    folder: &mut ReportFolder,
) -> Result<Vec<Figure>> {
    let mut figures = Vec::new();
    for instance in instances {
        let Some(manifest) = &instance.manifest else {
            continue;
        };
        if manifest.stage != contract::figures::STAGE {
            continue;
        }
        let artifact = store.artifact_dir(&manifest.stage, &manifest.key);
        let Some(file) = manifest.files.iter().find(|f| f.name.ends_with(SCREEN_PNG)) else {
            continue;
        };
        let (_, metadata, _) = read_parquet_footer(&artifact.join("points.parquet"))?;
        let source = artifact.join(&file.name);
        let bytes = fs::read(&source).with_context(|| format!("reading {}", source.display()))?;
        let (width, height) =
            png_size(&bytes).with_context(|| format!("decoding {}", source.display()))?;
        folder.write(&format!("{FIGURES}/{}", file.name), &bytes)?;
        figures.push(Figure {
            name: instance.line.id.instance.clone(),
            href: format!("{FIGURES}/{}", file.name),
            caption: metadata.get(DESCRIPTION).cloned().unwrap_or_default(),
            width,
            height,
        });
    }
    Ok(figures)
}

/// Width and height of a PNG, from its header (which also shows it decodes).
fn png_size(bytes: &[u8]) -> Result<(u32, u32)> {
    let reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info()?;
    let info = reader.info();
    Ok((info.width, info.height))
}

/// The whole page.
fn page(
    study: &Study,
    store: &Store,
    instances: &[Instance],
    figures: &[Figure],
) -> Result<String> {
    let reports: Vec<InstanceReport> = instances
        .iter()
        .map(|instance| InstanceReport {
            id: instance.line.id.clone(),
            key: instance.line.key.clone(),
            action: if instance.manifest.is_some() {
                Action::Fresh
            } else {
                Action::Skipped
            },
        })
        .collect();
    let sections: [(&str, &str, String); 8] = [
        ("missing", "Not fresh", not_fresh(instances)),
        ("summary", "Thermalization constants", {
            let mut tables = Tables::default();
            let table = &contract::table::HEADLINE;
            print(
                &mut tables,
                store,
                &reports,
                table,
                study.config.kernel.kick_floor,
            )?;
            tables.html
        }),
        ("paper", "The paper's numbers", {
            let mut tables = Tables::default();
            let kick_floor = study.config.kernel.kick_floor;
            for printout in contract::paper::HEADLINES {
                print(&mut tables, store, &reports, printout, kick_floor)?;
            }
            tables.html
        }),
        ("crosschecks", "Cross-checks: are the errors calibrated?", {
            let mut tables = Tables::default();
            let kick_floor = study.config.kernel.kick_floor;
            for printout in [&pulls::summary::HEADLINE, &pulls::checks::LARGEST] {
                print(&mut tables, store, &reports, printout, kick_floor)?;
            }
            tables.html
        }),
        ("figures", "Figures", figure_list(figures)),
        ("tables", "Every stage's tables", {
            let mut tables = Tables::default();
            stage_tables(&mut tables, store, &reports, study.config.kernel.kick_floor)?;
            tables.html
        }),
        ("stages", "What each stage computed", stage_list(instances)),
        ("provenance", "Provenance", provenance(study, instances)?),
    ];
    let title = format!("ternary study report: {}", file_name(&study.file));
    let mut out = String::new();
    writeln!(
        out,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
         {GENERATOR}\n\
         <title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<main>",
        escape(&title)
    )?;
    writeln!(out, "<h1>{}</h1>", escape(&title))?;
    writeln!(
        out,
        "<p class=\"lead\">{}</p>",
        escape(&headline(store, instances))
    )?;
    writeln!(out, "<nav>\n<h2>Contents</h2>\n<ol>")?;
    for (id, heading, body) in &sections {
        if !body.is_empty() {
            write!(out, "<li><a href=\"#{id}\">{}</a>", escape(heading))?;
            if *id == "figures" {
                out.push_str(&figure_contents(figures));
            }
            writeln!(out, "</li>")?;
        }
    }
    writeln!(out, "</ol>\n</nav>")?;
    for (id, heading, body) in &sections {
        if !body.is_empty() {
            writeln!(
                out,
                "<section id=\"{id}\">\n<h2>{}</h2>\n{body}</section>",
                escape(heading)
            )?;
        }
    }
    writeln!(out, "</main>\n</body>\n</html>")?;
    Ok(out)
}

/// The line under the title: counts of instances by state, the date of the
/// newest artifact and the report's version.
fn headline(store: &Store, instances: &[Instance]) -> String {
    let mut counts: BTreeMap<&str, usize> = BTreeMap::new();
    for instance in instances {
        *counts.entry(instance.line.freshness.name()).or_default() += 1;
    }
    let states: Vec<String> = counts
        .iter()
        .map(|(state, count)| format!("{count} {state}"))
        .collect();
    let newest = newest_artifact(store, instances).map_or("no artifact yet".to_string(), |date| {
        format!("newest artifact {date}")
    });
    format!(
        "{}: {}; {newest}; written by {}.",
        counted(instances.len(), "stage instance"),
        states.join(", "),
        tool_version()
    )
}

/// When the newest fresh artifact was written (its manifest's modification
/// time), as `YYYY-MM-DD HH:MM UTC`.
fn newest_artifact(store: &Store, instances: &[Instance]) -> Option<String> {
    instances
        .iter()
        .filter_map(|instance| instance.manifest.as_ref())
        .filter_map(|manifest| {
            let path = store
                .artifact_dir(&manifest.stage, &manifest.key)
                .join("manifest.json");
            let modified = fs::metadata(path).and_then(|m| m.modified()).ok()?;
            Some(modified.duration_since(UNIX_EPOCH).ok()?.as_secs())
        })
        .max()
        .map(utc_minute)
}

/// Seconds since 1970 as `YYYY-MM-DD HH:MM UTC` (proleptic Gregorian).
fn utc_minute(seconds: u64) -> String {
    let days = (seconds / 86_400) as i64;
    let minute = seconds % 86_400 / 60;
    // Howard Hinnant's civil_from_days.
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let day_of_era = z.rem_euclid(146_097);
    let year_of_era =
        (day_of_era - day_of_era / 1460 + day_of_era / 36_524 - day_of_era / 146_096) / 365;
    let day_of_year = day_of_era - (365 * year_of_era + year_of_era / 4 - year_of_era / 100);
    let mp = (5 * day_of_year + 2) / 153;
    let day = day_of_year - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = year_of_era + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02} UTC",
        minute / 60,
        minute % 60
    )
}

/// The instances that are not fresh, and why: their tables and figures are
/// not in the page (empty when every instance is fresh).
fn not_fresh(instances: &[Instance]) -> String {
    let missing: Vec<&Instance> = instances
        .iter()
        .filter(|instance| instance.manifest.is_none())
        .collect();
    if missing.is_empty() {
        return String::new();
    }
    let mut out = format!(
        "<p class=\"warning\">{} of {} instances are not fresh: the tables and figures they \
         would give are left out until <code>ternary run</code> computes them.</p>\n\
         <details>\n<summary>The instances and why</summary>\n<ul>\n",
        missing.len(),
        instances.len()
    );
    for instance in missing {
        let _ = writeln!(
            out,
            "<li><code>{}</code>: {}</li>",
            escape(&instance.line.id.to_string()),
            escape(&describe(&instance.line.freshness))
        );
    }
    out.push_str("</ul>\n</details>\n");
    out
}

/// The figures' names as links, for the contents.
fn figure_contents(figures: &[Figure]) -> String {
    let links: Vec<String> = figures
        .iter()
        .map(|figure| {
            let name = escape(&figure.name);
            format!("<a href=\"#figure-{name}\">{name}</a>")
        })
        .collect();
    format!("<br><small>{}</small>", links.join(", "))
}

/// Every figure with its number, name and caption.
fn figure_list(figures: &[Figure]) -> String {
    let mut out = String::new();
    for (k, figure) in figures.iter().enumerate() {
        let caption = escape(figure.caption.trim_end_matches('.'));
        let _ = writeln!(
            out,
            "<figure id=\"figure-{name}\">\n<img src=\"{href}\" alt=\"Figure {number}, {name}: {caption}\" \
             width=\"{width}\" height=\"{height}\">\n<figcaption><b>Figure {number}</b> \
             <code>{name}</code>: {caption}.</figcaption>\n</figure>",
            name = escape(&figure.name),
            href = escape(&figure.href),
            number = k + 1,
            width = figure.width,
            height = figure.height,
        );
    }
    out
}

/// Per stage: instances, fresh ones, total time and code fingerprint, then
/// each stage's instances with key and time in a collapsed list.
fn stage_list(instances: &[Instance]) -> String {
    let mut stages: Vec<&str> = Vec::new();
    for instance in instances {
        if !stages.contains(&instance.line.id.stage.as_str()) {
            stages.push(&instance.line.id.stage);
        }
    }
    let of = |stage: &str| -> Vec<&Instance> {
        instances
            .iter()
            .filter(|instance| instance.line.id.stage == stage)
            .collect()
    };
    let mut summary = Columns::new(&[
        ("stage", Align::Left),
        ("instances", Align::Right),
        ("fresh", Align::Right),
        ("wall time [s]", Align::Right),
        ("code fingerprint", Align::Left),
    ]);
    let mut details = String::new();
    for stage in &stages {
        let members = of(stage);
        let manifests: Vec<&Manifest> =
            members.iter().filter_map(|i| i.manifest.as_ref()).collect();
        let seconds: f64 = manifests.iter().map(|m| m.wall_seconds).sum();
        let fingerprints: BTreeSet<&str> = manifests
            .iter()
            .map(|m| m.code.fingerprint.as_str())
            .filter(|f| !f.is_empty())
            .collect();
        summary.push(vec![
            Cell::text(*stage),
            Cell::text(members.len().to_string()),
            Cell::text(manifests.len().to_string()),
            Cell::text(if manifests.is_empty() {
                "-".to_string()
            } else {
                seconds_text(seconds)
            }),
            Cell::text(
                fingerprints
                    .iter()
                    .map(|f| short(f))
                    .collect::<Vec<_>>()
                    .join(", "),
            ),
        ]);
        let _ = writeln!(
            details,
            "<details>\n<summary><code>{}</code>: {}, {} s</summary>",
            escape(stage),
            counted(members.len(), "instance"),
            seconds_text(seconds)
        );
        let mut table = Columns::new(&[
            ("instance", Align::Left),
            ("state", Align::Left),
            ("key", Align::Left),
            ("wall time [s]", Align::Right),
        ]);
        for instance in members {
            table.push(vec![
                Cell::text(instance.line.id.instance.as_str()),
                Cell::text(instance.line.freshness.name()),
                Cell::text(instance.line.key.as_deref().map_or("-".to_string(), short)),
                Cell::text(
                    instance
                        .manifest
                        .as_ref()
                        .map_or("-".to_string(), |m| seconds_text(m.wall_seconds)),
                ),
            ]);
        }
        details.push_str(&html_table(&table));
        details.push_str("</details>\n");
    }
    let total: f64 = instances
        .iter()
        .filter_map(|i| i.manifest.as_ref())
        .map(|m| m.wall_seconds)
        .sum();
    summary.push(vec![
        Cell::text("all"),
        Cell::text(instances.len().to_string()),
        Cell::text(
            instances
                .iter()
                .filter(|i| i.manifest.is_some())
                .count()
                .to_string(),
        ),
        Cell::text(seconds_text(total)),
        Cell::text(""),
    ]);
    let mut out = String::from(
        "<p>Wall time is each fresh artifact's own computation as its manifest records it \
         (the sum over a stage's fresh instances, not the elapsed time of a parallel run). \
         A key is the SHA-256 of an instance's parameters, inputs and code; the code \
         fingerprint, of the source files and crates the stage runs.</p>\n",
    );
    out.push_str(&html_table(&summary));
    out.push_str(&details);
    out
}

/// Seconds to three significant digits.
fn seconds_text(seconds: f64) -> String {
    super::numbers::significant_to(seconds, 3)
}

/// `count` and `noun`, plural unless one: `1 instance`, `4 instances`.
fn counted(count: usize, noun: &str) -> String {
    if count == 1 {
        format!("{count} {noun}")
    } else {
        format!("{count} {noun}s")
    }
}

/// The first [`SHORT`] characters of a key or fingerprint.
fn short(hex: &str) -> String {
    hex.chars().take(SHORT).collect()
}

/// The versions that wrote the artifacts, the code fingerprints, and the
/// configuration file verbatim.
fn provenance(study: &Study, instances: &[Instance]) -> Result<String> {
    let tools: BTreeSet<&str> = instances
        .iter()
        .filter_map(|i| i.manifest.as_ref())
        .map(|m| m.tool.as_str())
        .collect();
    let config = fs::read_to_string(&study.file)
        .with_context(|| format!("reading {}", study.file.display()))?;
    let mut out = String::new();
    writeln!(
        out,
        "<p>Artifacts written by {}; this page by {}. Every number and figure comes \
         from the store's fresh artifacts; <code>ternary verify</code> checks them \
         against their content hashes.</p>",
        if tools.is_empty() {
            "nothing yet".to_string()
        } else {
            tools
                .iter()
                .map(|t| escape(t))
                .collect::<Vec<_>>()
                .join(", ")
        },
        escape(&tool_version())
    )?;
    writeln!(
        out,
        "<details>\n<summary>The configuration, <code>{}</code> ({})</summary>\n<pre>{}</pre>\n</details>",
        escape(&file_name(&study.file)),
        counted(config.lines().count(), "line"),
        escape(&config)
    )?;
    Ok(out)
}

/// A path's file name as text.
fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// A table as HTML: right-aligned columns hold numbers.
fn html_table(table: &Columns) -> String {
    let class = |align: Align| match align {
        Align::Left => "",
        Align::Right => " class=\"num\"",
    };
    let mut out = String::from("<div class=\"scroll\"><table>\n<thead><tr>");
    for (head, align) in table.heads() {
        let _ = write!(out, "<th{}>{}</th>", class(*align), escape(head.trim()));
    }
    out.push_str("</tr></thead>\n<tbody>\n");
    for row in table.shown_rows() {
        out.push_str("<tr>");
        for (cell, (_, align)) in row.iter().zip(table.heads()) {
            let _ = write!(
                out,
                "<td{}>{}</td>",
                class(*align),
                unbroken(&escape(cell.trim()))
            );
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</tbody>\n</table></div>\n");
    out
}

/// A cell's text with `value ± error` kept on one line (cells wrap at their
/// other spaces: Table I's `published | ours (z)` breaks at its bar).
fn unbroken(html: &str) -> String {
    html.replace(" ± ", "\u{a0}±\u{a0}")
}

/// The summaries' blocks as HTML.
#[derive(Default)]
struct Tables {
    html: String,
}

impl Sink for Tables {
    fn title(&mut self, text: &str) {
        let _ = writeln!(self.html, "<p class=\"title\">{}</p>", escape(text));
    }

    fn table(&mut self, table: &Columns) {
        self.html.push_str(&html_table(table));
    }

    fn line(&mut self, text: &str) {
        let _ = writeln!(self.html, "<p class=\"note\">{}</p>", escape(text));
    }
}

/// `text` with the characters HTML gives a meaning escaped.
pub fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// The page's style: readable type, numbers in aligned figures, tables that
/// scroll sideways on narrow screens rather than overflow. A cell keeps its
/// value on one line (`(1.122363 ± 0.000056)e-4` broken at a space reads as
/// two numbers); only a row's last text column wraps, at least 40 characters
/// wide so that its rows stay a few lines tall.
const STYLE: &str = "
:root { color-scheme: light; }
body { margin: 0; background: #fff; color: #1a1a1a;
  font: 16px/1.5 system-ui, -apple-system, 'Segoe UI', 'DejaVu Sans', sans-serif; }
main { max-width: 1200px; margin: 0 auto; padding: 1.5rem 2rem 4rem; }
h1 { font-size: 1.7rem; margin: 0.5rem 0; }
h2 { font-size: 1.35rem; margin-top: 2.5rem; border-bottom: 1px solid #ccc; padding-bottom: 0.2rem; }
h3 { font-size: 1.1rem; }
.lead { color: #444; }
nav ol { columns: 2; }
nav li { break-inside: avoid; }
code, pre { font-family: 'DejaVu Sans Mono', Menlo, Consolas, monospace; font-size: 0.9em; }
pre { background: #f6f6f6; padding: 0.8rem; overflow-x: auto; border: 1px solid #e2e2e2; }
.title { font-weight: 600; margin: 1.6rem 0 0.4rem; max-width: 75ch; }
.note { margin: 0.2rem 0; font-size: 0.92em; max-width: 90ch; }
.warning { background: #fff4e0; border-left: 4px solid #e69f00; padding: 0.5rem 0.8rem; }
.scroll { overflow-x: auto; }
table { border-collapse: collapse; font-variant-numeric: tabular-nums; font-size: 0.9em; margin: 0.3rem 0 0.8rem; }
th, td { padding: 0.2rem 0.45rem; text-align: left; vertical-align: top; }
th, td { white-space: nowrap; }
th { border-bottom: 2px solid #888; font-weight: 600; }
tbody tr:nth-child(even) { background: #f7f7f7; }
.num { text-align: right; }
td:last-child:not(.num) { white-space: normal; min-width: 40ch; }
figure { margin: 2rem 0; }
figure img { display: block; width: 860px; max-width: 100%; height: auto; border: 1px solid #ddd; }
figcaption { margin-top: 0.5rem; max-width: 90ch; font-size: 0.95em; }
details { margin: 0.3rem 0; }
summary { cursor: pointer; }
";
