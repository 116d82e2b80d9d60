//! Figures: each figure is a long table (one row per plotted point: panel,
//! series, `x`, `y` and the error of `y`) that polars builds from the input
//! artifacts' tables, and a [`Layout`] (axes with units, log scales, marks)
//! that says how to draw it. [`render`] draws any figure as SVG and PNG at a
//! single journal column (8.6 cm wide, 8 pt text) and at a screen size, with
//! the DejaVu Sans font shipped in the binary: no system font is needed.
//!
//! Owns the drawing; the numbers come from the figure table only, so a figure
//! shows exactly what its table holds.

mod draw;
pub mod frames;
mod kernel_groups;
mod planning;
mod text;

pub mod catalogue;
pub mod collapse;
pub mod evolution;
pub mod finite_size;
pub mod gaps;
pub mod kernel_fit;
pub mod kernels;
pub mod kernels_at_theta;
pub mod kernels_density;
pub mod kernels_u_prime;
pub mod kicks;
pub mod md_boltzmann;
pub mod md_times;
pub mod near_integrable;
pub mod pulls;
pub mod rates;
pub mod spectrum;
pub mod truncation;

pub use catalogue::{Drawn, FigureKind, Keyed, PLANS, Plan, Topic};
pub use draw::{PALETTE, Size, render, series_colours};
pub use frames::{FigureRows, Point};

use serde::Serialize;

/// Kernel axis label.
const G_AXIS: &str = "G(u' → u) [ρ² l v_th / v_th]";
/// Velocity change axis label.
const DU_AXIS: &str = "u − u' [v_th]";

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Style {
    /// A line with a shaded band of +- the error.
    Band,
    /// Markers with error bars.
    Markers,
    /// A line without errors (a fit, a closed form).
    Line,
}

/// Decades a log axis shows by default, below its largest value: tails far
/// below the data's top carry no information on a figure.
pub const LOG_DECADES: u32 = 5;

/// An axis: label with its unit, and its scale.
#[derive(Clone, Debug, Serialize)]
pub struct Axis {
    /// Label, unit in brackets.
    pub label: &'static str,
    /// Logarithmic scale.
    pub log: bool,
    /// Decades shown at most on a log axis (work-precision plots need more).
    #[serde(skip_serializing_if = "is_default_decades")]
    pub decades: u32,
    /// A linear axis that starts at 0 (a positive ratio, whose distance from
    /// 0 is part of what it says).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub from_zero: bool,
}

impl Axis {
    /// A linear axis.
    pub fn linear(label: &'static str) -> Axis {
        Axis {
            label,
            log: false,
            decades: LOG_DECADES,
            from_zero: false,
        }
    }

    /// A linear axis from 0.
    pub fn from_zero(label: &'static str) -> Axis {
        Axis {
            from_zero: true,
            ..Axis::linear(label)
        }
    }

    /// A log axis showing [`LOG_DECADES`] decades.
    pub fn log(label: &'static str) -> Axis {
        Axis {
            log: true,
            ..Axis::linear(label)
        }
    }
}

fn is_default_decades(decades: &u32) -> bool {
    *decades == LOG_DECADES
}

/// A vertical line with a label (e.g. the paper's truncation).
#[derive(Clone, Debug, Serialize)]
pub struct Mark {
    /// Where.
    pub x: f64,
    /// What it marks.
    pub label: &'static str,
}

/// One panel: its axes, marks and how each series is drawn.
#[derive(Clone, Debug, Serialize)]
pub struct Panel {
    /// Name in the figure table's `panel` column, and the panel's tag (`(a)`).
    pub name: &'static str,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// Vertical marks.
    pub marks: Vec<Mark>,
    /// Style of a series by the start of its name (unlisted: markers).
    pub styles: Vec<(&'static str, Style)>,
    /// Series named alike after their last `", "` (`Boltzmann, 960 ns`, `MD,
    /// 960 ns`) share a colour, told apart by their styles.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub paired: bool,
    /// With `paired`, the pairs whose colours are fixed, in palette order
    /// (the same in every panel of a figure, whichever pairs it holds);
    /// other pairs follow in the order they appear.
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    pub pair_order: &'static [&'static str],
    /// Marker series drawn side by side: the `k`-th of `n` moved along the
    /// horizontal axis by `(k - (n - 1) / 2)` times [`DODGE`] of its span
    /// (in decades on a log axis), so points of several series at one `x`
    /// stay apart. Drawing only: the figure table keeps the true `x`.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub dodge: bool,
    /// Series drawn in distinct dash patterns (the `k`-th series the `k`-th
    /// of [`DASHES`]), so that curves lying on one another stay visible.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub dashed: bool,
    /// What the panel shows, after its tag (`(a) tagged particles`).
    #[serde(skip_serializing_if = "str::is_empty")]
    pub title: &'static str,
    /// A horizontal reference line (at 1 where a ratio is plotted).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub level: Option<f64>,
}

/// The share of the horizontal axis between neighbouring series of a
/// [`Panel::dodge`] panel.
pub const DODGE: f64 = 0.012;

/// Dash patterns of a [`Panel::dashed`] panel's series in order, (dash,
/// gap) in text heights, `None` solid: lengths that differ, so that lines on
/// one another show each colour in turn.
pub const DASHES: [Option<(f64, f64)>; 6] = [
    None,
    Some((0.9, 0.3)),
    Some((0.15, 0.3)),
    Some((0.45, 0.2)),
    Some((1.5, 0.45)),
    Some((0.08, 0.6)),
];

impl Panel {
    /// A panel of series drawn by `styles`, without marks, titles or
    /// reference levels, each series in its own colour, solid.
    pub fn new(name: &'static str, x: Axis, y: Axis, styles: Vec<(&'static str, Style)>) -> Panel {
        Panel {
            name,
            x,
            y,
            marks: Vec::new(),
            styles,
            paired: false,
            pair_order: &[],
            dodge: false,
            dashed: false,
            title: "",
            level: None,
        }
    }

    /// How the series `name` is drawn.
    pub fn style_of(&self, name: &str) -> Style {
        self.styles
            .iter()
            .find(|(pattern, _)| name.starts_with(pattern))
            .map_or(Style::Markers, |(_, style)| *style)
    }

    /// The dash pattern of the `k`-th series (see [`DASHES`]).
    pub fn dash_of(&self, k: usize) -> Option<(f64, f64)> {
        if self.dashed {
            DASHES[k % DASHES.len()]
        } else {
            None
        }
    }
}

/// A figure's drawing instructions: its panels, stacked.
#[derive(Clone, Debug, Serialize)]
pub struct Layout {
    /// Panels, top to bottom.
    pub panels: Vec<Panel>,
}
