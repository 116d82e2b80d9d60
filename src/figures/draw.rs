//! Drawing a figure's points with plotters, on SVG and bitmap backends alike.

use std::ops::Range;

use plotters::coord::Shift;
use plotters::coord::combinators::WithKeyPoints;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::element::{ComposedElement, DashedPathElement};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::text::{FAMILY, Typeset};
use super::{Axis, DODGE, Layout, Panel, Point, Style};

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
    /// Resolution the file is meant to be shown at, px per inch (a PNG's
    /// `pHYs` chunk).
    pub pixels_per_inch: f64,
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
        pixels_per_inch: 96.0,
    };
    /// [`Size::COLUMN_SVG`] at 600 px per inch (text 69 px = 8.25 pt).
    pub const COLUMN_PNG: Size = Size {
        suffix: "",
        width: 2032,
        panel_height: 1469,
        text: 68.75 * 1.24,
        stroke: 6,
        pixels_per_inch: 600.0,
    };
    /// A screen size: 1200 px wide, at a screen's 96 px per inch.
    pub const SCREEN: Size = Size {
        suffix: "_screen",
        width: 1200,
        panel_height: 760,
        text: 20.0 * 1.24,
        stroke: 3,
        pixels_per_inch: 96.0,
    };

    /// Height of a figure of `panels` panels, px.
    pub fn height(&self, panels: usize) -> u32 {
        self.panel_height * panels.max(1) as u32
    }

    /// The resolution as a PNG's `pHYs` chunk states it: pixels per metre.
    pub fn pixels_per_metre(&self) -> u32 {
        (self.pixels_per_inch / METRES_PER_INCH).round() as u32
    }

    /// This size drawn `factor` times finer: every length `factor` times
    /// longer.
    fn scaled(&self, factor: u32) -> Size {
        Size {
            width: self.width * factor,
            panel_height: self.panel_height * factor,
            text: self.text * f64::from(factor),
            stroke: self.stroke * factor,
            pixels_per_inch: self.pixels_per_inch * f64::from(factor),
            ..*self
        }
    }
}

/// SVG user units per pixel: an SVG is drawn this much finer than its size
/// and shown at its size through its `viewBox`, so that curves keep a tenth
/// of a pixel (plotters places everything on whole units).
const SVG_UNITS_PER_PX: u32 = 10;

/// One inch, m.
const METRES_PER_INCH: f64 = 0.0254;

/// The figure's files: `<name>.svg`, `<name>.png` (one column) and
/// `<name>_screen.svg`, `<name>_screen.png`.
pub fn render(
    name: &str,
    layout: &Layout,
    points: &[Point],
) -> Result<Vec<(String, Vec<u8>)>, String> {
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

/// The SVG drawn [`SVG_UNITS_PER_PX`] times finer than `size`, its `width`
/// and `height` those of `size` (its `viewBox` the finer drawing's).
fn svg_bytes(layout: &Layout, points: &[Point], size: &Size) -> Result<Vec<u8>, String> {
    let fine = size.scaled(SVG_UNITS_PER_PX);
    let panels = layout.panels.len();
    let mut text = String::new();
    {
        let backend = SVGBackend::with_string(&mut text, (fine.width, fine.height(panels)));
        let root = Typeset::vector(backend).into_drawing_area();
        draw(&root, layout, points, &fine).map_err(|e| e.to_string())?;
    }
    let dimensions = |size: &Size| {
        format!(
            "<svg width=\"{}\" height=\"{}\"",
            size.width,
            size.height(panels)
        )
    };
    let drawn = dimensions(&fine);
    if !text.starts_with(&drawn) {
        return Err(format!("an SVG starting otherwise than `{drawn}`"));
    }
    Ok(text.replacen(&drawn, &dimensions(size), 1).into_bytes())
}

fn png_bytes(layout: &Layout, points: &[Point], size: &Size) -> Result<Vec<u8>, String> {
    let (width, height) = (size.width, size.height(layout.panels.len()));
    let mut pixels = vec![0u8; (width * height * 3) as usize];
    {
        let backend = BitMapBackend::with_buffer(&mut pixels, (width, height));
        let root = Typeset::bitmap(backend).into_drawing_area();
        draw(&root, layout, points, size).map_err(|e| e.to_string())?;
    }
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let resolution = size.pixels_per_metre();
    encoder.set_pixel_dims(Some(png::PixelDimensions {
        xppu: resolution,
        yppu: resolution,
        unit: png::Unit::Meter,
    }));
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
        let letter = if layout.panels.len() > 1 {
            format!("({})", char::from(b'a' + k as u8))
        } else {
            String::new()
        };
        let tag = [letter.as_str(), panel.title]
            .into_iter()
            .filter(|part| !part.is_empty())
            .collect::<Vec<_>>()
            .join(" ");
        draw_panel(area, panel, &mine, size, &tag)?;
    }
    root.present()
}

/// The range of `values` (value, error) with their errors on `axis`,
/// padded by 4% of its span (from 0 on an axis that starts there), or by a
/// factor on a log axis (positive values only there, at most its decades
/// below the largest).
fn span(values: impl Iterator<Item = (f64, f64)>, axis: &Axis) -> Range<f64> {
    let (log, decades) = (axis.log, axis.decades);
    let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
    if axis.from_zero {
        (low, high) = (0.0, 0.0);
    }
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
    let x_range = span(points.iter().map(|p| (p.x, 0.0)), &panel.x);
    let y_range = span(points.iter().map(|p| (p.y, p.y_error)), &panel.y);
    let labels = [
        Labels::of(&x_range, panel.x.log),
        Labels::of(&y_range, panel.y.log),
    ];
    let plot = (&plot, labels);
    match (panel.x.log, panel.y.log) {
        (false, false) => chart(plot, panel, points, size, x_range, y_range),
        (true, false) => chart(plot, panel, points, size, log_axis(x_range), y_range),
        (false, true) => chart(plot, panel, points, size, x_range, log_axis(y_range)),
        (true, true) => chart(
            plot,
            panel,
            points,
            size,
            log_axis(x_range),
            log_axis(y_range),
        ),
    }
}

/// How an axis writes its tick labels.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Labels {
    /// The number's shortest form (`0.05`, `20`; powers of ten below 1e-3
    /// and from 1e4 on).
    Plain,
    /// Powers of ten (`10⁻³`, `2×10⁻³`).
    Powers,
}

impl Labels {
    /// A linear axis, or a log axis over fewer than three decades (ticked at
    /// 1, 2 and 5 times the powers of ten, [`log_ticks`]) whose ticks all have
    /// a plain form, reads plainly (`1, 2, 5, 10, 20`, not `10⁰, 2×10⁰, ...`);
    /// a log axis over more decades by its powers of ten.
    fn of(range: &Range<f64>, log: bool) -> Labels {
        if !log {
            return Labels::Plain;
        }
        let ticks = log_ticks(range);
        let decades_only = ticks.iter().all(|&t| is_power_of_ten(t));
        let plain = |t: &f64| (1e-3..1e4).contains(t);
        if !decades_only && ticks.iter().all(plain) {
            Labels::Plain
        } else {
            Labels::Powers
        }
    }
}

/// `true` when `value` is a power of ten (to rounding).
fn is_power_of_ten(value: f64) -> bool {
    let exponent = libm::log10(value);
    (exponent - exponent.round()).abs() < 1e-9
}

/// A log axis over `range` with its ticks ([`log_ticks`]).
fn log_axis(range: Range<f64>) -> LogAxis {
    LogAxis(range)
}

/// The range of a log axis, drawn with the ticks of [`log_ticks`].
#[derive(Clone)]
struct LogAxis(Range<f64>);

impl From<LogAxis> for WithKeyPoints<LogCoord<f64>> {
    fn from(axis: LogAxis) -> Self {
        let ticks = log_ticks(&axis.0);
        axis.0.log_scale().with_key_points(ticks)
    }
}

impl AsRangedCoord for LogAxis {
    type CoordDescType = WithKeyPoints<LogCoord<f64>>;
    type Value = f64;
}

/// Ticks of a log axis: every power of ten in `range`, and where fewer
/// than three fall in it also their doubles and fives (an axis over less
/// than two decades otherwise reads by one or two labels).
fn log_ticks(range: &Range<f64>) -> Vec<f64> {
    let first = libm::floor(libm::log10(range.start)) as i32;
    let last = libm::ceil(libm::log10(range.end)) as i32;
    let at = |multiples: &[f64]| -> Vec<f64> {
        (first..=last)
            .flat_map(|exponent| {
                let decade = libm::pow(10.0, f64::from(exponent));
                multiples.iter().map(move |m| m * decade)
            })
            .filter(|value| range.contains(value))
            .collect()
    };
    let decades = at(&[1.0]);
    if decades.len() >= 3 {
        decades
    } else {
        at(&[1.0, 2.0, 5.0])
    }
}

fn chart<DB, X, Y>(
    (area, labels): (&DrawingArea<DB, Shift>, [Labels; 2]),
    panel: &Panel,
    points: &[&Point],
    size: &Size,
    x: X,
    y: Y,
) -> DrawResult<DB>
where
    DB: DrawingBackend,
    X: AsRangedCoord<Value = f64>,
    Y: AsRangedCoord<Value = f64> + Clone,
    X::CoordDescType: ValueFormatter<f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let text = size.text;
    let font = |scale: f64| (FAMILY, text * scale).into_font();
    let y_labels = y_label_width(area, &y, labels[1], &font(1.0).into())?;
    let mut chart = ChartBuilder::on(area)
        .margin((text * 0.6) as i32)
        // Room for half the widest tick label at the x axis's right end.
        .margin_right((text * 2.0) as i32)
        .x_label_area_size((text * 2.8) as i32)
        // The widest tick label, the tick marks and the rotated axis title.
        .y_label_area_size((text * 4.6).max(f64::from(y_labels) + text * 2.6) as i32)
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
        .x_label_formatter(&|v| tick(*v, labels[0]))
        .y_label_formatter(&|v| tick(*v, labels[1]))
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
    let x_range = chart.x_range();
    if let Some(level) = panel.level {
        let line = vec![(x_range.start, level), (x_range.end, level)];
        let (dash, gap) = in_pixels(LEVEL_DASH, size);
        chart.draw_series(DashedLineSeries::new(
            line,
            dash,
            gap,
            MARK.stroke_width(size.stroke),
        ))?;
    }
    let names = series_names(points);
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
        let pen = Pen {
            colour,
            dash: panel.dash_of(k),
        };
        let floor = panel.y.log.then_some(y_low);
        draw_series(&mut chart, style, &series, pen, size, floor)?;
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
/// to their last `", "`) does, after those of [`Panel::pair_order`].
pub fn series_colours(panel: &Panel, names: &[&str]) -> Vec<RGBColor> {
    let mut pairs: Vec<&str> = Vec::new();
    names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let index = if panel.paired {
                let pair = name.rsplit_once(", ").map_or(*name, |(_, pair)| pair);
                let fixed = panel.pair_order.iter().position(|p| *p == pair);
                fixed.unwrap_or_else(|| {
                    if !pairs.contains(&pair) {
                        pairs.push(pair);
                    }
                    let later = pairs.iter().position(|p| *p == pair).unwrap_or(k);
                    panel.pair_order.len() + later
                })
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

/// Colour of vertical marks and reference levels.
const MARK: RGBColor = RGBColor(110, 110, 110);

/// Dash pattern of a reference level, (dash, gap) in text heights.
const LEVEL_DASH: (f64, f64) = (0.4, 0.3);

/// A dash pattern in text heights as whole pixels of `size`.
fn in_pixels((dash, gap): (f64, f64), size: &Size) -> (u32, u32) {
    let px = |length: f64| (length * size.text).round().max(1.0) as u32;
    (px(dash), px(gap))
}

/// How a series' lines are drawn: its colour and dash pattern (in text
/// heights, `None` solid).
#[derive(Clone, Copy)]
struct Pen {
    colour: RGBColor,
    dash: Option<(f64, f64)>,
}

/// A line through `points` with `pen`, `width` px wide.
fn draw_line<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    points: &[&Point],
    pen: Pen,
    width: u32,
    size: &Size,
) -> DrawResult<DB>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let line = pen.colour.stroke_width(width);
    let path = points.iter().map(|p| (p.x, p.y));
    match pen.dash {
        None => chart.draw_series(LineSeries::new(path, line))?,
        Some(dash) => {
            let (dash, gap) = in_pixels(dash, size);
            chart.draw_series(DashedLineSeries::new(path, dash, gap, line))?
        }
    };
    Ok(())
}

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

/// One legend entry: its sample (line or marker), pen and text.
struct Entry {
    text: String,
    style: Style,
    pen: Pen,
}

/// The legend entries of a panel: its series, then its marks.
fn entries(panel: &Panel, points: &[&Point]) -> Vec<Entry> {
    let names = series_names(points);
    let mut entries: Vec<Entry> = names
        .iter()
        .zip(series_colours(panel, &names))
        .enumerate()
        .map(|(k, (name, colour))| Entry {
            text: name.to_string(),
            style: panel.style_of(name),
            pen: Pen {
                colour,
                dash: panel.dash_of(k),
            },
        })
        .collect();
    entries.extend(panel.marks.iter().map(|mark| Entry {
        text: mark.label.to_string(),
        style: Style::Line,
        pen: Pen {
            colour: MARK,
            dash: None,
        },
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
    TextStyle::from((FAMILY, size.text).into_font())
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
        let line = entry.pen.colour.stroke_width(size.stroke + 1);
        let path = vec![(x, y), (x + sample, y)];
        match (entry.style, entry.pen.dash) {
            (Style::Markers, _) => {
                let radius = marker_radius(size);
                area.draw(&Circle::new(
                    (x + sample / 2, y),
                    radius,
                    entry.pen.colour.filled(),
                ))?;
            }
            (Style::Band | Style::Line, None) => area.draw(&PathElement::new(path, line))?,
            (Style::Band | Style::Line, Some(dash)) => {
                let (dash, gap) = in_pixels(dash, size);
                area.draw(&DashedPathElement::new(path, dash, gap, line))?
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

/// A tick label: in [`Labels::Powers`] `10⁻³` at a decade, `2×10⁻³`
/// between decades; in [`Labels::Plain`] the number's shortest form,
/// `5×10⁻⁴` below 1e-3 or from 1e4 on. Negative numbers take a minus sign
/// (U+2212).
fn tick(value: f64, labels: Labels) -> String {
    let label = if labels == Labels::Powers {
        if is_power_of_ten(value) {
            power_of_ten(libm::log10(value).round() as i32)
        } else {
            scientific(&format!("{value:.0e}"))
        }
    } else {
        let rounded = (value * 1e12).round() / 1e12;
        if rounded == 0.0 {
            "0".into()
        } else if rounded.abs() >= 1e4 || rounded.abs() < 1e-3 {
            scientific(&format!("{rounded:e}"))
        } else {
            format!("{rounded}")
        }
    };
    label.replace('-', "−")
}

/// Width in pixels of the widest tick label plotters will write on the y axis
/// (the same key points as `.y_labels(5)`): `2×10⁻⁴` is twice as wide as `20`.
fn y_label_width<DB, Y>(
    area: &DrawingArea<DB, Shift>,
    y: &Y,
    labels: Labels,
    font: &TextStyle,
) -> Result<u32, DrawError<DB>>
where
    DB: DrawingBackend,
    Y: AsRangedCoord<Value = f64> + Clone,
{
    let spec: Y::CoordDescType = y.clone().into();
    let mut widest = 0;
    for value in spec.key_points(5) {
        widest = widest.max(area.estimate_text_size(&tick(value, labels), font)?.0);
    }
    Ok(widest)
}

/// A number in Rust's `e` notation (`2e-3`, `1e4`) as `2×10⁻³`, `10⁴`.
fn scientific(e_notation: &str) -> String {
    let (mantissa, exponent) = e_notation.split_once('e').unwrap_or((e_notation, "0"));
    let power = power_of_ten(exponent.parse().unwrap_or(0));
    if mantissa == "1" {
        power
    } else {
        format!("{mantissa}×{power}")
    }
}

/// `10⁻⁴`: ten to `exponent`, in Unicode superscripts (DejaVu Sans has
/// them, so PNG and SVG alike show them).
fn power_of_ten(exponent: i32) -> String {
    let superscript = |c: char| match c {
        '-' => '⁻',
        '1' => '¹',
        '2' => '²',
        '3' => '³',
        digit => char::from_u32(0x2070 + digit.to_digit(10).unwrap_or(0)).unwrap_or(digit),
    };
    let digits: String = exponent.to_string().chars().map(superscript).collect();
    format!("10{digits}")
}

/// One series in its style. On a log axis (`floor`: the frame's bottom)
/// an error whose lower end is at or below zero has no place there: its band
/// reaches down to the frame's bottom, its bar is drawn open ([`open_bar`]).
fn draw_series<DB, X, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    style: Style,
    series: &[&Point],
    pen: Pen,
    size: &Size,
    floor: Option<f64>,
) -> DrawResult<DB>
where
    DB: DrawingBackend,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    let (colour, width) = (pen.colour, size.stroke.max(1) + 1);
    // The lower end drawn, and whether it is open (the frame's bottom).
    let low = |p: &Point| {
        let low = p.y - p.y_error;
        match floor {
            Some(bottom) if low <= 0.0 => (bottom, true),
            _ => (low, false),
        }
    };
    match style {
        Style::Band => {
            let mut outline: Vec<(f64, f64)> =
                series.iter().map(|p| (p.x, p.y + p.y_error)).collect();
            outline.extend(series.iter().rev().map(|p| (p.x, low(p).0)));
            chart.draw_series(std::iter::once(Polygon::new(
                outline,
                colour.mix(0.25).filled(),
            )))?;
            draw_line(chart, series, pen, width, size)?;
        }
        Style::Line => draw_line(chart, series, pen, width, size)?,
        Style::Markers => {
            let width = (size.text * 0.35) as u32;
            let bar = colour.stroke_width(size.stroke);
            let (open, closed): (Vec<&Point>, Vec<&Point>) = series
                .iter()
                .copied()
                .filter(|p| p.y_error > 0.0)
                .partition(|p| low(p).1);
            chart.draw_series(closed.iter().map(|p| {
                ErrorBar::new_vertical(p.x, low(p).0, p.y, p.y + p.y_error, bar, width)
            }))?;
            let open: Vec<_> = open
                .iter()
                .map(|p| {
                    let bottom = (p.x, low(p).0);
                    let drop = chart.backend_coord(&bottom).1
                        - chart.backend_coord(&(p.x, p.y + p.y_error)).1;
                    open_bar(bottom, drop, bar, width as i32)
                })
                .collect();
            chart.draw_series(open)?;
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

/// An error bar open downward: from its upper end, `drop` px above
/// `bottom` (the frame's bottom edge) and capped `width` px wide like a
/// closed bar, down to `bottom`, where it ends in an arrow head.
fn open_bar<DB: DrawingBackend>(
    bottom: (f64, f64),
    drop: i32,
    style: ShapeStyle,
    width: i32,
) -> OpenBar<DB> {
    let half = width / 2;
    let cap_and_bar = vec![(-half, -drop), (half, -drop), (0, -drop), (0, 0)];
    EmptyElement::at(bottom)
        + PathElement::new(cap_and_bar, style)
        + Polygon::new(
            vec![(0, 0), (-half, -width), (half, -width)],
            style.filled(),
        )
}

/// The elements of an [`open_bar`]: a path and a triangle placed in pixels
/// from a point of the chart.
type OpenBar<DB> = ComposedElement<(f64, f64), DB, PathElement<(i32, i32)>, Polygon<(i32, i32)>>;

#[cfg(test)]
mod tests {
    use super::{Labels, log_ticks, tick};

    /// Ticks at the decades of an axis over three or more, at 1, 2 and 5
    /// times them over fewer.
    #[test]
    fn short_log_axes_tick_at_doubles_and_fives() {
        let close = |got: Vec<f64>, want: &[f64]| {
            got.len() == want.len()
                && got
                    .iter()
                    .zip(want)
                    .all(|(g, w)| (g / w - 1.0).abs() < 1e-12)
        };
        assert!(close(log_ticks(&(9e-6..2e-2)), &[1e-5, 1e-4, 1e-3, 1e-2]));
        let short = log_ticks(&(0.015..0.6));
        assert!(
            close(short.clone(), &[0.02, 0.05, 0.1, 0.2, 0.5]),
            "{short:?}"
        );
    }

    #[test]
    fn log_ticks_are_powers_of_ten_in_superscripts() {
        assert_eq!(tick(1e-4, Labels::Powers), "10⁻⁴");
        assert_eq!(tick(1.0, Labels::Powers), "10⁰");
        assert_eq!(tick(1e12, Labels::Powers), "10¹²");
        assert_eq!(tick(2e-3, Labels::Powers), "2×10⁻³");
    }

    #[test]
    fn log_axes_over_few_plain_decades_read_plainly() {
        assert_eq!(Labels::of(&(0.8..40.0), true), Labels::Plain);
        assert_eq!(tick(2.0, Labels::Plain), "2");
        assert_eq!(tick(0.05, Labels::Plain), "0.05");
        // Many decades, or ticks beyond the plain forms: powers of ten.
        assert_eq!(Labels::of(&(1e-6..1.0), true), Labels::Powers);
        assert_eq!(Labels::of(&(1e-5..4e-4), true), Labels::Powers);
        assert_eq!(Labels::of(&(1e-6..1.0), false), Labels::Plain);
    }

    #[test]
    fn linear_ticks_take_minus_signs_and_powers_of_ten() {
        assert_eq!(tick(-0.05, Labels::Plain), "−0.05");
        assert_eq!(tick(0.0, Labels::Plain), "0");
        assert_eq!(tick(15.0, Labels::Plain), "15");
        assert_eq!(tick(-5e-4, Labels::Plain), "−5×10⁻⁴");
        assert_eq!(tick(2e4, Labels::Plain), "2×10⁴");
    }
}
