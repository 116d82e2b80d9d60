//! The manual checked: README.md and every page under docs/ link only to files
//! and headings that exist, README stays short, and every figure README quotes
//! agrees with the page it is quoted from.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Component, Path, PathBuf};

/// The repository's root.
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// README.md, CONTRIBUTING.md and every Markdown page under docs/, relative to the root.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![PathBuf::from("README.md"), PathBuf::from("CONTRIBUTING.md")];
    let mut pending = vec![PathBuf::from("docs")];
    while let Some(dir) = pending.pop() {
        for entry in fs::read_dir(root().join(&dir)).unwrap().flatten() {
            let path = dir.join(entry.file_name());
            if entry.file_type().unwrap().is_dir() {
                pending.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                pages.push(path);
            }
        }
    }
    pages.sort();
    pages
}

/// The lines of a page that are prose: fenced and indented code blocks left out.
fn prose_lines(text: &str) -> Vec<&str> {
    let mut fenced = false;
    text.lines()
        .filter(|line| {
            if line.trim_start().starts_with("```") {
                fenced = !fenced;
                return false;
            }
            !fenced && !line.starts_with("    ")
        })
        .collect()
}

/// A line with its code spans (between backticks) blanked out.
fn without_code(line: &str) -> String {
    line.split('`').step_by(2).collect::<Vec<_>>().join(" ")
}

/// The targets of the inline links and images of a page's prose.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    for line in prose_lines(text) {
        let line = without_code(line);
        let mut rest = line.as_str();
        while let Some(start) = rest.find("](") {
            let after = &rest[start + 2..];
            let Some(end) = after.find(')') else { break };
            targets.push(after[..end].to_string());
            rest = &after[end..];
        }
    }
    targets
}

/// GitHub's anchor of a heading: lower case, code marks and punctuation
/// dropped, spaces as hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// Every anchor of a page: its headings' slugs, a repeated one numbered `-1`, `-2`, ...
fn anchors(text: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    for line in prose_lines(text) {
        let Some(heading) = line.strip_prefix('#') else {
            continue;
        };
        let base = slug(heading.trim_start_matches('#'));
        let mut anchor = base.clone();
        let mut repeat = 0;
        while found.contains(&anchor) {
            repeat += 1;
            anchor = format!("{base}-{repeat}");
        }
        found.insert(anchor);
    }
    found
}

/// `path` with `.` and `..` resolved lexically; `None` if it leaves the repository.
fn normalized(path: &Path) -> Option<PathBuf> {
    let mut parts: Vec<Component> = Vec::new();
    for part in path.components() {
        match part {
            Component::CurDir => {}
            Component::ParentDir => {
                parts.pop()?;
            }
            other => parts.push(other),
        }
    }
    Some(parts.iter().collect())
}

/// What is wrong with one link of `page` (`None` when it resolves).
fn broken(page: &Path, target: &str) -> Option<String> {
    if target.starts_with("http://") || target.starts_with("https://") {
        return None;
    }
    let (file, anchor) = target.split_once('#').unwrap_or((target, ""));
    let linked = if file.is_empty() {
        page.to_path_buf()
    } else {
        let Some(path) = normalized(&page.parent().unwrap().join(file)) else {
            return Some(format!("{target}: outside the repository"));
        };
        path
    };
    if !root().join(&linked).exists() {
        return Some(format!("{target}: no such file"));
    }
    if anchor.is_empty() {
        return None;
    }
    let text = fs::read_to_string(root().join(&linked)).unwrap_or_default();
    let missing = !anchors(&text).contains(anchor);
    missing.then(|| format!("{target}: no heading #{anchor} in {}", linked.display()))
}

#[test]
fn every_link_and_anchor_resolves() {
    let mut problems = Vec::new();
    let mut links = 0;
    for page in pages() {
        let text = fs::read_to_string(root().join(&page)).unwrap();
        for target in link_targets(&text) {
            links += 1;
            if let Some(problem) = broken(&page, &target) {
                problems.push(format!("{}: {problem}", page.display()));
            }
        }
    }
    assert!(
        problems.is_empty(),
        "broken links:\n{}",
        problems.join("\n")
    );
    assert!(
        links >= 40,
        "only {links} links found: is the parser broken?"
    );
}

/// Every chapter is reachable from the manual's index.
#[test]
fn the_index_lists_every_chapter() {
    let index = fs::read_to_string(root().join("docs/README.md")).unwrap();
    let listed: BTreeSet<String> = link_targets(&index).into_iter().collect();
    let unlisted: Vec<PathBuf> = pages()
        .into_iter()
        .filter(|page| page.parent() == Some(Path::new("docs")))
        .filter(|page| page.file_name().unwrap() != "README.md")
        .filter(|page| !listed.contains(page.file_name().unwrap().to_str().unwrap()))
        .collect();
    assert!(
        unlisted.is_empty(),
        "docs/README.md does not list {unlisted:?}"
    );
}

#[test]
fn the_parser_knows_links_anchors_and_code() {
    let text = "# A `code` title\n## A title\n## A title\n[x](b.md#c) `[no](d.md)`\n    [no](e.md)\n```\n[no](f.md)\n```\n![i](g.png)\n";
    assert_eq!(link_targets(text), ["b.md#c", "g.png"]);
    let expected: BTreeSet<String> = ["a-code-title", "a-title", "a-title-1"]
        .map(String::from)
        .into();
    assert_eq!(anchors(text), expected);
    assert_eq!(
        slug("`ternary rate`: a real gas"),
        "ternary-rate-a-real-gas"
    );
    assert!(broken(Path::new("README.md"), "../../etc/passwd").is_some());
    assert!(broken(Path::new("docs/README.md"), "tutorial.md#no-such-heading").is_some());
    assert!(broken(Path::new("docs/README.md"), "../README.md").is_none());
}

#[test]
fn the_readme_is_read_in_five_minutes() {
    let readme = fs::read_to_string(root().join("README.md")).unwrap();
    let lines = readme.lines().count();
    assert!(lines <= 150, "README.md has {lines} lines: at most 150");
}

/// The section of a page under heading `title` (to the next heading of its level).
fn section<'a>(text: &'a str, title: &str) -> &'a str {
    let level = title.split(' ').next().unwrap();
    let start = text
        .find(&format!("\n{title}\n"))
        .unwrap_or_else(|| panic!("no heading {title:?}"));
    let body = &text[start + title.len() + 2..];
    let end = body.find(&format!("\n{level} ")).unwrap_or(body.len());
    &body[..end]
}

/// The durations a text quotes: `16 min 20 s`, `9 min`, `45 s`, as written.
fn durations(text: &str) -> Vec<String> {
    let words: Vec<&str> = text.split_whitespace().collect();
    let number = |w: &str| !w.is_empty() && w.chars().all(|c| c.is_ascii_digit() || c == '.');
    let unit = |w: &str| {
        matches!(
            w.trim_end_matches([',', ';', ')', '.', ':']),
            "min" | "s" | "h"
        )
    };
    let mut found = Vec::new();
    let mut k = 0;
    while k + 1 < words.len() {
        if number(words[k]) && unit(words[k + 1]) {
            let mut end = k + 2;
            while end + 1 < words.len()
                && !words[end - 1].ends_with([',', ';', ')', '.', ':'])
                && number(words[end])
                && unit(words[end + 1])
            {
                end += 2;
            }
            let quoted = words[k..end].join(" ");
            found.push(
                quoted
                    .trim_end_matches([',', ';', ')', '.', ':'])
                    .to_string(),
            );
            k = end;
        } else {
            k += 1;
        }
    }
    found
}

/// The quoted values that their source does not hold.
fn missing(quoted: &[String], holds: impl Fn(&str) -> bool) -> Vec<&String> {
    quoted.iter().filter(|q| !holds(q)).collect()
}

/// Every duration README's setup quotes is in docs/benchmarks.md's table of today's figures.
#[test]
fn the_readme_quotes_todays_figures() {
    let readme = fs::read_to_string(root().join("README.md")).unwrap();
    let benchmarks = fs::read_to_string(root().join("docs/benchmarks.md")).unwrap();
    let today = section(&benchmarks, "## Today's figures");
    let quoted = durations(section(&readme, "## Setup: two commands"));
    assert!(quoted.len() >= 3, "the setup quotes {quoted:?}");
    let drifted = missing(&quoted, |q| today.contains(q));
    assert!(
        drifted.is_empty(),
        "README quotes {drifted:?}, which docs/benchmarks.md's today's figures do not hold"
    );
}

/// The lines of a text's indented code blocks.
fn indented(text: &str) -> Vec<&str> {
    text.lines()
        .filter(|line| line.starts_with("    "))
        .collect()
}

/// The `a_n` rows README shows are cells of the default study's print in
/// docs/default-study.md: each row's cells, as written, in the row that starts alike.
#[test]
fn the_readme_quotes_the_default_study() {
    let readme = fs::read_to_string(root().join("README.md")).unwrap();
    let source = fs::read_to_string(root().join("docs/default-study.md")).unwrap();
    let cells = |line: &str| -> Vec<String> {
        line.trim()
            .split("  ")
            .map(str::trim)
            .filter(|c| !c.is_empty())
            .map(String::from)
            .collect()
    };
    let shown = indented(section(&readme, "## What the first run prints"));
    assert!(shown.len() >= 5, "README shows {} rows", shown.len());
    for row in shown {
        let row_cells = cells(row);
        let matching = indented(&source)
            .into_iter()
            .find(|line| cells(line).first() == row_cells.first())
            .unwrap_or_else(|| panic!("README row {row:?} starts no row of docs/default-study.md"));
        let source_cells = cells(matching);
        let drifted = missing(&row_cells, |c| source_cells.iter().any(|s| s == c));
        assert!(
            drifted.is_empty(),
            "README row {row:?}: {drifted:?} not in {matching:?}"
        );
    }
}

/// CI runs README's test command, as written.
#[test]
fn ci_runs_the_readmes_test_command() {
    let readme = fs::read_to_string(root().join("README.md")).unwrap();
    let ci = fs::read_to_string(root().join(".ci/run")).unwrap();
    let command = section(&readme, "## Setup: two commands")
        .lines()
        .find(|line| line.trim_start().starts_with("python3 -m pip install"))
        .expect("a test command")
        .trim();
    assert!(
        ci.lines().any(|line| line.trim() == command),
        ".ci/run does not run README's test command {command:?}"
    );
    assert!(durations("took 16 min 20 s, then 9 min; 45 s.") == ["16 min 20 s", "9 min", "45 s"]);
}

/// The Rust version README asks for is the one `Cargo.toml` declares.
#[test]
fn the_readme_asks_for_the_rust_version_cargo_declares() {
    let readme = fs::read_to_string(root().join("README.md")).unwrap();
    let manifest = fs::read_to_string(root().join("Cargo.toml")).unwrap();
    let version = manifest
        .lines()
        .find_map(|line| line.strip_prefix("rust-version = "))
        .expect("a rust-version")
        .trim_matches('"');
    let asked = format!("Rust ({version} or newer)");
    assert!(
        section(&readme, "## Setup: two commands").contains(&asked),
        "README's setup does not say {asked:?}"
    );
}
