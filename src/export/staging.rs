//! Where a bundle is written: a staging directory of the store's
//! ([`Store::begin_outside`]: named with the store's id and this process,
//! marked, recorded in the store) next to the target, moved into place once
//! complete, so a bundle appears whole or not at all. Staging left by a
//! killed export is removed by its marker; a directory that merely looks
//! like staging (a user's `.export-2023/`) is never touched.

use std::fs;
use std::path::Path;

use anyhow::{Context, Result, bail};

use crate::pipeline::store::{OutsideStaging, Store};

/// Where a bundle is written before it appears at its target.
pub(super) struct BundleStaging {
    /// The marked staging directory; the bundle is its `content()`.
    staging: OutsideStaging,
    /// `true` when it lies inside the (empty) target, which may be a mount
    /// point: the bundle's entries are then moved up one by one; otherwise
    /// the whole bundle directory is renamed onto the target.
    inside: bool,
}

impl BundleStaging {
    /// The directory the bundle is written into.
    pub(super) fn dir(&self) -> std::path::PathBuf {
        self.staging.content()
    }

    /// Moves the written bundle to `target` and removes the staging.
    pub(super) fn place(self, target: &Path) -> Result<()> {
        let moved = |from: &Path, to: &Path| {
            fs::rename(from, to).with_context(|| format!("moving the bundle into {}", to.display()))
        };
        let bundle = self.dir();
        if self.inside {
            for entry in
                fs::read_dir(&bundle).with_context(|| format!("reading {}", bundle.display()))?
            {
                let name = entry?.file_name();
                moved(&bundle.join(&name), &target.join(&name))?;
            }
        } else {
            moved(&bundle, target)?;
        }
        self.abandon()
    }

    /// Removes the staging and what it holds.
    pub(super) fn abandon(self) -> Result<()> {
        let dir = self.staging.dir.clone();
        self.staging
            .finish()
            .with_context(|| format!("removing {}", dir.display()))
    }
}

/// Prefix of a staging directory inside an existing empty target.
const INSIDE_STAGING: &str = ".export-";

/// Checks the target `dir` (missing, or an empty directory, which may be a
/// mount point), removes staging of this store's exports that were killed
/// (by their marker), and creates the staging directory: inside an existing
/// target (a mount point cannot be renamed over), beside a missing one.
/// Every error names its path.
pub(super) fn prepare_target(store: &Store, dir: &Path) -> Result<BundleStaging> {
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
    store.clean_outside(parent, &beside)?;
    if dir.exists() {
        if !dir.is_dir() {
            bail!(
                "{} is a file, not a directory: export into a new or empty directory",
                dir.display()
            );
        }
        store.clean_outside(dir, INSIDE_STAGING)?;
        let listing = fs::read_dir(dir).with_context(|| format!("reading {}", dir.display()))?;
        if listing.count() > 0 {
            bail!(
                "{} is not empty: export into a new or empty directory",
                dir.display()
            );
        }
        return Ok(BundleStaging {
            staging: store.begin_outside(dir, INSIDE_STAGING)?,
            inside: true,
        });
    }
    fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
    Ok(BundleStaging {
        staging: store.begin_outside(parent, &beside)?,
        inside: false,
    })
}
