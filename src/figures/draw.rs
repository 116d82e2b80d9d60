//! Drawing a figure's points with plotters, on SVG and bitmap backends alike.

use std::ops::Range;
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{FontStyle, register_font};

use super::{DODGE, Layout, Panel, Point, Style};

/// DejaVu Sans (Bitstream Vera licence: fonts/DejaVu-LICENSE), the one font of
/// every figure.
const FONT: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

/// Colour-blind safe colours (Okabe and Ito), one per series in order.
pub const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
];

/// The size a figure is drawn at: pixels of one panel and a scale for text
/// and strokes. Plotters draws text at 1/1.24 of the size it is given (the
/// font's line height against its glyph height), hence the factor in `text`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Size {
    /// File-name suffix (`""` or `"_screen"`).
    pub suffix: &'static str,
    /// Width, px.
    pub width: u32,
    /// Height of one panel, px.
    pub panel_height: u32,
    /// Text height of every label (ticks, axes, legend), px.
    pub text: f64,
    /// Stroke width of lines, px.
    pub stroke: u32,
}

impl Size {
    /// A single journal column, 8.6 cm wide: SVG at 96 px per inch (325 px,
    /// text 11 px = 8.25 pt), PNG at 600 px per inch (2032 px).
    pub const COLUMN_SVG: Size = Size {
        suffix: "",
        width: 325,
        panel_height: 235,
        text: 11.0 * 1.24,
        stroke: 1,
    };
    /// [`Size::COLUMN_SVG`] at 600 px per inch (text 69 px = 8.25 pt).
    pub const COLUMN_PNG: Size = Size {
        suffix: "",
        width: 2032,
        panel_height: 1469,
        text: 68.75 * 1.24,
        stroke: 6,
    };
    /// A screen size: 1200 px wide.
    pub const SCREEN: Size = Size {
        suffix: "_screen",
        width: 1200,
        panel_height: 760,
        text: 20.0 * 1.24,
        stroke: 3,
    };

    /// Height of a figure of `panels` panels, px.
    pub fn height(&self, panels: usize) -> u32 {
        self.panel_height * panels.max(1) as u32
    }
}

fn register_fonts() {
    static REGISTERED: OnceLock<()> = OnceLock::new();
    REGISTERED.get_or_init(|| {
        // The font is valid (it is the crate's own file); a failure would leave
        // text undrawn, which the figure tests see.
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// The figure's files: `<name>.svg`, `<name>.png` (one column) and
/// `<name>_screen.svg`, `<name>_screen.png`.
pub fn render(
    name: &str,
    layout: &Layout,
    points: &[Point],
) -> Result<Vec<(String, Vec<u8>)>, String> {
    register_fonts();
    let mut files = Vec::new();
    for (svg, png) in [
        (Size::COLUMN_SVG, Size::COLUMN_PNG),
        (Size::SCREEN, Size::SCREEN),
    ] {
        files.push((
            format!("{name}{}.svg", svg.suffix),
            svg_bytes(layout, points, &svg)?,
        ));
        files.push((
            format!("{name}{}.png", png.suffix),
            png_bytes(layout, points, &png)?,
        ));
    }
    Ok(files)
}

fn svg_bytes(layout: &Layout, points: &[Point], size: &Size) -> Result<Vec<u8>, String> {
    let mut text = String::new();
    {
        let dimensions = (size.width, size.height(layout.panels.len()));
        let root = SVGBackend::with_string(&mut text, dimensions).into_drawing_area();
        draw(&root, layout, points, size).map_err(|e| e.to_string())?;
    }
    Ok(text.into_bytes())
}

fn png_bytes(layout: &Layout, points: &[Point], size: &Size) -> Result<Vec<u8>, String> {
    let (width, height) = (size.width, size.height(layout.panels.len()));
    let mut pixels = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
        draw(&root, layout, points, size).map_err(|e| e.to_string())?;
    }
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer
        .write_image_data(&pixels)
        .map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())?;
    Ok(bytes)
}

type DrawError<DB> = DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>;
type DrawResult<DB> = Result<(), DrawError<DB>>;

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    layout: &Layout,
    points: &[Point],
    size: &Size,
) -> DrawResult<DB> {
    root.fill(&WHITE)?;
    let areas = root.split_evenly((layout.panels.len().max(1), 1));
    for (k, (area, panel)) in areas.iter().zip(&layout.panels).enumerate() {
        let mine: Vec<&Point> = points.iter().filter(|p| p.panel == panel.name).collect();
        let tag = if layout.panels.len() > 1 {
            format!("({})", char::from(b'a' + k as u8))
        } else {
            String::new()
        };
        draw_panel(area, panel, &mine, size, &tag)?;
    }
    root.present()
}

/// The range of `values` (value, error) with their errors, padded by 4%
/// of its span, or by a factor on a log axis (positive values only there,
/// at most `decades` below the largest).
fn span(values: impl Iterator<Item = (f64, f64)>, log: bool, decades: u32) -> Range<f64> {
    let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
    for (value, error) in values {
        for v in [value - error, value, value + error] {
            if v.is_finite() && (!log || v > 0.0) {
                low = low.min(v);
                high = high.max(v);
            }
        }
    }
    if !low.is_finite() || !high.is_finite() {
        return if log { 1e-3..1.0 } else { 0.0..1.0 };
    }
    if log {
        let low = low.max(high / 10f64.powi(decades as i32));
        let pad = libm::pow(high / low, 0.04).max(1.05);
        low / pad..high * pad
    } else {
        let pad = ((high - low) * 0.04).max(high.abs().max(1e-300) * 1e-9);
        low - pad..high + pad
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    points: &[&Point],
    size: &Size,
    tag: &str,
) -> DrawResult<DB> {
    let entries = entries(panel, points);
    let strip = legend_height(area, &entries, size, tag)?;
    let (top, plot) = area.split_vertically(strip);
    draw_legend(&top, &entries, size, tag)?;
    let x_range = span(
        points.iter().map(|p| (p.x, 0.0)),
        panel.x.log,
        panel.x.decades,
    );
    let y_range = span(
        points.iter().map(|p| (p.y, p.y_error)),
        panel.y.log,
        panel.y.decades,
    );
    match (panel.x.log, panel.y.log) {
        (false, false) => chart(&plot, panel, points, size, x_range, y_range),
        (true, false) => chart(&plot, panel, points, size, x_range.log_scale(), y_range),
        (false, true) => chart(&plot, panel, points, size, x_range, y_range.log_scale()),
        (true, true) => chart(
            &plot,
            panel,
            points,
            size,
            x_range.log_scale(),
            y_range.log_scale(),
        ),
    }
}

fn chart<DB, X, Y>(
    area: &DrawingArea<DB, Shift>,
    panel: &Panel,
    points: &[&Point],
    size: &Size,
    x: X,
    y: Y,
) -> DrawResult<DB>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64>,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let text = size.text;
    let font = |scale: f64| ("sans-serif", text * scale).into_font();
    let mut chart = ChartBuilder::on(area)
        .margin((text * 0.6) as i32)
        // Room for half the widest tick label at the x axis's right end.
        .margin_right((text * 2.0) as i32)
        .x_label_area_size((text * 2.8) as i32)
        .y_label_area_size((text * 4.6) as i32)
        .build_cartesian_2d(x, y)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc(panel.x.label)
        .y_desc(panel.y.label)
        .axis_desc_style(font(1.0))
        .label_style(font(1.0))
        .x_labels(5)
        .y_labels(5)
        .x_label_formatter(&|v| tick(*v, panel.x.log))
        .y_label_formatter(&|v| tick(*v, panel.y.log))
        .set_all_tick_mark_size((text * 0.35) as i32)
        .axis_style(BLACK.stroke_width(size.stroke))
        .draw()?;
    // On a log axis, points below the shown decades are left out (not drawn
    // along the axis).
    let y_low = if panel.y.log {
        chart.y_range().start
    } else {
        f64::NEG_INFINITY
    };
    let names = series_names(points);
    let x_range = chart.x_range();
    for (k, (name, colour)) in names.iter().zip(series_colours(panel, &names)).enumerate() {
        let style = panel.style_of(name);
        let moved = if panel.dodge && style == Style::Markers {
            (k as f64 - 0.5 * (names.len() - 1) as f64) * DODGE
        } else {
            0.0
        };
        let series: Vec<Point> = points
            .iter()
            .filter(|p| p.series == *name && p.x.is_finite() && p.y.is_finite())
            .filter(|p| (!panel.x.log || p.x > 0.0) && p.y >= y_low)
            .map(|p| Point {
                x: dodged(p.x, moved, panel.x.log, &x_range),
                ..(*p).clone()
            })
            .collect();
        let series: Vec<&Point> = series.iter().collect();
        draw_series(&mut chart, style, &series, colour, size, panel.y.log)?;
    }
    for mark in &panel.marks {
        let (low, high) = (chart.y_range().start, chart.y_range().end);
        chart.draw_series(LineSeries::new(
            vec![(mark.x, low), (mark.x, high)],
            MARK.stroke_width(size.stroke),
        ))?;
    }
    Ok(())
}

/// The colour of each series of `panel`: the `k`-th series gets the `k`-th
/// colour, or with [`Panel::paired`] the `k`-th pair (series named alike up
/// to their last `", "`) does.
pub fn series_colours(panel: &Panel, names: &[&str]) -> Vec<RGBColor> {
    let mut pairs: Vec<&str> = Vec::new();
    names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let index = if panel.paired {
                let pair = name.rsplit_once(", ").map_or(*name, |(_, pair)| pair);
                if !pairs.contains(&pair) {
                    pairs.push(pair);
                }
                pairs.iter().position(|p| *p == pair).unwrap_or(k)
            } else {
                k
            };
            PALETTE[index % PALETTE.len()]
        })
        .collect()
}

/// `x` moved by the share `moved` of the axis `range` (of its decades on a
/// log axis).
fn dodged(x: f64, moved: f64, log: bool, range: &Range<f64>) -> f64 {
    if moved == 0.0 {
        x
    } else if log {
        x * libm::pow(range.end / range.start, moved)
    } else {
        x + moved * (range.end - range.start)
    }
}

/// Colour of vertical marks.
const MARK: RGBColor = RGBColor(110, 110, 110);

/// The names of the series among `points`, in order of appearance.
fn series_names<'p>(points: &[&'p Point]) -> Vec<&'p str> {
    let mut names: Vec<&str> = Vec::new();
    for point in points {
        if !names.contains(&point.series.as_str()) {
            names.push(&point.series);
        }
    }
    names
}

/// Where each legend entry goes (x, row) and how many rows they take.
type Placed = (Vec<(i32, i32)>, i32);

/// One legend entry: its sample (line or marker), colour and text.
struct Entry {
    text: String,
    style: Style,
    colour: RGBColor,
}

/// The legend entries of a panel: its series, then its marks.
fn entries(panel: &Panel, points: &[&Point]) -> Vec<Entry> {
    let names = series_names(points);
    let mut entries: Vec<Entry> = names
        .iter()
        .zip(series_colours(panel, &names))
        .map(|(name, colour)| Entry {
            text: name.to_string(),
            style: panel.style_of(name),
            colour,
        })
        .collect();
    entries.extend(panel.marks.iter().map(|mark| Entry {
        text: mark.label.to_string(),
        style: Style::Line,
        colour: MARK,
    }));
    entries
}

/// Where each legend entry goes: rows of entries filling the width (after the
/// panel tag), each entry a sample and its text. Returns (column x, row) per
/// entry and the number of rows.
fn legend_rows<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    size: &Size,
    start: i32,
) -> Result<Placed, DrawError<DB>> {
    let font = legend_font(size);
    let width = area.dim_in_pixel().0 as i32;
    let sample = (size.text * 1.6) as i32;
    let gap = (size.text * 1.0) as i32;
    let (mut x, mut row) = (start, 0);
    let mut places = Vec::new();
    for entry in entries {
        let (text_width, _) = area.estimate_text_size(&entry.text, &font)?;
        let wide = sample + gap / 3 + text_width as i32;
        if x > start && x + wide > width - gap {
            x = start;
            row += 1;
        }
        places.push((x, row));
        x += wide + gap;
    }
    Ok((places, row + 1))
}

fn legend_font(size: &Size) -> TextStyle<'static> {
    TextStyle::from(("sans-serif", size.text).into_font())
}

/// Height of one legend row, px.
fn legend_row_height(size: &Size) -> i32 {
    (size.text * 1.05) as i32
}

/// Draws the legend (with the panel's tag first) in rows on `area`, which is
/// [`legend_height`] tall.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    size: &Size,
    tag: &str,
) -> DrawResult<DB> {
    let font = legend_font(size);
    let centre = Pos::new(HPos::Left, VPos::Center);
    let margin = (size.text * 0.6) as i32;
    let row_height = legend_row_height(size);
    let mut start = margin;
    if !tag.is_empty() {
        area.draw(&Text::new(
            tag.to_string(),
            (margin, row_height / 2 + margin / 2),
            font.clone().pos(centre),
        ))?;
        start += area.estimate_text_size(tag, &font)?.0 as i32 + (size.text * 0.8) as i32;
    }
    let (places, _) = legend_rows(area, entries, size, start)?;
    let sample = (size.text * 1.6) as i32;
    for (entry, (x, row)) in entries.iter().zip(places) {
        let y = margin / 2 + row * row_height + row_height / 2;
        let line = entry.colour.stroke_width(size.stroke + 1);
        match entry.style {
            Style::Markers => {
                let radius = marker_radius(size);
                area.draw(&Circle::new(
                    (x + sample / 2, y),
                    radius,
                    entry.colour.filled(),
                ))?;
            }
            Style::Band | Style::Line => {
                area.draw(&PathElement::new(vec![(x, y), (x + sample, y)], line))?;
            }
        }
        let text_x = x + sample + (size.text * 0.35) as i32;
        area.draw(&Text::new(
            entry.text.clone(),
            (text_x, y),
            font.clone().pos(centre),
        ))?;
    }
    Ok(())
}

/// Height of the legend strip above a panel, px.
fn legend_height<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
    size: &Size,
    tag: &str,
) -> Result<u32, DrawError<DB>> {
    let margin = (size.text * 0.6) as i32;
    let start = if tag.is_empty() {
        margin
    } else {
        margin
            + area.estimate_text_size(tag, &legend_font(size))?.0 as i32
            + (size.text * 0.8) as i32
    };
    let (_, rows) = legend_rows(area, entries, size, start)?;
    Ok((rows * legend_row_height(size) + margin) as u32)
}

/// Radius of a marker, px.
fn marker_radius(size: &Size) -> i32 {
    (size.text * 0.13).max(2.0) as i32
}

/// A tick label: `1e-3` on a log axis, plain (shortest form) on a linear one.
fn tick(value: f64, log: bool) -> String {
    if log {
        let exponent = libm::log10(value).round();
        if (libm::log10(value) - exponent).abs() < 1e-9 {
            return format!("1e{exponent}");
        }
        return format!("{value:.0e}");
    }
    let rounded = (value * 1e12).round() / 1e12;
    if rounded == 0.0 {
        "0".into()
    } else if rounded.abs() >= 1e4 || rounded.abs() < 1e-3 {
        format!("{rounded:e}")
    } else {
        format!("{rounded}")
    }
}

/// One series in its style; returns the annotation for its legend entry.
fn draw_series<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    style: Style,
    series: &[&Point],
    colour: RGBColor,
    size: &Size,
    log_y: bool,
) -> DrawResult<DB>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let line = colour.stroke_width(size.stroke.max(1) + 1);
    let low = |p: &Point| {
        let low = p.y - p.y_error;
        if log_y && low <= 0.0 { p.y / 10.0 } else { low }
    };
    match style {
        Style::Band => {
            let mut outline: Vec<(f64, f64)> =
                series.iter().map(|p| (p.x, p.y + p.y_error)).collect();
            outline.extend(series.iter().rev().map(|p| (p.x, low(p))));
            chart.draw_series(std::iter::once(Polygon::new(
                outline,
                colour.mix(0.25).filled(),
            )))?;
            chart.draw_series(LineSeries::new(series.iter().map(|p| (p.x, p.y)), line))?;
        }
        Style::Line => {
            chart.draw_series(LineSeries::new(series.iter().map(|p| (p.x, p.y)), line))?;
        }
        Style::Markers => {
            let width = (size.text * 0.35) as u32;
            chart.draw_series(series.iter().filter(|p| p.y_error > 0.0).map(|p| {
                ErrorBar::new_vertical(
                    p.x,
                    low(p),
                    p.y,
                    p.y + p.y_error,
                    colour.stroke_width(size.stroke),
                    width,
                )
            }))?;
            let radius = marker_radius(size);
            chart.draw_series(
                series
                    .iter()
                    .map(|p| Circle::new((p.x, p.y), radius, colour.filled())),
            )?;
        }
    }
    Ok(())
}
