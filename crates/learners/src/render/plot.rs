//! Line plots to PNG (learning curves, mean |ASZ| over time): axes with
//! "nice" tick values and numeric labels, a title, axis labels and a legend.
//! Non-finite values (NaN, ±inf) are skipped and break the line; empty and
//! flat data give a plot with a sensible range instead of a panic.

use super::text::{
    draw_line, draw_rect, draw_text, draw_text_centered, draw_text_up, fill_disc, fill_rect,
    text_size,
};
use anyhow::{Context, Result};
use image::{ImageFormat, Rgb, RgbImage};
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

const BACKGROUND: Rgb<u8> = Rgb([255, 255, 255]);
const AXIS: Rgb<u8> = Rgb([40, 40, 40]);
const GRID: Rgb<u8> = Rgb([228, 228, 228]);
const TEXT: Rgb<u8> = Rgb([20, 20, 20]);
const MUTED: Rgb<u8> = Rgb([120, 120, 120]);

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

/// Where the data area of a plot lies and which values its edges stand for.
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

/// Text scale for a plot of this size.
fn text_scale(width: u32, height: u32) -> u32 {
    if width.min(height) >= 1000 {
        2
    } else {
        1
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

/// Lays out a plot of `width x height` pixels for this data.
pub fn plot_frame(
    series: &[Series],
    title: &str,
    x_label: &str,
    y_label: &str,
    width: u32,
    height: u32,
) -> PlotFrame {
    let ts = text_scale(width, height);
    let ch = (8 * ts) as i64;
    let pad = (6 * ts) as i64;
    let tick = (4 * ts) as i64;
    let ((xl, xh), (yl, yh)) = data_range(series).unwrap_or(((0.0, 1.0), (0.0, 1.0)));
    let y_target = ((height as i64 / (ch * 5)).clamp(2, 8)) as usize;
    let y_ticks = nice_ticks(yl, yh, y_target);
    let y_label_w = tick_labels(&y_ticks)
        .iter()
        .map(|l| text_size(l, ts).0 as i64)
        .max()
        .unwrap_or(0);
    let top = pad + if title.is_empty() { 0 } else { ch + pad };
    let left = pad + if y_label.is_empty() { 0 } else { ch + pad } + y_label_w + pad / 2 + tick;
    let bottom_margin =
        tick + pad / 2 + ch + pad + if x_label.is_empty() { 0 } else { ch + pad / 2 };
    // Room for about 10 characters per x tick label.
    let plot_w = (width as i64 - left - pad * 3).max(1);
    let x_target = ((plot_w / (ch * 10)).clamp(2, 10)) as usize;
    let x_ticks = nice_ticks(xl, xh, x_target);
    let x_last_w = tick_labels(&x_ticks)
        .last()
        .map(|l| text_size(l, ts).0 as i64)
        .unwrap_or(0);
    let right_margin = pad.max(x_last_w / 2 + pad);
    let right = (width as i64 - 1 - right_margin).max(left + 1);
    let bottom = (height as i64 - 1 - bottom_margin).max(top + 1);
    PlotFrame {
        left,
        top,
        right,
        bottom,
        x_ticks,
        y_ticks,
    }
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
    let (width, height) = (width.max(1), height.max(1));
    let mut img = RgbImage::from_pixel(width, height, BACKGROUND);
    let ts = text_scale(width, height);
    let ch = (8 * ts) as i32;
    let pad = (6 * ts) as i32;
    let tick = (4 * ts) as i64;
    let f = plot_frame(series, title, x_label, y_label, width, height);
    let (plot_w, plot_h) = (f.right - f.left, f.bottom - f.top);

    // Grid lines, then axes box.
    for &t in &f.x_ticks {
        let (px, _) = f.to_pixel(t, 0.0);
        fill_rect(&mut img, px.floor() as i64, f.top, 1, plot_h + 1, GRID);
    }
    for &t in &f.y_ticks {
        let (_, py) = f.to_pixel(0.0, t);
        fill_rect(&mut img, f.left, py.floor() as i64, plot_w + 1, 1, GRID);
    }

    // The series.
    let thickness = 1.6 * ts as f64;
    let mut any_data = false;
    for s in series {
        let color = Rgb(s.color);
        let finite: Vec<Option<(f64, f64)>> = s
            .points
            .iter()
            .map(|&(x, y)| (x.is_finite() && y.is_finite()).then(|| f.to_pixel(x, y)))
            .collect();
        let n_finite = finite.iter().flatten().count();
        any_data |= n_finite > 0;
        for w in finite.windows(2) {
            if let (Some(a), Some(b)) = (w[0], w[1]) {
                draw_line(&mut img, a.0, a.1, b.0, b.1, thickness, color);
            }
        }
        for (i, p) in finite.iter().enumerate() {
            let Some(p) = p else { continue };
            let prev = i > 0 && finite[i - 1].is_some();
            let next = i + 1 < finite.len() && finite[i + 1].is_some();
            if n_finite <= 25 || !(prev || next) {
                fill_disc(&mut img, p.0, p.1, 2.5 * ts as f64, color);
            }
        }
    }
    draw_rect(&mut img, f.left, f.top, plot_w + 1, plot_h + 1, AXIS);
    if !any_data {
        let msg = "no data";
        let (tw, th) = text_size(msg, ts);
        draw_text(
            &mut img,
            ((f.left + f.right) / 2 - tw as i64 / 2) as i32,
            ((f.top + f.bottom) / 2 - th as i64 / 2) as i32,
            msg,
            MUTED,
            ts,
        );
    }

    // Ticks and their labels.
    for (t, label) in f.x_ticks.iter().zip(tick_labels(&f.x_ticks)) {
        let (px, _) = f.to_pixel(*t, 0.0);
        let px = px.floor() as i64;
        fill_rect(&mut img, px, f.bottom + 1, 1, tick, AXIS);
        draw_text_centered(
            &mut img,
            px as i32,
            (f.bottom + 1 + tick) as i32 + pad / 2,
            &label,
            TEXT,
            ts,
        );
    }
    for (t, label) in f.y_ticks.iter().zip(tick_labels(&f.y_ticks)) {
        let (_, py) = f.to_pixel(0.0, *t);
        let py = py.floor() as i64;
        fill_rect(&mut img, f.left - tick, py, tick, 1, AXIS);
        let (tw, _) = text_size(&label, ts);
        draw_text(
            &mut img,
            (f.left - tick - tw as i64) as i32 - pad / 2,
            py as i32 - ch / 2,
            &label,
            TEXT,
            ts,
        );
    }

    // Title and axis labels.
    if !title.is_empty() {
        draw_text_centered(&mut img, (width / 2) as i32, pad, title, TEXT, ts);
    }
    if !x_label.is_empty() {
        draw_text_centered(
            &mut img,
            ((f.left + f.right) / 2) as i32,
            height as i32 - pad / 2 - ch,
            x_label,
            TEXT,
            ts,
        );
    }
    if !y_label.is_empty() {
        let (tw, _) = text_size(y_label, ts);
        draw_text_up(
            &mut img,
            pad,
            ((f.top + f.bottom) / 2 - tw as i64 / 2) as i32,
            y_label,
            TEXT,
            ts,
        );
    }

    draw_legend(&mut img, series, &f, ts);
    img
}

/// A boxed legend in the corner of the data area that hides the fewest points.
fn draw_legend(img: &mut RgbImage, series: &[Series], f: &PlotFrame, ts: u32) {
    let entries: Vec<&Series> = series.iter().filter(|s| !s.label.is_empty()).collect();
    if entries.is_empty() {
        return;
    }
    let ch = (8 * ts) as i64;
    let pad = (4 * ts) as i64;
    let swatch = (16 * ts) as i64;
    let row_h = ch + pad;
    let label_w = entries
        .iter()
        .map(|s| text_size(&s.label, ts).0 as i64)
        .max()
        .unwrap_or(0);
    let box_w = pad + swatch + pad + label_w + pad;
    let box_h = pad + entries.len() as i64 * row_h;
    let margin = pad;
    let corners = [
        (f.right - margin - box_w, f.top + margin), // top right
        (f.left + margin + 1, f.top + margin),      // top left
        (f.right - margin - box_w, f.bottom - margin - box_h), // bottom right
        (f.left + margin + 1, f.bottom - margin - box_h), // bottom left
    ];
    // Count data samples (points and segment midpoints) under each box.
    let covered = |(bx, by): (i64, i64)| -> usize {
        let inside = |p: (f64, f64)| {
            p.0 >= bx as f64
                && p.0 <= (bx + box_w) as f64
                && p.1 >= by as f64
                && p.1 <= (by + box_h) as f64
        };
        let mut n = 0;
        for s in series {
            let px: Vec<Option<(f64, f64)>> = s
                .points
                .iter()
                .map(|&(x, y)| (x.is_finite() && y.is_finite()).then(|| f.to_pixel(x, y)))
                .collect();
            for (i, p) in px.iter().enumerate() {
                let Some(p) = *p else { continue };
                n += inside(p) as usize;
                if let Some(Some(q)) = px.get(i + 1) {
                    // Sample long segments so a line crossing the box counts.
                    let steps = (((q.0 - p.0).abs() + (q.1 - p.1).abs()) / 4.0)
                        .ceil()
                        .clamp(1.0, 200.0) as usize;
                    for k in 1..steps {
                        let t = k as f64 / steps as f64;
                        n += inside((p.0 + (q.0 - p.0) * t, p.1 + (q.1 - p.1) * t)) as usize;
                    }
                }
            }
        }
        n
    };
    let (bx, by) = corners.iter().copied().min_by_key(|&c| covered(c)).unwrap();
    fill_rect(img, bx, by, box_w, box_h, BACKGROUND);
    draw_rect(img, bx, by, box_w, box_h, Rgb([190, 190, 190]));
    for (i, s) in entries.iter().enumerate() {
        let y = by + pad + i as i64 * row_h;
        let mid = y as f64 + ch as f64 / 2.0;
        draw_line(
            img,
            (bx + pad) as f64,
            mid,
            (bx + pad + swatch) as f64,
            mid,
            2.0 * ts as f64,
            Rgb(s.color),
        );
        draw_text(
            img,
            (bx + pad + swatch + pad) as i32,
            y as i32,
            &s.label,
            TEXT,
            ts,
        );
    }
}

/// Writes `img` as a PNG, creating missing parent folders; errors name the path.
pub fn save_png(img: &RgbImage, path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).with_context(|| {
            format!(
                "cannot create folder {} for {}",
                parent.display(),
                path.display()
            )
        })?;
    }
    img.save_with_format(path, ImageFormat::Png)
        .with_context(|| format!("cannot write PNG {}", path.display()))
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
            .any(|(_, y, p)| (y as i64) < f.top && *p == TEXT));
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
