//! `ternary report`: the static HTML page of a study, checked as a reader's
//! browser sees it (Debian's headless `chromium`, where installed) and as
//! files: self-contained, reproducible, and without writing to the store.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;

use common::{
    files_under, run_counts, small_study, stderr, stdout, ternary, workspace, write_config,
};

/// Figures of [`small_study`].
const SMALL_STUDY_FIGURES: usize = 4;

/// Every file of `dir` with its bytes.
fn contents(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    files_under(dir)
        .into_iter()
        .map(|path| {
            let bytes = fs::read(dir.join(&path)).unwrap();
            (path, bytes)
        })
        .collect()
}

/// Writes the report of `config` into `dir` and returns the page.
fn report(config: &Path, dir: &Path) -> String {
    let output = ternary(config, &["report", &dir.to_string_lossy()]);
    assert!(
        output.status.success(),
        "report failed: {}",
        stderr(&output)
    );
    assert!(
        stdout(&output).starts_with("report: "),
        "{}",
        stdout(&output)
    );
    fs::read_to_string(dir.join("index.html")).unwrap()
}

/// The values of attribute `name` (`src`, `href`, `alt`) in `html`.
fn attributes<'a>(html: &'a str, name: &str) -> Vec<&'a str> {
    let opening = format!(" {name}=\"");
    html.split(opening.as_str())
        .skip(1)
        .map(|rest| rest.split('"').next().unwrap())
        .collect()
}

/// Width, height and pixels (8-bit RGB or RGBA) of a PNG.
fn decode_png(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut pixels = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut pixels).unwrap();
    pixels.truncate(info.buffer_size());
    (info.width, info.height, pixels)
}

/// The page of a computed study holds its tables, every figure (a PNG next
/// to it that decodes, with alt text and caption), each stage and the
/// configuration; it names nothing outside its directory; a second report
/// gives the same bytes; the store is only read.
#[test]
fn the_report_is_complete_self_contained_and_reproducible() {
    let dir = workspace("report");
    let config = write_config(&dir, &small_study("data"));
    run_counts(&config, &[]);
    let store = dir.join("data");
    let before = contents(&store);
    let out = dir.join("out");
    let page = report(&config, &out);
    assert_eq!(contents(&store), before, "report changed the store");

    for heading in [
        "Thermalization constants",
        "The paper&#39;s numbers",
        "Figures",
        "Every stage&#39;s tables",
        "What each stage computed",
        "Provenance",
    ] {
        assert!(page.contains(&format!(">{heading}</h2>")), "no {heading}");
    }
    assert!(
        !page.contains("Not fresh"),
        "a complete study has no missing part"
    );
    assert!(page.contains("<td>ipp-6</td>"), "no a_n row of ipp-6");
    assert!(page.contains("<summary><code>collisions</code>"));
    assert!(page.contains("inverse_power = [6]"), "no configuration");
    assert!(!page.contains("<script"), "the page needs no script");

    let sources = attributes(&page, "src");
    assert_eq!(sources.len(), SMALL_STUDY_FIGURES, "{sources:?}");
    assert_eq!(attributes(&page, "alt").len(), sources.len());
    assert_eq!(page.matches("<figcaption>").count(), sources.len());
    for src in &sources {
        assert!(
            src.starts_with("figures/") && src.ends_with(".png"),
            "{src}"
        );
        let (width, height, _) = decode_png(&out.join(src));
        assert!(width > 0 && height > 0, "{src}");
    }
    for href in attributes(&page, "href") {
        assert!(href.starts_with('#'), "a link out of the page: {href}");
    }
    assert!(!page.contains("http://") && !page.contains("https://"));

    let first = contents(&out);
    report(&config, &out);
    assert_eq!(contents(&out), first, "a second report differs");

    in_chromium(&out);
}

/// A study not computed yet gets a page that says what is missing, and no
/// store is created for it.
#[test]
fn an_incomplete_store_gives_a_page_that_says_what_is_missing() {
    let dir = workspace("report-missing");
    let config = write_config(&dir, &small_study("data"));
    let page = report(&config, &dir.join("out"));
    assert!(!dir.join("data").exists(), "report created the store");
    assert!(page.contains(">Not fresh</h2>"));
    assert!(page.contains("12 of 12 instances are not fresh"), "{page}");
    assert!(!page.contains("<img"));

    let inside = ternary(
        &config,
        &["report", &dir.join("data/report").to_string_lossy()],
    );
    assert!(!inside.status.success(), "a report inside the store");
    assert!(
        stderr(&inside).contains("is inside the store"),
        "{}",
        stderr(&inside)
    );
    assert!(!dir.join("data").exists(), "report created the store");
}

/// A report never overwrites what is not its own: a directory holding a
/// user's page, or other files and no page, is refused by name and left
/// untouched; an empty one takes the report.
#[test]
fn a_report_refuses_a_directory_that_holds_other_files() {
    let dir = workspace("report-foreign");
    let config = write_config(&dir, &small_study("data"));
    for (folder, file) in [("page", "index.html"), ("notes", "notes.txt")] {
        let out = dir.join(folder);
        fs::create_dir_all(&out).unwrap();
        fs::write(out.join(file), "a user's file").unwrap();
        let before = contents(&out);
        let refused = ternary(&config, &["report", &out.to_string_lossy()]);
        assert!(!refused.status.success(), "a report over {file}");
        assert!(
            stderr(&refused).contains("holds files and no earlier report"),
            "{}",
            stderr(&refused)
        );
        assert_eq!(
            contents(&out),
            before,
            "the refused report wrote into {folder}"
        );
    }
    let empty = dir.join("empty");
    fs::create_dir_all(&empty).unwrap();
    assert!(report(&config, &empty).contains("<meta name=\"generator\""));
}

/// `report x/../data/artifacts/report` and a link into the store wrote
/// inside the store; a link in the place of a figure was written through
/// (a file outside the report overwritten); a figure the user edited was
/// replaced silently (issue 54, item 4). Now the folder is resolved before
/// the store check, links are replaced and never followed, and an edited
/// file is kept with an error that names it.
#[test]
fn a_report_never_escapes_its_folder_nor_overwrites_edits() {
    let dir = workspace("report-escapes");
    let config = write_config(&dir, &small_study("data"));
    run_counts(&config, &[]);
    let store = dir.join("data");
    let before = contents(&store);
    std::os::unix::fs::symlink(&store, dir.join("storelink")).unwrap();
    for target in [
        "x/../data/artifacts/report",
        "storelink/rep",
        "data/../data/refs/r",
    ] {
        let refused = ternary(&config, &["report", &dir.join(target).to_string_lossy()]);
        assert!(!refused.status.success(), "a report at {target}");
        assert!(
            stderr(&refused).contains("is inside the store"),
            "{target}: {}",
            stderr(&refused)
        );
    }
    assert_eq!(contents(&store), before, "a report wrote into the store");
    assert!(!dir.join("x").exists());

    let out = dir.join("out");
    let page = report(&config, &out);
    let figure = attributes(&page, "src")[0].to_string();
    // A link in the place of a figure: not followed; the report refuses,
    // naming it, and the file it names is intact.
    let outside = dir.join("precious.png");
    fs::write(&outside, "precious").unwrap();
    fs::remove_file(out.join(&figure)).unwrap();
    std::os::unix::fs::symlink(&outside, out.join(&figure)).unwrap();
    let refused = ternary(&config, &["report", &out.to_string_lossy()]);
    assert!(!refused.status.success(), "a report through a link");
    assert!(stderr(&refused).contains(&figure), "{}", stderr(&refused));
    assert_eq!(fs::read_to_string(&outside).unwrap(), "precious");
    assert!(
        fs::symlink_metadata(out.join(&figure))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    fs::remove_file(out.join(&figure)).unwrap();
    report(&config, &out);
    // A figure the user edited: kept, and the report refuses, naming it.
    fs::write(out.join(&figure), "my edit").unwrap();
    let refused = ternary(&config, &["report", &out.to_string_lossy()]);
    assert!(!refused.status.success(), "a report over an edited figure");
    assert!(stderr(&refused).contains(&figure), "{}", stderr(&refused));
    assert_eq!(fs::read_to_string(out.join(&figure)).unwrap(), "my edit");
    // An edited page likewise.
    fs::remove_file(out.join(&figure)).unwrap();
    report(&config, &out);
    let edited = fs::read_to_string(out.join("index.html")).unwrap() + "<!-- my note -->";
    fs::write(out.join("index.html"), &edited).unwrap();
    assert!(
        !ternary(&config, &["report", &out.to_string_lossy()])
            .status
            .success()
    );
    assert_eq!(fs::read_to_string(out.join("index.html")).unwrap(), edited);
}

/// The page as headless Chromium shows it: every image loaded (a copy of the
/// page with a checking script, beside it) and a screenshot that is not
/// blank. Skipped, saying so, where no `chromium` is installed.
fn in_chromium(dir: &Path) {
    let Some(browser) = ["chromium", "chromium-browser"]
        .into_iter()
        .find(|name| Command::new(name).arg("--version").output().is_ok())
    else {
        eprintln!("skipped the browser checks: no `chromium` on PATH");
        return;
    };
    let page = fs::read_to_string(dir.join("index.html")).unwrap();
    let check = page.replace(
        "</body>",
        "<script>window.addEventListener('load', () => { \
         const images = [...document.images]; \
         const loaded = images.filter(i => i.complete && i.naturalWidth > 0).length; \
         document.body.insertAdjacentHTML('beforeend', \
           `<p id=\"checked\">loaded ${loaded} of ${images.length}</p>`); });</script></body>",
    );
    let harness = dir.join("check.html");
    fs::write(&harness, check).unwrap();
    let run = |extra: &[&str], target: &Path| {
        let output = Command::new(browser)
            .args([
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--hide-scrollbars",
                "--window-size=1200,3000",
                "--virtual-time-budget=10000",
            ])
            .args(extra)
            .arg(format!("file://{}", target.display()))
            .output()
            .unwrap();
        assert!(output.status.success(), "chromium: {}", stderr(&output));
        stdout(&output)
    };
    let dom = run(&["--dump-dom"], &harness);
    fs::remove_file(&harness).unwrap();
    let expected = format!("loaded {SMALL_STUDY_FIGURES} of {SMALL_STUDY_FIGURES}");
    assert!(dom.contains(&expected), "not every image loaded: {}", {
        dom.split("id=\"checked\">")
            .nth(1)
            .unwrap_or("no check ran")
    });

    let shot = dir.with_extension("png");
    run(
        &[&format!("--screenshot={}", shot.display())],
        &dir.join("index.html"),
    );
    let (width, height, pixels) = decode_png(&shot);
    let channels = pixels.len() / (width * height) as usize;
    let first = &pixels[..channels];
    assert!(
        pixels.chunks(channels).any(|pixel| pixel != first),
        "the screenshot is blank"
    );
}
