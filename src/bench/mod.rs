//! Work-precision benchmarks (not tests): error against CPU time, measured in
//! one process so that ratios between methods are meaningful. Results are
//! recorded in docs/benchmarks.md with the command that produced them. Part of
//! the command line, not of the library; the kernel benchmark takes the
//! study's engine, offset proposal, bins and fit range from `--config`.
//!
//! One benchmark per file (integrators, kernel, quadrature, far kernel, md, balance),
//! the sampler runs of the kernel benchmarks in `sampler.rs`, this machine's speed
//! for `status`'s estimate in `speed.rs`; this file holds the
//! work-precision figure they share.

use std::path::{Path, PathBuf};

use ternary::figures::{Axis, Layout, Panel, Point, Style, render};

mod balance;
mod far_kernel;
mod integrators;
mod kernel;
mod md;
mod quadrature;
mod sampler;
mod speed;

pub use balance::{BalanceBenchOptions, balance};
pub use far_kernel::far_kernel;
pub use integrators::{WorkPrecisionOptions, integrators};
pub use kernel::kernel;
pub use md::{MdBenchOptions, md};
pub use sampler::{KernelBenchOptions, StudySettings};
pub use speed::machine_slowness;

/// A benchmark's work-precision figure: error against cost, drawn like the
/// study's figures (SVG and PNG, one column and screen size).
pub struct BenchFigure {
    /// File stem, e.g. `work_precision_kernel`.
    pub name: &'static str,
    /// Axes and styles.
    pub layout: Layout,
    /// The measured points.
    pub points: Vec<Point>,
}

impl BenchFigure {
    /// Writes the figure's files into `dir` (created if missing); their paths.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        render(self.name, &self.layout, &self.points)?
            .into_iter()
            .map(|(file, bytes)| {
                let path = dir.join(file);
                std::fs::write(&path, bytes).map_err(|e| format!("{}: {e}", path.display()))?;
                Ok(path)
            })
            .collect()
    }
}

/// A log-log work-precision panel: `y` against seconds.
fn work_precision_panel(
    name: &'static str,
    x: &'static str,
    y: &'static str,
    style: Style,
) -> Panel {
    // Errors span up to ten decades (integrator tolerances 1e-5..1e-14).
    let y = Axis {
        decades: 12,
        ..Axis::log(y)
    };
    Panel::new(name, Axis::log(x), y, vec![("", style)])
}

/// A point of `series` in `panel`; only positive errors can be drawn on log axes.
fn work_precision_point(panel: &str, series: &str, x: f64, y: f64, y_error: f64) -> Option<Point> {
    (x > 0.0 && y > 0.0).then(|| Point {
        panel: panel.to_string(),
        series: series.to_string(),
        x,
        y,
        y_error,
    })
}

/// The sizes of a work-precision table: `points * num / den` for each
/// `(num, den)`, at least 16, each once (the default 4096 points gives 2^10
/// to 2^16 sampled scenes and 64 to 12288 quadrature pairs).
fn work_precision_sizes(points: u32, ratios: &[(u32, u32)]) -> Vec<u32> {
    let mut sizes: Vec<u32> = ratios
        .iter()
        .map(|&(num, den)| (points * num / den).max(16))
        .collect();
    sizes.dedup();
    sizes
}
