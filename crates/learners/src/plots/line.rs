//! Line plots to PNG (learning curves, mean |ASZ| over time), drawn with
//! plotters: axes with "nice" tick values and numeric labels, a title, axis
//! labels and a legend in the corner that hides the fewest points.
//! Non-finite values (NaN, ±inf) are skipped and break the line; empty and
//! flat data give a plot with a sensible range instead of a panic.

use super::canvas::Canvas;
use super::plotters_font;
use crate::error::LearnError;
use image::{ImageFormat, RgbImage};
use plotters::coord::ranged1d::KeyPointHint;
use plotters::coord::Shift;
use plotters::element::Text as PlotText;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// One line of a plot. Series with an empty label are left out of the legend.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub color: [u8; 3],
}

impl Series {
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, color: [u8; 3]) -> Series {
        Series {
            label: label.into(),
            points,
            color,
        }
    }
}

/// Ten well-separated line colours (the "tab10" palette).
pub const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// The `i`-th palette colour (cycling).
pub fn palette(i: usize) -> [u8; 3] {
    PALETTE[i % PALETTE.len()]
}

const AXIS: RGBColor = RGBColor(40, 40, 40);
const GRID: RGBColor = RGBColor(228, 228, 228);
const TEXT: RGBColor = RGBColor(20, 20, 20);
const MUTED: RGBColor = RGBColor(120, 120, 120);

/// The tick values of an axis covering [lo, hi] with about `target` ticks, at
/// 1, 2 or 5 times a power of ten; the first tick is <= lo and the last >= hi.
/// An empty or degenerate range is widened first. Always at least 2 ticks.
pub fn nice_ticks(lo: f64, hi: f64, target: usize) -> Vec<f64> {
    let (lo, hi) = widen(lo, hi);
    let target = target.max(2);
    let (m, e) = nice_step_parts((hi - lo) / (target - 1) as f64);
    let step = scaled(m, e);
    let first = (lo / step).floor();
    let last = (hi / step).ceil();
    if !(step.is_finite() && step > 0.0 && first.is_finite() && last.is_finite())
        || last - first > 1000.0
    {
        return vec![lo, hi];
    }
    let n = (last - first).round() as i64;
    let ticks: Vec<f64> = (0..=n.max(1))
        .map(|i| {
            let t = scaled((first + i as f64) * m, e);
            // (first + i) * step can come out as 0.30000000000000004 or -0.
            if t.abs() < step * 1e-9 {
                0.0
            } else {
                t
            }
        })
        .collect();
    if ticks.iter().all(|t| t.is_finite()) {
        ticks
    } else {
        vec![lo, hi]
    }
}

/// A range that is finite and not empty: NaN/inf fall back to [0, 1], a
/// single value v to v ± max(|v| / 10, 1) (or ± |v| / 10 for tiny but nonzero v).
fn widen(lo: f64, hi: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let (lo, hi) = if lo <= hi { (lo, hi) } else { (hi, lo) };
    if hi - lo > hi.abs().max(lo.abs()) * 1e-12 && (hi - lo).is_finite() {
        return (lo, hi);
    }
    let v = (lo + hi) / 2.0;
    let d = if v == 0.0 {
        1.0
    } else {
        (v.abs() / 10.0).min(1.0).max(v.abs() * 1e-3)
    };
    (v - d, v + d)
}

/// `m * 10^e` computed so that steps like 0.2 come out as the double nearest 0.2.
fn scaled(m: f64, e: i32) -> f64 {
    if e < 0 {
        m / 10f64.powi(-e)
    } else {
        m * 10f64.powi(e)
    }
}

/// (mantissa 1, 2, 5 or 10, decimal exponent) of the 1-2-5 step nearest to x (x > 0).
fn nice_step_parts(x: f64) -> (f64, i32) {
    if !(x.is_finite() && x > 0.0) {
        return (1.0, 0);
    }
    let e = x.log10().floor() as i32;
    let f = x / 10f64.powi(e);
    let m = if f < 1.5 {
        1.0
    } else if f < 3.0 {
        2.0
    } else if f < 7.0 {
        5.0
    } else {
        10.0
    };
    (m, e)
}

/// Tick labels with as many decimals as the tick spacing needs; scientific
/// notation for very large or very small magnitudes.
pub fn tick_labels(ticks: &[f64]) -> Vec<String> {
    let step = if ticks.len() >= 2 {
        (ticks[1] - ticks[0]).abs()
    } else {
        1.0
    };
    let max = ticks.iter().fold(0f64, |m, t| m.max(t.abs()));
    if max >= 1e6 || (step > 0.0 && step < 1e-4) {
        return ticks
            .iter()
            .map(|&t| {
                if t == 0.0 {
                    "0".to_string()
                } else {
                    format!("{t:.1e}")
                }
            })
            .collect();
    }
    // The tick spacing carries float noise (2.8 - 2.7 = 0.09999999999999964).
    let decimals = if step > 0.0 {
        (-step.log10() - 1e-6).ceil().clamp(0.0, 6.0) as usize
    } else {
        0
    };
    // A step like 0.25 is never produced (1-2-5 steps), but 2.5e-n can come
    // from a fallback range: one more decimal keeps labels distinct.
    let decimals = if decimals < 6
        && ((step * 10f64.powi(decimals as i32)).round() - step * 10f64.powi(decimals as i32)).abs()
            > 1e-6
    {
        decimals + 1
    } else {
        decimals
    };
    ticks
        .iter()
        .map(|&t| {
            let s = format!("{t:.decimals$}");
            if s.starts_with('-')
                && s.trim_start_matches('-')
                    .chars()
                    .all(|c| c == '0' || c == '.')
            {
                s[1..].to_string()
            } else {
                s
            }
        })
        .collect()
}

/// Where the data area of a plot lies and which values its edges stand for,
/// as plotters laid it out.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotFrame {
    /// Pixel bounds of the data area: left, top, right, bottom (inclusive).
    pub left: i64,
    pub top: i64,
    pub right: i64,
    pub bottom: i64,
    pub x_ticks: Vec<f64>,
    pub y_ticks: Vec<f64>,
}

/// Share of the tick span left empty beyond each outer tick.
const X_MARGIN: f64 = 0.02;
const Y_MARGIN: f64 = 0.04;

fn widen_by(ticks: &[f64], margin: f64) -> (f64, f64) {
    let (lo, hi) = (ticks[0], *ticks.last().unwrap());
    let pad = (hi - lo) * margin;
    (lo - pad, hi + pad)
}

impl PlotFrame {
    // The axes reach a little past the outer ticks, so that a line at the
    // last tick (an SR of 100% is common) is drawn inside the box, not on
    // its border where it cannot be seen.
    fn x_range(&self) -> (f64, f64) {
        widen_by(&self.x_ticks, X_MARGIN)
    }
    fn y_range(&self) -> (f64, f64) {
        widen_by(&self.y_ticks, Y_MARGIN)
    }
    /// Pixel position (x, y) of the data point (x, y).
    pub fn to_pixel(&self, x: f64, y: f64) -> (f64, f64) {
        let (x0, x1) = self.x_range();
        let (y0, y1) = self.y_range();
        let px = self.left as f64 + (x - x0) / (x1 - x0) * (self.right - self.left) as f64 + 0.5;
        let py = self.bottom as f64 - (y - y0) / (y1 - y0) * (self.bottom - self.top) as f64 + 0.5;
        (px, py)
    }
}

/// Text sizes for a plot of this size: (labels, title) in pixels.
fn font_sizes(width: u32, height: u32) -> (u32, u32) {
    if width.min(height) >= 1000 {
        (24, 28)
    } else {
        (13, 15)
    }
}

/// Finite data range over all series, if there is any finite point.
fn data_range(series: &[Series]) -> Option<((f64, f64), (f64, f64))> {
    let mut r: Option<((f64, f64), (f64, f64))> = None;
    for &(x, y) in series.iter().flat_map(|s| s.points.iter()) {
        if !(x.is_finite() && y.is_finite()) {
            continue;
        }
        r = Some(match r {
            None => ((x, x), (y, y)),
            Some(((xl, xh), (yl, yh))) => ((xl.min(x), xh.max(x)), (yl.min(y), yh.max(y))),
        });
    }
    r
}

/// The layout of `line_plot`'s data area for this data and size.
pub fn plot_frame(
    series: &[Series],
    title: &str,
    x_label: &str,
    y_label: &str,
    width: u32,
    height: u32,
) -> PlotFrame {
    draw_line_plot(series, title, x_label, y_label, width, height).1
}

/// Draws `series` as lines on one pair of axes. Non-finite points are skipped
/// and split their line; points with no finite neighbour, and every point of
/// a series with at most 25 points, get a marker. Never panics on odd input
/// (no series, no points, NaN, a single value, a tiny image).
pub fn line_plot(
    series: &[Series],
    title: &str,
    x_label: &str,
    y_label: &str,
    width: u32,
    height: u32,
) -> RgbImage {
    draw_line_plot(series, title, x_label, y_label, width, height).0
}

fn draw_line_plot(
    series: &[Series],
    title: &str,
    x_label: &str,
    y_label: &str,
    width: u32,
    height: u32,
) -> (RgbImage, PlotFrame) {
    let (width, height) = (width.max(1), height.max(1));
    let ((xl, xh), (yl, yh)) = data_range(series).unwrap_or(((0.0, 1.0), (0.0, 1.0)));
    // A tick every 40 pixels or more up the y axis, every 80 or more
    // along the x axis (room for about 10 characters per label); twice that
    // on large images, whose text is twice as large.
    let ts = if width.min(height) >= 1000 { 2 } else { 1 };
    let y_ticks = nice_ticks(yl, yh, (height / (40 * ts)).clamp(2, 8) as usize);
    let x_ticks = nice_ticks(
        xl,
        xh,
        (width.saturating_sub(80 * ts) / (80 * ts)).clamp(2, 10) as usize,
    );
    let mut buf = vec![255u8; width as usize * height as usize * 3];
    let area = {
        let root = Canvas::new(&mut buf, (width, height)).into_drawing_area();
        let text = Text {
            title,
            x_label,
            y_label,
        };
        // Too small for axes and text (or a font that will not load): the
        // series alone over the whole image, so that nothing panics.
        let area = draw_chart(&root, series, &text, &x_ticks, &y_ticks)
            .or_else(|_| {
                root.fill(&WHITE).ok();
                draw_chart(&root, series, &Text::NONE, &x_ticks, &y_ticks)
            })
            .unwrap_or((0..width as i32, 0..height as i32));
        root.present().ok();
        area
    };
    let img = RgbImage::from_raw(width, height, buf).expect("buffer of width x height x 3");
    let frame = PlotFrame {
        left: area.0.start as i64,
        top: area.1.start as i64,
        right: (area.0.end as i64 - 1).max(area.0.start as i64),
        bottom: (area.1.end as i64 - 1).max(area.1.start as i64),
        x_ticks,
        y_ticks,
    };
    (img, frame)
}

/// An axis over [lo, hi] whose ticks (and grid lines) are exactly
/// `nice_ticks`'s, so plotters draws the ticks the frame reports.
#[derive(Clone)]
struct TickAxis {
    lo: f64,
    hi: f64,
    ticks: Vec<f64>,
}

impl TickAxis {
    fn new(ticks: &[f64], margin: f64) -> TickAxis {
        let (lo, hi) = widen_by(ticks, margin);
        TickAxis {
            lo,
            hi,
            ticks: ticks.to_vec(),
        }
    }
}

impl Ranged for TickAxis {
    type FormatOption = plotters::coord::ranged1d::DefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = (v - self.lo) / (self.hi - self.lo);
        let px = limit.0 as f64 + t * (limit.1 - limit.0) as f64;
        // A value beyond any pixel (1e300 on a unit axis) pins to a far
        // edge instead of wrapping.
        if px.is_finite() {
            px.round().clamp(-1e6, 1e6) as i32
        } else {
            limit.0
        }
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        // Grid lines at the ticks only: no lighter lines between them.
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.lo..self.hi
    }
}

/// A plot's words.
struct Text<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
}

impl Text<'_> {
    const NONE: Text<'static> = Text {
        title: "",
        x_label: "",
        y_label: "",
    };
}

type Area<'a> = DrawingArea<Canvas<'a>, Shift>;
type DrawResult<T> =
    Result<T, DrawingAreaErrorKind<<Canvas<'static> as DrawingBackend>::ErrorType>>;

/// Draws the chart; returns the pixel ranges of its data area.
fn draw_chart(
    root: &Area,
    series: &[Series],
    text: &Text,
    x_ticks: &[f64],
    y_ticks: &[f64],
) -> DrawResult<(std::ops::Range<i32>, std::ops::Range<i32>)> {
    plotters_font::register();
    let (width, height) = root.dim_in_pixel();
    let (label_px, title_px) = font_sizes(width, height);
    let label_font = (plotters_font::FAMILY, label_px).into_font().color(&TEXT);
    let (x_axis, y_axis) = (
        TickAxis::new(x_ticks, X_MARGIN),
        TickAxis::new(y_ticks, Y_MARGIN),
    );
    let (x0, x1, y0, y1) = (x_axis.lo, x_axis.hi, y_axis.lo, y_axis.hi);
    let x_labels = tick_labels(x_ticks);
    let y_labels = tick_labels(y_ticks);
    let label_of = |ticks: &[f64], labels: &[String], v: f64| -> String {
        ticks
            .iter()
            .position(|t| *t == v)
            .map(|i| labels[i].clone())
            .unwrap_or_default()
    };
    let (y_label_w, x_last_w) = label_widths(root, &x_labels, &y_labels, &label_font)?;
    let pad = label_px / 2;
    let desc = |s: &str| if s.is_empty() { 0 } else { label_px + pad };
    let mut builder = ChartBuilder::on(root);
    builder
        .margin_top(pad)
        .margin_right(pad.max(x_last_w / 2 + pad))
        .margin_left(pad)
        .x_label_area_size(label_px + 2 * pad + desc(text.x_label))
        .y_label_area_size(y_label_w + 2 * pad + desc(text.y_label));
    if !text.title.is_empty() {
        builder.caption(
            text.title,
            (plotters_font::FAMILY, title_px).into_font().color(&TEXT),
        );
    }
    let mut chart = builder.build_cartesian_2d(x_axis, y_axis)?;
    let x_fmt = |v: &f64| label_of(x_ticks, &x_labels, *v);
    let y_fmt = |v: &f64| label_of(y_ticks, &y_labels, *v);
    chart
        .configure_mesh()
        .bold_line_style(GRID)
        .light_line_style(TRANSPARENT)
        .axis_style(AXIS)
        .label_style(label_font.clone())
        .axis_desc_style(label_font.clone())
        .x_desc(text.x_label)
        .y_desc(text.y_label)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .set_all_tick_mark_size(pad / 2 + 1)
        .draw()?;

    let plot_area = chart.plotting_area().clone();
    let mut any_data = false;
    for s in series {
        any_data |= draw_series(&mut chart, &plot_area, s, label_px)?;
    }
    if !any_data {
        let (xm, ym) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        plot_area.draw(&PlotText::new(
            "no data",
            (xm, ym),
            label_font
                .color(&MUTED)
                .pos(Pos::new(HPos::Center, VPos::Center)),
        ))?;
    }
    draw_legend(&mut chart, series, &label_font, pad)?;
    Ok(chart.plotting_area().get_pixel_range())
}

/// The widest y label and the last x label's width, which size the margins;
/// apart from `draw_chart` to keep it to the drawing.
fn label_widths(
    root: &Area,
    x_labels: &[String],
    y_labels: &[String],
    label_font: &TextStyle,
) -> DrawResult<(u32, u32)> {
    let y_label_w = y_labels
        .iter()
        .map(|l| root.estimate_text_size(l, label_font).map(|(w, _)| w))
        .collect::<Result<Vec<u32>, _>>()?
        .into_iter()
        .max()
        .unwrap_or(0);
    let x_last_w = root
        .estimate_text_size(x_labels.last().map_or("", |l| l.as_str()), label_font)?
        .0;
    Ok((y_label_w, x_last_w))
}

type Chart<'a, 'b> = ChartContext<'a, Canvas<'b>, Cartesian2d<TickAxis, TickAxis>>;

/// One series' lines and markers; apart from `draw_chart` so the gaps-at-NaN
/// rule reads on its own. Returns whether the series had a finite point.
fn draw_series<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    plot_area: &DrawingArea<Canvas<'_>, Cartesian2d<TickAxis, TickAxis>>,
    s: &Series,
    label_px: u32,
) -> DrawResult<bool> {
    let color = RGBColor(s.color[0], s.color[1], s.color[2]);
    let style = color.stroke_width(if label_px > 20 { 3 } else { 2 });
    let finite: Vec<Option<(f64, f64)>> = s
        .points
        .iter()
        .map(|&(x, y)| (x.is_finite() && y.is_finite()).then_some((x, y)))
        .collect();
    let n_finite = finite.iter().flatten().count();
    // A line per run of finite points: a NaN leaves a gap.
    let runs: Vec<Vec<(f64, f64)>> = finite
        .split(|p| p.is_none())
        .map(|run| run.iter().flatten().copied().collect::<Vec<_>>())
        .filter(|run| !run.is_empty())
        .collect();
    let mut labelled = false;
    for run in runs.iter().map(|r| r.as_slice()).chain(
        // A labelled series without data still gets its legend entry.
        (runs.is_empty()).then_some(&[][..]),
    ) {
        let drawn = chart.draw_series(LineSeries::new(run.iter().copied(), style))?;
        if !labelled && !s.label.is_empty() {
            drawn
                .label(s.label.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], style));
            labelled = true;
        }
    }
    let marker = label_px as f64 * 0.18;
    for (i, p) in finite.iter().enumerate() {
        let Some(p) = *p else { continue };
        let prev = i > 0 && finite[i - 1].is_some();
        let next = i + 1 < finite.len() && finite[i + 1].is_some();
        if n_finite <= 25 || !(prev || next) {
            plot_area.draw(&Circle::new(p, marker.round() as i32, color.filled()))?;
        }
    }
    Ok(n_finite > 0)
}

/// The legend box, when any series is labelled; apart from `draw_chart`
/// because its placement depends on where the data lies.
fn draw_legend<'a, 'b: 'a>(
    chart: &mut Chart<'a, 'b>,
    series: &[Series],
    label_font: &TextStyle,
    pad: u32,
) -> DrawResult<()> {
    let legend_entries: Vec<&str> = series
        .iter()
        .filter(|s| !s.label.is_empty())
        .map(|s| s.label.as_str())
        .collect();
    if !legend_entries.is_empty() {
        let corner = legend_corner(chart, series, &legend_entries, label_font, pad as i32);
        chart
            .configure_series_labels()
            .position(corner)
            .margin(pad)
            .legend_area_size(22)
            .label_font(label_font.clone())
            .background_style(WHITE)
            .border_style(RGBColor(190, 190, 190))
            .draw()?;
    }
    Ok(())
}

/// The corner of the data area where the legend hides the fewest points
/// (data points and samples along the lines between them).
fn legend_corner(
    chart: &ChartContext<'_, Canvas<'_>, Cartesian2d<TickAxis, TickAxis>>,
    series: &[Series],
    entries: &[&str],
    font: &TextStyle,
    pad: i32,
) -> SeriesLabelPosition {
    let area = chart.plotting_area();
    let (aw, ah) = area.dim_in_pixel();
    // The box plotters will draw: the same sizes as `SeriesLabelStyle::draw`.
    let mut text = MultiLineText::<_, &str>::new((0, 0), font);
    for e in entries {
        text.push_line(*e);
    }
    // The font measured every label already (the mesh); a failure here
    // leaves the legend at the default corner.
    let Ok((w, h)) = text.estimate_dimension() else {
        return SeriesLabelPosition::UpperRight;
    };
    let (bw, bh) = (w + 22 + 2 * pad, h + 2 * pad);
    let (x_range, y_range) = area.get_pixel_range();
    let corners = [
        SeriesLabelPosition::UpperRight,
        SeriesLabelPosition::UpperLeft,
        SeriesLabelPosition::LowerRight,
        SeriesLabelPosition::LowerLeft,
    ];
    let origin = |c: &SeriesLabelPosition| -> (i32, i32) {
        let left = matches!(
            c,
            SeriesLabelPosition::UpperLeft | SeriesLabelPosition::LowerLeft
        );
        let upper = matches!(
            c,
            SeriesLabelPosition::UpperLeft | SeriesLabelPosition::UpperRight
        );
        (
            x_range.start + if left { 5 } else { aw as i32 - bw - 5 },
            y_range.start + if upper { 5 } else { ah as i32 - bh - 5 },
        )
    };
    let covered = |c: &SeriesLabelPosition| -> usize {
        let (bx, by) = origin(c);
        let inside = |p: (i32, i32)| p.0 >= bx && p.0 <= bx + bw && p.1 >= by && p.1 <= by + bh;
        let mut n = 0;
        for s in series {
            let px: Vec<Option<(i32, i32)>> = s
                .points
                .iter()
                .map(|&(x, y)| {
                    (x.is_finite() && y.is_finite()).then(|| chart.backend_coord(&(x, y)))
                })
                .collect();
            for (i, p) in px.iter().enumerate() {
                let Some(p) = *p else { continue };
                n += inside(p) as usize;
                if let Some(Some(q)) = px.get(i + 1) {
                    // Sample long segments so a line crossing the box counts.
                    let steps = (((q.0 - p.0).abs() + (q.1 - p.1).abs()) as f64 / 4.0)
                        .ceil()
                        .clamp(1.0, 200.0) as i32;
                    for k in 1..steps {
                        n += inside((p.0 + (q.0 - p.0) * k / steps, p.1 + (q.1 - p.1) * k / steps))
                            as usize;
                    }
                }
            }
        }
        n
    };
    corners.into_iter().min_by_key(|c| covered(c)).unwrap()
}

/// Writes `img` as a PNG, creating missing parent folders; errors name the path.
pub fn save_png(img: &RgbImage, path: impl AsRef<Path>) -> Result<(), LearnError> {
    let path = path.as_ref();
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| {
            LearnError::io(
                format!(
                    "cannot create folder {} for {}",
                    parent.display(),
                    path.display()
                ),
                e,
            )
        })?;
    }
    img.save_with_format(path, ImageFormat::Png)
        .map_err(|cause| LearnError::Image {
            context: format!("cannot write PNG {}", path.display()),
            cause,
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    const RED: [u8; 3] = [214, 39, 40];
    const BLUE: [u8; 3] = [31, 119, 180];

    fn pixels_of(img: &RgbImage, c: [u8; 3]) -> Vec<(u32, u32)> {
        img.enumerate_pixels()
            .filter(|(_, _, p)| p.0 == c)
            .map(|(x, y, _)| (x, y))
            .collect()
    }

    #[test]
    fn ticks_are_nice_and_cover_the_data() {
        assert_eq!(
            nice_ticks(0.0, 97.0, 6),
            vec![0.0, 20.0, 40.0, 60.0, 80.0, 100.0]
        );
        assert_eq!(
            nice_ticks(-3.0, 3.0, 7),
            vec![-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0]
        );
        let t = nice_ticks(0.0013, 0.0042, 5);
        assert!(
            t[0] <= 0.0013 && *t.last().unwrap() >= 0.0042 && t.len() >= 3 && t.len() <= 8,
            "{t:?}"
        );
        assert_eq!(tick_labels(&t)[1], "0.002");
        assert_eq!(
            tick_labels(&[0.0, 0.1, 0.2, 0.30000000000000004]),
            vec!["0.0", "0.1", "0.2", "0.3"]
        );
        assert_eq!(
            tick_labels(&[-0.0, 500.0, 1000.0]),
            vec!["0", "500", "1000"]
        );
        assert_eq!(tick_labels(&[2.7, 2.8, 2.9]), vec!["2.7", "2.8", "2.9"]);
        assert_eq!(tick_labels(&[0.0, 0.05, 0.1]), vec!["0.00", "0.05", "0.10"]);
        assert_eq!(tick_labels(&[0.0, 0.25, 0.5]), vec!["0.00", "0.25", "0.50"]);
        assert_eq!(tick_labels(&[-2.0, 0.0, 2.0]), vec!["-2", "0", "2"]);
        // Degenerate ranges widen instead of dividing by zero.
        let flat = nice_ticks(5.0, 5.0, 5);
        assert!(
            flat.len() >= 2 && flat[0] < 5.0 && *flat.last().unwrap() > 5.0,
            "{flat:?}"
        );
        assert_eq!(
            nice_ticks(f64::NAN, 1.0, 5),
            vec![0.0, 0.2, 0.4, 0.6, 0.8, 1.0]
        );
        let zero = nice_ticks(0.0, 0.0, 3);
        assert!(zero[0] < 0.0 && *zero.last().unwrap() > 0.0, "{zero:?}");
        let huge = nice_ticks(0.0, 3e9, 4);
        assert!(huge.iter().all(|t| t.is_finite()) && tick_labels(&huge)[1].contains('e'));
        let extreme = nice_ticks(-f64::MAX, f64::MAX, 5);
        assert!(extreme.len() >= 2 && extreme.iter().all(|t| t.is_finite()));
    }

    #[test]
    fn rising_series_goes_up_left_to_right() {
        let pts: Vec<(f64, f64)> = (0..200)
            .map(|i| (i as f64, (i as f64).sqrt() * 3.0))
            .collect();
        let img = line_plot(
            &[Series::new("", pts, RED)],
            "rising",
            "step",
            "value",
            640,
            400,
        );
        assert_eq!(img.dimensions(), (640, 400));
        let px = pixels_of(&img, RED);
        assert!(px.len() > 300, "only {} series pixels", px.len());
        let mean_y = |lo: u32, hi: u32| {
            let ys: Vec<f64> = px
                .iter()
                .filter(|p| p.0 >= lo && p.0 < hi)
                .map(|p| p.1 as f64)
                .collect();
            assert!(!ys.is_empty(), "no line pixels in columns {lo}..{hi}");
            ys.iter().sum::<f64>() / ys.len() as f64
        };
        let (xmin, xmax) = (
            px.iter().map(|p| p.0).min().unwrap(),
            px.iter().map(|p| p.0).max().unwrap(),
        );
        assert!(xmax - xmin > 400, "line spans only {xmin}..{xmax}");
        let q = (xmax - xmin) / 4;
        let quarters: Vec<f64> = (0..4)
            .map(|i| mean_y(xmin + i * q, xmin + (i + 1) * q))
            .collect();
        for w in quarters.windows(2) {
            assert!(
                w[1] < w[0] - 5.0,
                "line does not rise: mean rows per quarter {quarters:?}"
            );
        }
        // The data's corners land where the frame says.
        let f = plot_frame(
            &[Series::new(
                "",
                vec![(0.0, 0.0), (199.0, 199f64.sqrt() * 3.0)],
                RED,
            )],
            "rising",
            "step",
            "value",
            640,
            400,
        );
        for x in [25.0, 100.0, 160.0] {
            let (x0, y0) = f.to_pixel(x, f64::sqrt(x) * 3.0);
            assert!(
                px.iter()
                    .any(|p| (p.0 as f64 + 0.5 - x0).abs() < 1.5
                        && (p.1 as f64 + 0.5 - y0).abs() < 1.5),
                "no line at x = {x}"
            );
        }
        // Title text is drawn above the data area.
        assert!(img
            .enumerate_pixels()
            .any(|(_, y, p)| (y as i64) < f.top && p.0 == [TEXT.0, TEXT.1, TEXT.2]));
    }

    #[test]
    fn a_line_at_the_top_tick_is_drawn_inside_the_box() {
        // SR curves sit at 100% for long stretches: that line must not
        // merge with the axes' border.
        let pts: Vec<(f64, f64)> = (0..50).map(|i| (i as f64, 100.0)).collect();
        let floor = vec![(0.0, 0.0), (49.0, 0.0)];
        let series = [Series::new("", pts, RED), Series::new("", floor, BLUE)];
        let f = plot_frame(&series, "sr", "min", "SR %", 640, 400);
        assert_eq!(*f.y_ticks.last().unwrap(), 100.0);
        assert_eq!(f.y_ticks[0], 0.0);
        let img = line_plot(&series, "sr", "min", "SR %", 640, 400);
        let red = pixels_of(&img, RED);
        let blue = pixels_of(&img, BLUE);
        assert!(!red.is_empty() && !blue.is_empty());
        let gap = ((f.bottom - f.top) as f64 * 0.03) as i64;
        assert!(
            red.iter().all(|p| p.1 as i64 >= f.top + gap),
            "the 100% line touches the top border (top {})",
            f.top
        );
        assert!(
            blue.iter().all(|p| (p.1 as i64) <= f.bottom - gap),
            "the 0% line touches the bottom border (bottom {})",
            f.bottom
        );
        // The first and last points stay off the left and right borders.
        assert!(red
            .iter()
            .all(|p| p.0 as i64 > f.left + 2 && (p.0 as i64) < f.right - 2));
    }

    #[test]
    fn legend_shows_labelled_series_only() {
        let pts: Vec<(f64, f64)> = (0..50).map(|i| (i as f64, i as f64)).collect();
        let plain = line_plot(&[Series::new("", pts.clone(), RED)], "", "", "", 400, 300);
        let labelled_series = [Series::new("captors", pts, RED)];
        let labelled = line_plot(&labelled_series, "", "", "", 400, 300);
        let (a, b) = (
            pixels_of(&plain, RED).len(),
            pixels_of(&labelled, RED).len(),
        );
        assert!(b > a + 20, "legend swatch missing: {a} vs {b} pixels");
        // The rising line leaves the top-left corner empty: the legend goes there.
        let f = plot_frame(&labelled_series, "", "", "", 400, 300);
        let in_legend = pixels_of(&labelled, RED)
            .iter()
            .filter(|p| (p.0 as i64) < f.left + 40 && (p.1 as i64) < f.top + 20)
            .count();
        assert!(in_legend >= 10, "{in_legend}");
    }

    #[test]
    fn odd_input_does_not_panic() {
        let cases: Vec<Vec<Series>> = vec![
            vec![],
            vec![Series::new("empty", vec![], RED)],
            vec![Series::new(
                "nan",
                vec![(f64::NAN, 1.0), (2.0, f64::NAN), (f64::INFINITY, 3.0)],
                RED,
            )],
            vec![Series::new(
                "flat",
                (0..10).map(|i| (i as f64, 7.0)).collect(),
                RED,
            )],
            vec![Series::new("one", vec![(3.0, 4.0)], RED)],
            vec![Series::new(
                "gap",
                vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0), (3.0, 4.0)],
                palette(1),
            )],
            vec![
                Series::new("huge", vec![(0.0, -1e300), (1.0, 1e300)], RED),
                Series::new("b", vec![(0.0, 0.0)], palette(2)),
            ],
        ];
        for series in &cases {
            for (w, h) in [(640, 480), (60, 40), (1, 1), (0, 0), (1200, 1100)] {
                let img = line_plot(series, "title", "x", "y", w, h);
                assert_eq!(img.dimensions(), (w.max(1), h.max(1)));
            }
        }
        // A flat series is drawn as a horizontal line in the middle of the frame.
        let img = line_plot(&cases[3], "", "", "", 400, 300);
        let rows: std::collections::BTreeSet<u32> = pixels_of(&img, RED)
            .iter()
            .filter(|p| p.0 > 100 && p.0 < 250)
            .map(|p| p.1)
            .collect();
        assert!(!rows.is_empty() && rows.len() <= 6, "{rows:?}");
        let f = plot_frame(&cases[3], "", "", "", 400, 300);
        let mid = (f.top + f.bottom) as f64 / 2.0;
        assert!(
            rows.iter()
                .all(|&r| (r as f64 - mid).abs() < (f.bottom - f.top) as f64 / 4.0),
            "{rows:?} vs {mid}"
        );
        // An isolated point still shows (as a marker).
        let img = line_plot(&cases[5], "", "", "", 400, 300);
        assert!(pixels_of(&img, palette(1)).len() > 20);
    }

    #[test]
    fn save_png_creates_folders_and_names_the_path_on_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a/b/plot.png");
        let img = line_plot(
            &[Series::new("s", vec![(0.0, 0.0), (1.0, 1.0)], RED)],
            "t",
            "x",
            "y",
            200,
            150,
        );
        save_png(&img, &path).unwrap();
        let back = image::open(&path).unwrap().to_rgb8();
        assert_eq!(back, img);
        // A file where a folder should be.
        let blocker = dir.path().join("file");
        std::fs::write(&blocker, b"x").unwrap();
        let err = save_png(&img, blocker.join("x.png")).unwrap_err();
        assert!(format!("{err:#}").contains("file"), "{err:#}");
    }
}
