//! Where a bundle is written: a staging directory next to the target,
//! renamed into place once complete, so a bundle appears whole or not at all
//! (and staging left by a killed export is removed).

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

/// Where a bundle is written before it appears at its target.
pub(super) struct BundleStaging {
    /// The staging directory.
    pub(super) dir: PathBuf,
    /// `true` when it lies inside the (empty) target, which may be a mount
    /// point: its entries are then moved up one by one; otherwise the whole
    /// directory is renamed onto the target.
    inside: bool,
}

impl BundleStaging {
    /// Moves the written bundle to `target`.
    pub(super) fn place(&self, target: &Path) -> Result<()> {
        let moved = |from: &Path, to: &Path| {
            fs::rename(from, to).with_context(|| format!("moving the bundle into {}", to.display()))
        };
        if !self.inside {
            return moved(&self.dir, target);
        }
        for entry in
            fs::read_dir(&self.dir).with_context(|| format!("reading {}", self.dir.display()))?
        {
            let name = entry?.file_name();
            moved(&self.dir.join(&name), &target.join(&name))?;
        }
        fs::remove_dir(&self.dir).with_context(|| format!("removing {}", self.dir.display()))
    }
}

/// Prefix of a staging directory inside an existing empty target.
const INSIDE_STAGING: &str = ".export-";

/// Checks the target `dir` (missing, or an empty directory, which may be a
/// mount point), removes staging debris of exports that were killed (named
/// for a process that no longer runs), and creates the staging directory:
/// inside an existing target (a mount point cannot be renamed over), beside
/// a missing one. Every error names its path.
pub(super) fn prepare_target(dir: &Path) -> Result<BundleStaging> {
    let name = dir
        .file_name()
        .with_context(|| format!("{}: the bundle directory has no name", dir.display()))?
        .to_string_lossy()
        .into_owned();
    let parent = dir
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let beside = format!(".{name}.export-");
    remove_dead_staging(parent, &beside)?;
    let pid = std::process::id();
    if dir.exists() {
        if !dir.is_dir() {
            bail!(
                "{} is a file, not a directory: export into a new or empty directory",
                dir.display()
            );
        }
        remove_dead_staging(dir, INSIDE_STAGING)?;
        let listing = fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))?;
        if listing.count() > 0 {
            bail!(
                "{} is not empty: export into a new or empty directory",
                dir.display()
            );
        }
        let staging = dir.join(format!("{INSIDE_STAGING}{pid}"));
        fs::create_dir(&staging).with_context(|| format!("creating {}", staging.display()))?;
        return Ok(BundleStaging {
            dir: staging,
            inside: true,
        });
    }
    fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    let staging = parent.join(format!("{beside}{pid}"));
    if staging.exists() {
        fs::remove_dir_all(&staging).with_context(|| format!("removing {}", staging.display()))?;
    }
    fs::create_dir(&staging).with_context(|| format!("creating {}", staging.display()))?;
    Ok(BundleStaging {
        dir: staging,
        inside: false,
    })
}

/// Removes the directories `<prefix><pid>` in `dir` whose process no longer
/// runs: what an export killed midway left.
fn remove_dead_staging(dir: &Path, prefix: &str) -> Result<()> {
    let Ok(listing) = fs::read_dir(dir) else {
        return Ok(());
    };
    for entry in listing.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = name
            .strip_prefix(prefix)
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        let running = Path::new("/proc").join(pid.to_string()).exists();
        if !running && entry.path().is_dir() {
            fs::remove_dir_all(entry.path())
                .with_context(|| format!("removing {}", entry.path().display()))?;
        }
    }
    Ok(())
}
