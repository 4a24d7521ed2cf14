//! Figures as SVG (plotters): one or more panels in a grid, and a legend in a strip of its own to
//! the right of them, so that no legend ever covers data. Each SVG carries, in a `<metadata>`
//! element, the pixel rectangles of its plot areas and of its legend ([`AREAS_ID`]), so that a
//! test can render it and look for data where data should be.
//!
//! Colours follow the labels: a series without an explicit colour takes the palette colour of its
//! label, the same in every panel of a figure.

use plotters::coord::Shift;
use plotters::coord::ranged1d::SegmentValue;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::collections::HashMap;
use std::ops::Range;
use thiserror::Error;

#[derive(Debug, Error)]
pub enum ChartError {
    #[error("figure `{figure}`: {message}")]
    Draw { figure: String, message: String },
}

/// `id` of the `<metadata>` element listing the areas: one line per area,
/// `plot x0 y0 x1 y1` or `legend x0 y0 x1 y1`, in pixels of the SVG's view box.
pub const AREAS_ID: &str = "slidestack-areas";

/// Colour of [`Mark::Faint`] lines.
pub const FAINT: RGBColor = RGBColor(200, 200, 200);

/// The palette (Tableau 10), given to labels in order of first appearance.
pub const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(188, 189, 34),
    RGBColor(127, 127, 127),
];

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stroke {
    Solid,
    Dashed,
    Dotted,
}

/// How a series is drawn.
#[derive(Debug, Clone, PartialEq)]
pub enum Mark {
    Line {
        stroke: Stroke,
        width: u32,
    },
    /// Filled circles; `opacity` below 1 lets dense clouds show their density.
    Points {
        radius: u32,
        opacity: f64,
    },
    /// A line with a circle at every point.
    LinePoints,
    /// A thin light grey line (e.g. every motion behind the mean).
    Faint,
    /// The area between `lower` and the series' `y`, lightly filled.
    Band {
        lower: Vec<f64>,
    },
}

/// One curve, point set or band of a panel. An empty label gives no legend entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub label: String,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    pub mark: Mark,
    /// `None`: the palette colour of the label.
    pub colour: Option<RGBColor>,
}

impl Series {
    pub fn line(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            label: label.into(),
            x,
            y,
            mark: Mark::Line {
                stroke: Stroke::Solid,
                width: 2,
            },
            colour: None,
        }
    }
    pub fn points(label: impl Into<String>, x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            mark: Mark::Points {
                radius: 3,
                opacity: 1.0,
            },
            ..Self::line(label, x, y)
        }
    }
    pub fn faint(x: Vec<f64>, y: Vec<f64>) -> Self {
        Self {
            mark: Mark::Faint,
            ..Self::line("", x, y)
        }
    }
    /// The area between `lower` and `upper` over `x`.
    pub fn band(label: impl Into<String>, x: Vec<f64>, lower: Vec<f64>, upper: Vec<f64>) -> Self {
        Self {
            mark: Mark::Band { lower },
            ..Self::line(label, x, upper)
        }
    }
    /// A horizontal line at `y` over `[x0, x1]`.
    pub fn hline(label: impl Into<String>, x0: f64, x1: f64, y: f64) -> Self {
        Self::line(label, vec![x0, x1], vec![y, y])
    }
    /// A vertical line at `x` over `[y0, y1]`.
    pub fn vline(label: impl Into<String>, x: f64, y0: f64, y1: f64) -> Self {
        Self::line(label, vec![x, x], vec![y0, y1])
    }
    pub fn stroke(mut self, stroke: Stroke, width: u32) -> Self {
        self.mark = Mark::Line { stroke, width };
        self
    }
    pub fn mark(mut self, mark: Mark) -> Self {
        self.mark = mark;
        self
    }
    pub fn colour(mut self, c: RGBColor) -> Self {
        self.colour = Some(c);
        self
    }
}

/// An axis: its description (with its unit), a fixed range or `None` for the data's, and
/// whether it is logarithmic (values ≤ 0 are then left out).
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    pub label: String,
    pub range: Option<(f64, f64)>,
    pub log: bool,
}

impl Axis {
    pub fn new(label: impl Into<String>) -> Self {
        Self {
            label: label.into(),
            range: None,
            log: false,
        }
    }
    pub fn range(mut self, lo: f64, hi: f64) -> Self {
        self.range = Some((lo, hi));
        self
    }
    pub fn log(mut self) -> Self {
        self.log = true;
        self
    }
}

/// One segment of stacked horizontal bars: its label and its length in each category.
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    pub label: String,
    pub values: Vec<f64>,
    pub colour: Option<RGBColor>,
}

/// What a panel draws.
#[derive(Debug, Clone, PartialEq)]
pub enum Plot {
    Xy(Vec<Series>),
    /// Horizontal bars, one per category (top first), each the sum of its segments.
    StackedBars {
        categories: Vec<String>,
        segments: Vec<Segment>,
    },
}

#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    pub title: String,
    pub x: Axis,
    pub y: Axis,
    pub plot: Plot,
}

impl Panel {
    pub fn xy(title: impl Into<String>, x: Axis, y: Axis, series: Vec<Series>) -> Self {
        Self {
            title: title.into(),
            x,
            y,
            plot: Plot::Xy(series),
        }
    }
}

/// Panels in a grid of `columns`, each `panel_px` pixels, under a title; ranges shared across
/// panels where asked (fixed ranges of an axis always win).
#[derive(Debug, Clone, PartialEq)]
pub struct Figure {
    pub title: String,
    pub panels: Vec<Panel>,
    pub columns: usize,
    pub panel_px: (u32, u32),
    pub share_x: bool,
    pub share_y: bool,
}

impl Figure {
    /// One panel.
    pub fn single(title: impl Into<String>, panel: Panel) -> Self {
        Self {
            title: title.into(),
            panels: vec![panel],
            columns: 1,
            panel_px: (640, 420),
            share_x: false,
            share_y: false,
        }
    }
    /// Several panels with shared axes.
    pub fn grid(title: impl Into<String>, panels: Vec<Panel>, columns: usize) -> Self {
        Self {
            title: title.into(),
            panels,
            columns: columns.max(1),
            panel_px: (330, 250),
            share_x: true,
            share_y: true,
        }
    }
    pub fn panel_px(mut self, w: u32, h: u32) -> Self {
        self.panel_px = (w, h);
        self
    }
}

const TITLE_PX: u32 = 34;
const LEGEND_ROW_PX: i32 = 18;
const LEGEND_FONT: u32 = 13;

/// What a legend entry shows.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Sample {
    Line(RGBColor, Stroke, u32),
    Point(RGBColor),
    LinePoint(RGBColor),
    /// A light fill (bands).
    Area(RGBColor),
    /// A full fill (bars).
    Bar(RGBColor),
}

fn transform(v: &[f64], log: bool) -> Vec<f64> {
    if !log {
        return v.to_vec();
    }
    v.iter()
        .map(|x| if *x > 0.0 { x.log10() } else { f64::NAN })
        .collect()
}

/// The finite range of some values, padded by 4 % (a unit range when there are none).
fn padded(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    let pad = if span > 0.0 {
        0.04 * span
    } else {
        0.05 * lo.abs().max(1.0)
    };
    (lo - pad, hi + pad)
}

fn axis_values<'a>(p: &'a Panel, x: bool) -> Box<dyn Iterator<Item = f64> + 'a> {
    match &p.plot {
        Plot::Xy(series) => {
            let log = if x { p.x.log } else { p.y.log };
            Box::new(series.iter().flat_map(move |s| {
                let mut v = if x { s.x.clone() } else { s.y.clone() };
                if let (false, Mark::Band { lower }) = (x, &s.mark) {
                    v.extend_from_slice(lower);
                }
                transform(&v, log)
            }))
        }
        Plot::StackedBars { segments, .. } => {
            let cats = segments.first().map_or(0, |s| s.values.len());
            let totals: Vec<f64> = (0..cats)
                .map(|c| segments.iter().map(|s| s.values[c].max(0.0)).sum())
                .collect();
            Box::new(totals.into_iter().chain(std::iter::once(0.0)))
        }
    }
}

fn ranges(fig: &Figure) -> Vec<((f64, f64), (f64, f64))> {
    let fixed = |a: &Axis| {
        a.range.map(|(lo, hi)| {
            if a.log {
                (lo.log10(), hi.log10())
            } else {
                (lo, hi)
            }
        })
    };
    let shared_x = padded(fig.panels.iter().flat_map(|p| axis_values(p, true)));
    let shared_y = padded(fig.panels.iter().flat_map(|p| axis_values(p, false)));
    fig.panels
        .iter()
        .map(|p| {
            let x = fixed(&p.x).unwrap_or_else(|| {
                if fig.share_x {
                    shared_x
                } else {
                    padded(axis_values(p, true))
                }
            });
            let y = fixed(&p.y).unwrap_or_else(|| {
                if fig.share_y {
                    shared_y
                } else {
                    padded(axis_values(p, false))
                }
            });
            (x, y)
        })
        .collect()
}

/// Palette colours by label, in order of first appearance over the figure.
fn colours(fig: &Figure) -> HashMap<String, RGBColor> {
    let mut map = HashMap::new();
    let mut next = 0;
    let mut take =
        |label: &str, explicit: Option<RGBColor>, map: &mut HashMap<String, RGBColor>| {
            if explicit.is_none() && !map.contains_key(label) {
                map.insert(label.to_string(), PALETTE[next % PALETTE.len()]);
                next += 1;
            }
        };
    for p in &fig.panels {
        match &p.plot {
            Plot::Xy(series) => {
                for s in series.iter().filter(|s| s.mark != Mark::Faint) {
                    take(&s.label, s.colour, &mut map);
                }
            }
            Plot::StackedBars { segments, .. } => {
                for s in segments {
                    take(&s.label, s.colour, &mut map);
                }
            }
        }
    }
    map
}

/// The explicit colour, else the label's, else [`FAINT`].
fn colour_for(
    explicit: Option<RGBColor>,
    label: &str,
    map: &HashMap<String, RGBColor>,
) -> RGBColor {
    explicit
        .or_else(|| map.get(label).copied())
        .unwrap_or(FAINT)
}

fn legend(fig: &Figure, colour_of: &HashMap<String, RGBColor>) -> Vec<(String, Sample)> {
    let mut out: Vec<(String, Sample)> = Vec::new();
    let mut push = |label: &str, sample: Sample| {
        if !label.is_empty() && !out.iter().any(|(l, _)| l == label) {
            out.push((label.to_string(), sample));
        }
    };
    for p in &fig.panels {
        match &p.plot {
            Plot::Xy(series) => {
                for s in series {
                    let c = colour_for(s.colour, &s.label, colour_of);
                    let sample = match &s.mark {
                        Mark::Line { stroke, width } => Sample::Line(c, *stroke, *width),
                        Mark::Points { .. } => Sample::Point(c),
                        Mark::LinePoints => Sample::LinePoint(c),
                        Mark::Faint => Sample::Line(s.colour.unwrap_or(FAINT), Stroke::Solid, 1),
                        Mark::Band { .. } => Sample::Area(c),
                    };
                    push(&s.label, sample);
                }
            }
            Plot::StackedBars { segments, .. } => {
                for s in segments {
                    push(
                        &s.label,
                        Sample::Bar(colour_for(s.colour, &s.label, colour_of)),
                    );
                }
            }
        }
    }
    out
}

/// Width of a text at the legend's font, px (a generous estimate: SVG text is laid out by the
/// viewer).
fn text_px(s: &str) -> i32 {
    (s.chars().count() as f64 * 0.62 * f64::from(LEGEND_FONT)).ceil() as i32
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;
type DrawResult<T> = Result<T, Box<dyn std::error::Error>>;

fn boxed<E: std::error::Error + Send + Sync + 'static>(e: E) -> Box<dyn std::error::Error> {
    Box::new(e)
}

/// Tick label of a log10 axis value: `1e-3`, or the value itself near 1.
fn power_label(v: &f64) -> String {
    if (v - v.round()).abs() > 1e-9 {
        return String::new();
    }
    match v.round() as i32 {
        0 => "1".to_string(),
        1 => "10".to_string(),
        e => format!("1e{e}"),
    }
}

/// A tick label of a linear axis: at most 4 significant digits, no trailing zeros.
fn tick_label(v: &f64) -> String {
    if *v == 0.0 {
        return "0".into();
    }
    let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 8) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

type PixelRect = (Range<i32>, Range<i32>);

fn draw_dashed(
    chart: &mut ChartContext<SVGBackend, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    pts: &[(f64, f64)],
    colour: RGBColor,
    stroke: Stroke,
    width: u32,
) -> DrawResult<()> {
    // Dashes in pixels, laid along the polyline so that the pattern runs on across its vertices.
    let px: Vec<(f64, f64)> = pts
        .iter()
        .map(|p| {
            let (x, y) = chart.backend_coord(p);
            (f64::from(x), f64::from(y))
        })
        .collect();
    let (on, off): (f64, f64) = match stroke {
        Stroke::Dashed => (7.0, 4.0),
        Stroke::Dotted => (2.0, 3.0),
        Stroke::Solid => unreachable!("solid lines are drawn whole"),
    };
    let style = colour.stroke_width(width);
    let area = chart.plotting_area().strip_coord_spec();
    let (x0, y0) = (
        area.get_pixel_range().0.start,
        area.get_pixel_range().1.start,
    );
    let mut phase = 0.0f64;
    for w in px.windows(2) {
        let (a, b) = (w[0], w[1]);
        let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let mut t = 0.0;
        while t < len {
            let in_on = phase < on;
            let step = if in_on { on - phase } else { on + off - phase }.min(len - t);
            if in_on {
                let p = |s: f64| {
                    let f = s / len;
                    (
                        (a.0 + f * (b.0 - a.0)).round() as i32 - x0,
                        (a.1 + f * (b.1 - a.1)).round() as i32 - y0,
                    )
                };
                area.draw(&PathElement::new(vec![p(t), p(t + step)], style))
                    .map_err(boxed)?;
            }
            t += step;
            phase = (phase + step) % (on + off);
        }
    }
    Ok(())
}

fn draw_xy(
    area: &Area,
    panel: &Panel,
    series: &[Series],
    (xr, yr): ((f64, f64), (f64, f64)),
    colour_of: &HashMap<String, RGBColor>,
) -> DrawResult<PixelRect> {
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(62)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
        .map_err(boxed)?;
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(panel.x.label.as_str())
        .y_desc(panel.y.label.as_str())
        .max_light_lines(2)
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(225, 225, 225))
        .label_style(("sans-serif", 12))
        .axis_desc_style(("sans-serif", 13));
    let log_ticks = |a: f64, b: f64| ((b.floor() - a.ceil()) as usize + 1).clamp(2, 12) * 4;
    if panel.x.log {
        mesh.x_labels(log_ticks(xr.0, xr.1))
            .x_label_formatter(&power_label);
    } else {
        mesh.x_labels(6).x_label_formatter(&tick_label);
    }
    if panel.y.log {
        mesh.y_labels(log_ticks(yr.0, yr.1))
            .y_label_formatter(&power_label);
    } else {
        mesh.y_labels(6).y_label_formatter(&tick_label);
    }
    mesh.draw().map_err(boxed)?;
    // Bands first, then faint lines, then the rest in order: data are never hidden by a fill.
    let order = |s: &Series| match s.mark {
        Mark::Band { .. } => 0,
        Mark::Faint => 1,
        _ => 2,
    };
    let mut sorted: Vec<&Series> = series.iter().collect();
    sorted.sort_by_key(|s| order(s));
    for s in sorted {
        let xs = transform(&s.x, panel.x.log);
        let ys = transform(&s.y, panel.y.log);
        let pts: Vec<(f64, f64)> = xs
            .iter()
            .zip(&ys)
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(x, y)| (*x, *y))
            .collect();
        let col = colour_for(s.colour, &s.label, colour_of);
        match &s.mark {
            Mark::Faint => {
                chart
                    .draw_series(LineSeries::new(pts, s.colour.unwrap_or(FAINT)))
                    .map_err(boxed)?;
            }
            Mark::Line {
                stroke: Stroke::Solid,
                width,
            } => {
                chart
                    .draw_series(LineSeries::new(pts, col.stroke_width(*width)))
                    .map_err(boxed)?;
            }
            Mark::Line { stroke, width } => draw_dashed(&mut chart, &pts, col, *stroke, *width)?,
            Mark::Points { radius, opacity } => {
                // One circle per pixel position: dense clouds stay small files.
                let mut seen = std::collections::HashSet::new();
                let unique: Vec<(f64, f64)> = pts
                    .into_iter()
                    .filter(|p| seen.insert(chart.backend_coord(p)))
                    .collect();
                let style = col.mix(*opacity).filled();
                chart
                    .draw_series(unique.into_iter().map(|p| Circle::new(p, *radius, style)))
                    .map_err(boxed)?;
            }
            Mark::LinePoints => {
                chart
                    .draw_series(LineSeries::new(pts.clone(), col.stroke_width(1)))
                    .map_err(boxed)?;
                chart
                    .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, col.filled())))
                    .map_err(boxed)?;
            }
            Mark::Band { lower } => {
                let lo = transform(lower, panel.y.log);
                let mut poly: Vec<(f64, f64)> = Vec::new();
                let ok = |i: usize| xs[i].is_finite() && ys[i].is_finite() && lo[i].is_finite();
                for i in (0..xs.len()).filter(|&i| ok(i)) {
                    poly.push((xs[i], ys[i]));
                }
                for i in (0..xs.len()).rev().filter(|&i| ok(i)) {
                    poly.push((xs[i], lo[i]));
                }
                chart
                    .draw_series(std::iter::once(Polygon::new(poly, col.mix(0.22).filled())))
                    .map_err(boxed)?;
            }
        }
    }
    Ok(chart.plotting_area().get_pixel_range())
}

fn draw_bars(
    area: &Area,
    panel: &Panel,
    categories: &[String],
    segments: &[Segment],
    xr: (f64, f64),
    colour_of: &HashMap<String, RGBColor>,
) -> DrawResult<PixelRect> {
    let k = categories.len() as i32;
    let widest = categories.iter().map(|c| text_px(c)).max().unwrap_or(0);
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 15))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(widest + 16)
        .build_cartesian_2d(xr.0.min(0.0)..xr.1, (0..k - 1).into_segmented())
        .map_err(boxed)?;
    let names = categories.to_vec();
    let label = move |v: &SegmentValue<i32>| match v {
        SegmentValue::CenterOf(i) => names.get((k - 1 - i) as usize).cloned().unwrap_or_default(),
        _ => String::new(),
    };
    chart
        .configure_mesh()
        .disable_y_mesh()
        .x_desc(panel.x.label.as_str())
        .y_desc(panel.y.label.as_str())
        .light_line_style(RGBColor(235, 235, 235))
        .bold_line_style(RGBColor(225, 225, 225))
        .label_style(("sans-serif", 12))
        .axis_desc_style(("sans-serif", 13))
        .x_labels(6)
        .x_label_formatter(&tick_label)
        .y_labels(categories.len())
        .y_label_formatter(&label)
        .draw()
        .map_err(boxed)?;
    for (c, _) in categories.iter().enumerate() {
        // Category 0 at the top.
        let row = k - 1 - c as i32;
        let mut start = 0.0;
        for s in segments {
            let v = s.values[c].max(0.0);
            let col = colour_for(s.colour, &s.label, colour_of);
            let mut r = Rectangle::new(
                [
                    (start, SegmentValue::Exact(row)),
                    (start + v, SegmentValue::Exact(row + 1)),
                ],
                col.filled(),
            );
            r.set_margin(6, 6, 0, 0);
            chart.draw_series(std::iter::once(r)).map_err(boxed)?;
            start += v;
        }
    }
    Ok(chart.plotting_area().get_pixel_range())
}

fn draw_legend(area: &Area, entries: &[(String, Sample)], rows: usize) -> DrawResult<()> {
    let font = ("sans-serif", LEGEND_FONT).into_font().color(&BLACK);
    let col_px = entries.iter().map(|(l, _)| text_px(l)).max().unwrap_or(0) + 48;
    for (i, (label, sample)) in entries.iter().enumerate() {
        let (c, r) = ((i / rows) as i32, (i % rows) as i32);
        let (x, y) = (8 + c * col_px, 12 + r * LEGEND_ROW_PX);
        let mid = y + LEGEND_ROW_PX / 2 - 2;
        match *sample {
            Sample::Line(col, stroke, width) => {
                let style = col.stroke_width(width.max(1));
                let dashes: Vec<(i32, i32)> = match stroke {
                    Stroke::Solid => vec![(0, 28)],
                    Stroke::Dashed => vec![(0, 7), (11, 18), (22, 28)],
                    Stroke::Dotted => vec![(0, 2), (5, 7), (10, 12), (15, 17), (20, 22), (25, 27)],
                };
                for (a, b) in dashes {
                    area.draw(&PathElement::new(vec![(x + a, mid), (x + b, mid)], style))
                        .map_err(boxed)?;
                }
            }
            Sample::Point(col) => {
                area.draw(&Circle::new((x + 14, mid), 4, col.filled()))
                    .map_err(boxed)?;
            }
            Sample::LinePoint(col) => {
                area.draw(&PathElement::new(
                    vec![(x, mid), (x + 28, mid)],
                    col.stroke_width(1),
                ))
                .map_err(boxed)?;
                area.draw(&Circle::new((x + 14, mid), 3, col.filled()))
                    .map_err(boxed)?;
            }
            Sample::Area(col) => {
                area.draw(&Rectangle::new(
                    [(x, mid - 6), (x + 28, mid + 6)],
                    col.mix(0.3).filled(),
                ))
                .map_err(boxed)?;
            }
            Sample::Bar(col) => {
                area.draw(&Rectangle::new(
                    [(x, mid - 6), (x + 28, mid + 6)],
                    col.filled(),
                ))
                .map_err(boxed)?;
            }
        }
        area.draw(&Text::new(label.clone(), (x + 36, mid - 7), font.clone()))
            .map_err(boxed)?;
    }
    Ok(())
}

/// Renders a figure as an SVG document.
pub fn render(fig: &Figure) -> Result<String, ChartError> {
    let colour_of = colours(fig);
    let entries = legend(fig, &colour_of);
    let cols = fig.columns.min(fig.panels.len()).max(1);
    let rows = fig.panels.len().div_ceil(cols);
    let (pw, ph) = fig.panel_px;
    let height = TITLE_PX + rows as u32 * ph;
    let legend_rows = (((height as i32 - TITLE_PX as i32 - 20) / LEGEND_ROW_PX).max(1)) as usize;
    let legend_cols = entries.len().div_ceil(legend_rows);
    let legend_px = if entries.is_empty() {
        0
    } else {
        let widest = entries.iter().map(|(l, _)| text_px(l)).max().unwrap_or(0);
        (legend_cols as i32 * (widest + 48) + 16) as u32
    };
    let width = cols as u32 * pw + legend_px;
    let mut svg = String::new();
    let mut areas: Vec<(&str, PixelRect)> = Vec::new();
    let result = (|| -> DrawResult<()> {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(boxed)?;
        let body = root.titled(&fig.title, ("sans-serif", 18)).map_err(boxed)?;
        let (plots, legend_area) = body.split_horizontally(cols as u32 * pw);
        let ranges = ranges(fig);
        let cells = plots.split_evenly((rows, cols));
        for ((panel, cell), r) in fig.panels.iter().zip(&cells).zip(&ranges) {
            let rect = match &panel.plot {
                Plot::Xy(series) => draw_xy(cell, panel, series, *r, &colour_of)?,
                Plot::StackedBars {
                    categories,
                    segments,
                } => draw_bars(cell, panel, categories, segments, r.0, &colour_of)?,
            };
            areas.push(("plot", rect));
        }
        if !entries.is_empty() {
            draw_legend(&legend_area, &entries, legend_rows)?;
            areas.push(("legend", legend_area.get_pixel_range()));
        }
        root.present().map_err(boxed)?;
        Ok(())
    })();
    result.map_err(|e| ChartError::Draw {
        figure: fig.title.clone(),
        message: e.to_string(),
    })?;
    let meta: String = areas
        .iter()
        .map(|(kind, (x, y))| format!("{kind} {} {} {} {}\n", x.start, y.start, x.end, y.end))
        .collect();
    let at = svg.find('>').map_or(0, |i| i + 1);
    svg.insert_str(
        at,
        &format!("\n<metadata id=\"{AREAS_ID}\">\n{meta}</metadata>"),
    );
    Ok(svg)
}

/// The areas listed in an SVG written by [`render`]: `(kind, x0, y0, x1, y1)`.
pub fn areas(svg: &str) -> Vec<(String, [i32; 4])> {
    let start = format!("<metadata id=\"{AREAS_ID}\">");
    let Some(from) = svg.find(&start).map(|i| i + start.len()) else {
        return Vec::new();
    };
    let to = svg[from..]
        .find("</metadata>")
        .map_or(svg.len(), |i| from + i);
    svg[from..to]
        .lines()
        .filter_map(|l| {
            let mut it = l.split_whitespace();
            let kind = it.next()?.to_string();
            let v: Vec<i32> = it.filter_map(|t| t.parse().ok()).collect();
            (v.len() == 4).then(|| (kind, [v[0], v[1], v[2], v[3]]))
        })
        .collect()
}

/// A one-panel line/point chart (the shape the benchmark reports use).
pub fn chart(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    simple(title, Axis::new(x_label), Axis::new(y_label), series)
}

/// [`chart`] with logarithmic axes; values ≤ 0 are left out.
pub fn chart_log_log(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    simple(
        title,
        Axis::new(x_label).log(),
        Axis::new(y_label).log(),
        series,
    )
}

fn simple(title: &str, x: Axis, y: Axis, series: &[Series]) -> String {
    let fig = Figure::single(title, Panel::xy("", x, y, series.to_vec()));
    render(&fig).unwrap_or_else(|e| {
        format!(
            "<svg xmlns='http://www.w3.org/2000/svg'><text>{}</text></svg>",
            super::page::escape(&e.to_string())
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_lists_its_areas_and_keeps_the_legend_beside_the_plots() {
        let panel = |t: &str| {
            Panel::xy(
                t,
                Axis::new("T (s)"),
                Axis::new("PSA (g)"),
                vec![
                    Series::line("target", vec![0.1, 1.0], vec![0.4, 0.16]),
                    Series::faint(vec![0.1, 1.0], vec![0.3, 0.2]),
                    Series::band("±10 %", vec![0.1, 1.0], vec![0.36, 0.14], vec![0.44, 0.18]),
                    Series::line("mean", vec![0.1, 1.0], vec![0.41, 0.15])
                        .stroke(Stroke::Dashed, 2),
                ],
            )
        };
        let svg = render(&Figure::grid("Spectra", vec![panel("a"), panel("b")], 2)).unwrap();
        assert!(svg.starts_with("<svg"));
        assert!(svg.contains("Spectra") && svg.contains("target") && svg.contains("PSA (g)"));
        let a = areas(&svg);
        assert_eq!(a.iter().filter(|(k, _)| k == "plot").count(), 2);
        let (_, legend) = a.iter().find(|(k, _)| k == "legend").unwrap();
        for (_, p) in a.iter().filter(|(k, _)| k == "plot") {
            assert!(
                p[2] <= legend[0],
                "plot {p:?} reaches into the legend {legend:?}"
            );
        }
    }

    #[test]
    fn tick_labels_are_short() {
        assert_eq!(tick_label(&0.30000000000000004), "0.3");
        assert_eq!(tick_label(&1200.0), "1200");
        assert_eq!(tick_label(&0.00125), "0.00125");
        assert_eq!(tick_label(&-2.5), "-2.5");
    }
}
