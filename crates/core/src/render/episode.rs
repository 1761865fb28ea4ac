//! One episode as an animated GIF: the map (free space light, obstacles dark,
//! a faint 1 m grid), the Absolutely Safe Zone shaded as in the paper's
//! Fig. 1 (target-first cells green, captor-first cells in faint per-captor
//! tints), the robots as discs of their true 0.2 m radius with a heading
//! "nose" (captors in blues with their index, the target red), short trails
//! of their recent positions, and a header with the step, |ASZ| and whether
//! the target has been caught.
//!
//! Frames use a few dozen flat colours, so the GIF encoder keeps an exact
//! palette (no dithering noise) and LZW compresses them well; cropping to the
//! map's free area keeps frames small.

use super::font::{draw_text, text_size};
use super::map_image::{FREE_COLOR, OBSTACLE_COLOR};
use super::raster::{draw_circle, draw_line, fill_disc, fill_rect, mix};
use crate::asz::{cells_to_m2, AszFields};
use crate::env::config::{PROBE_DIST, RADIUS};
use crate::env::placement::PlacementError;
use crate::env::{Action, Controller, Robot, Side, TrapEnv};
use crate::error::Chain;
use crate::fs::FsError;
use crate::map::prepared::PAD;
use crate::map::{Grid, PreparedMap, CELL_SIZE};
use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, Frame, Rgb, RgbImage, RgbaImage};
use std::collections::VecDeque;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why an episode could not be rendered; each message names the seed or
/// the file.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The episode's robots could not be placed.
    #[error("episode seed {seed}: {cause}")]
    Episode { seed: u64, cause: PlacementError },
    /// The GIF encoder refused; `what` says at which step.
    #[error("{what}: {}", Chain(.cause))]
    Gif {
        what: &'static str,
        cause: image::ImageError,
    },
    #[error("cannot create folder {} for {}: {}", .folder.display(), .out.display(), Chain(.cause))]
    Folder {
        folder: PathBuf,
        out: PathBuf,
        cause: std::io::Error,
    },
    #[error("cannot write GIF {}: {cause}", .out.display())]
    Write { out: PathBuf, cause: FsError },
}

/// How an episode is drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    /// Pixels per 0.05 m cell (at least 1).
    pub scale: u32,
    /// Draw every n-th step (the first and the last state are always drawn).
    pub every: u32,
    /// Delay between frames in milliseconds (GIF resolution: 10 ms). 100 ms
    /// with `every = 1` is real time (one step is 0.1 s).
    pub frame_delay_ms: u32,
    /// Crop to the bounding box of the map's free cells plus a 0.5 m margin.
    pub crop: bool,
    /// Shade the ASZ (target-first cells) and the captors' regions.
    pub show_asz: bool,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            scale: 2,
            every: 1,
            frame_delay_ms: 100,
            crop: true,
            show_asz: true,
        }
    }
}

/// What happened in a rendered episode.
#[derive(Clone, Debug, PartialEq)]
pub struct EpisodeSummary {
    /// Name of the map the seed picked.
    pub map: String,
    pub seed: u64,
    /// Steps played.
    pub steps: u32,
    pub captured: bool,
    /// |ASZ| of the final state, in cells and m².
    pub final_asz_cells: usize,
    pub final_asz_m2: f64,
    /// Frames in the GIF and its size in bytes.
    pub frames: usize,
    pub bytes: u64,
}

/// Target disc.
pub const TARGET_COLOR: Rgb<u8> = Rgb([225, 35, 35]);
/// Captor discs, by captor index (cycling).
pub const CAPTOR_COLORS: [Rgb<u8>; 6] = [
    Rgb([35, 95, 225]),
    Rgb([0, 150, 185]),
    Rgb([115, 70, 215]),
    Rgb([30, 55, 140]),
    Rgb([0, 115, 120]),
    Rgb([80, 120, 255]),
];
/// Target-first (ASZ) cells: this colour blended over the map.
pub const ASZ_COLOR: Rgb<u8> = Rgb([30, 185, 60]);
const ASZ_ALPHA: f32 = 0.45;
const CAPTOR_REGION_ALPHA: f32 = 0.13;
const OUTLINE: Rgb<u8> = Rgb([20, 20, 24]);
const COLLIDED_OUTLINE: Rgb<u8> = Rgb([255, 150, 0]);
const HEADER_BG: Rgb<u8> = Rgb([28, 30, 36]);
const HEADER_TEXT: Rgb<u8> = Rgb([245, 245, 245]);
const HEADER_MUTED: Rgb<u8> = Rgb([165, 170, 180]);
const CAPTURED_COLOR: Rgb<u8> = Rgb([255, 200, 0]);
const GRID_LINE: f32 = 0.07;
/// Steps of trail kept behind each robot (3 s).
const TRAIL_STEPS: usize = 30;
/// Margin around the free area when cropping (cells; 0.5 m).
const CROP_MARGIN: i64 = 10;
/// Frames are at least this many pixels wide (per text scale).
const MIN_WIDTH: u32 = 320;
/// The last frame stays this long (ms) before the animation loops.
const FINAL_HOLD_MS: u32 = 1500;

/// The colour of captor `i`.
pub fn captor_color(i: usize) -> Rgb<u8> {
    CAPTOR_COLORS[i % CAPTOR_COLORS.len()]
}

/// Where a map's cells land in a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameLayout {
    pub scale: u32,
    /// Grid row and column drawn at the top-left of the map area (may lie
    /// outside the grid: such cells are drawn as obstacle).
    pub row0: i64,
    pub col0: i64,
    /// Cells drawn down and across.
    pub rows: i64,
    pub cols: i64,
    /// Height of the text band above the map.
    pub header_h: u32,
    pub text_scale: u32,
    pub width: u32,
    pub height: u32,
    /// Grid side and extent, for the world-to-pixel mapping.
    side: usize,
}

/// Text scale of the header at `scale` pixels per cell.
fn text_scale_for(scale: u32) -> u32 {
    if scale >= 4 {
        2
    } else {
        1
    }
}

impl FrameLayout {
    /// The layout for `grid`, at least `MIN_WIDTH` pixels (per text scale) wide.
    pub fn new(grid: &Grid, opts: &RenderOptions) -> FrameLayout {
        FrameLayout::with_min_width(grid, opts, 0)
    }

    /// The layout for `grid`, widened (around the map's centre, with
    /// obstacle cells) to at least `min_width` pixels so header text fits.
    pub fn with_min_width(grid: &Grid, opts: &RenderOptions, min_width: u32) -> FrameLayout {
        let scale = opts.scale.max(1);
        let text_scale = text_scale_for(scale);
        let side = grid.side() as i64;
        let (mut r0, mut r1, mut c0, mut c1) = (0, side, 0, side);
        if opts.crop {
            let (mut rl, mut rh, mut cl, mut ch) = (side, -1, side, -1);
            for r in 0..side {
                for c in 0..side {
                    if grid.is_free(r as isize, c as isize) {
                        rl = rl.min(r);
                        rh = rh.max(r);
                        cl = cl.min(c);
                        ch = ch.max(c);
                    }
                }
            }
            if rh >= 0 {
                r0 = (rl - CROP_MARGIN).max(0);
                r1 = (rh + 1 + CROP_MARGIN).min(side);
                c0 = (cl - CROP_MARGIN).max(0);
                c1 = (ch + 1 + CROP_MARGIN).min(side);
            }
        }
        // Widen narrow crops (around their centre) so the header text fits.
        let min_cols = (MIN_WIDTH * text_scale).max(min_width).div_ceil(scale) as i64;
        if c1 - c0 < min_cols {
            let extra = min_cols - (c1 - c0);
            c0 -= extra / 2;
            c1 += extra - extra / 2;
        }
        let header_h = 3 * 4 * text_scale + 2 * line_height(text_scale);
        let (rows, cols) = (r1 - r0, c1 - c0);
        FrameLayout {
            scale,
            row0: r0,
            col0: c0,
            rows,
            cols,
            header_h,
            text_scale,
            width: cols as u32 * scale,
            height: rows as u32 * scale + header_h,
            side: grid.side(),
        }
    }

    /// Pixel position (x, y, fractional) of a world point (m).
    pub fn to_pixel(&self, p: [f64; 2]) -> (f64, f64) {
        let half = self.side as f64 * CELL_SIZE / 2.0;
        let (col, row) = ((p[0] + half) / CELL_SIZE, (half - p[1]) / CELL_SIZE);
        let s = self.scale as f64;
        (
            (col - self.col0 as f64) * s,
            (row - self.row0 as f64) * s + self.header_h as f64,
        )
    }

    /// Pixels per metre.
    pub fn pixels_per_metre(&self) -> f64 {
        self.scale as f64 / CELL_SIZE
    }
}

/// The static part of every frame: header band, map cells, 1 m grid, scale bar.
fn base_image(grid: &Grid, l: &FrameLayout) -> RgbImage {
    let mut img = RgbImage::from_pixel(l.width, l.height, HEADER_BG);
    let s = l.scale as i64;
    let cells_per_metre = (1.0 / CELL_SIZE).round() as i64;
    let centre = (l.side / 2) as i64;
    let grid_free = mix(FREE_COLOR, Rgb([0, 0, 0]), GRID_LINE);
    for r in 0..l.rows {
        for c in 0..l.cols {
            let (gr, gc) = (l.row0 + r, l.col0 + c);
            let free = grid.is_free(gr as isize, gc as isize);
            let color = if free { FREE_COLOR } else { OBSTACLE_COLOR };
            let (x, y) = (c * s, r * s + l.header_h as i64);
            fill_rect(&mut img, x, y, s, s, color);
            if free && s >= 2 {
                // Metre lines on cell boundaries aligned with the world origin.
                if (gc - centre).rem_euclid(cells_per_metre) == 0 {
                    fill_rect(&mut img, x, y, 1, s, grid_free);
                }
                if (gr - centre).rem_euclid(cells_per_metre) == 0 {
                    fill_rect(&mut img, x, y, s, 1, grid_free);
                }
            }
        }
    }
    // 1 m scale bar, bottom left, on a dark box.
    let ts = l.text_scale;
    let metre = l.pixels_per_metre().round() as i64;
    let pad = 3 * ts as i64;
    let (lw, lh) = text_size("1 m", ts);
    let box_w = metre.max(lw as i64) + 2 * pad;
    let box_h = lh as i64 + 3 * pad + 2;
    if box_w + 8 < l.width as i64 && box_h + 8 < (l.height - l.header_h) as i64 {
        let (x0, y0) = (4, l.height as i64 - 4 - box_h);
        fill_rect(&mut img, x0, y0, box_w, box_h, OBSTACLE_COLOR);
        draw_text(
            &mut img,
            (x0 + pad) as i32,
            (y0 + pad) as i32,
            "1 m",
            HEADER_TEXT,
            ts,
        );
        fill_rect(
            &mut img,
            x0 + pad,
            y0 + 2 * pad + lh as i64,
            metre,
            2,
            HEADER_TEXT,
        );
    }
    img
}

/// |ASZ| in cells of the current state, and every reached cell labelled
/// with its robot (captors 0..K, the target K on the ASZ's cells): the
/// per-robot fields of `TrapEnv::asz_cells`, so the count is the env's.
fn asz_regions(fields: &mut AszFields, env: &TrapEnv) -> (usize, Vec<(usize, u8)>) {
    let (captors, target) = env.asz_sources();
    let cells = fields.asz_cells(&**env.map(), target, &captors);
    (cells, fields.regions())
}

/// Per-step state kept for drawing.
struct Painter {
    layout: FrameLayout,
    base: RgbImage,
    map: Arc<PreparedMap>,
    fields: AszFields,
    trails: Vec<VecDeque<[f64; 2]>>,
    footer: String,
    show_asz: bool,
}

impl Painter {
    /// A painter for `env`'s current episode, its first state recorded.
    fn new(env: &TrapEnv, opts: &RenderOptions, footer: String) -> Painter {
        let map = env.map().clone();
        let min_width = header_width(
            env.cfg.episode_length,
            &footer,
            text_scale_for(opts.scale.max(1)),
        );
        let layout = FrameLayout::with_min_width(&map.grid, opts, min_width);
        let mut painter = Painter {
            base: base_image(&map.grid, &layout),
            layout,
            map,
            fields: AszFields::new(),
            trails: vec![VecDeque::with_capacity(TRAIL_STEPS + 1); env.num_agents()],
            footer,
            show_asz: opts.show_asz,
        };
        painter.record(env);
        painter
    }

    fn record(&mut self, env: &TrapEnv) {
        for (t, r) in self.trails.iter_mut().zip(&env.robots) {
            if t.len() == TRAIL_STEPS + 1 {
                t.pop_front();
            }
            t.push_back(r.pos);
        }
    }

    /// Draws the current state; returns the frame and |ASZ| in cells.
    fn frame(&mut self, env: &TrapEnv) -> (RgbImage, usize) {
        let (asz, regions) = asz_regions(&mut self.fields, env);
        let mut img = self.base.clone();
        let k = env.num_captors();
        if self.show_asz {
            self.paint_regions(&mut img, regions, k);
        }
        let l = &self.layout;
        let ppm = l.pixels_per_metre();
        let color_of = |i: usize| {
            if i == k {
                TARGET_COLOR
            } else {
                captor_color(i)
            }
        };
        // Trails under the robots.
        let trail_w = (0.06 * ppm).max(1.0);
        for (i, trail) in self.trails.iter().enumerate() {
            let c = mix(color_of(i), Rgb([255, 255, 255]), 0.45);
            for (a, b) in trail.iter().zip(trail.iter().skip(1)) {
                let (pa, pb) = (l.to_pixel(*a), l.to_pixel(*b));
                draw_line(&mut img, pa.0, pa.1, pb.0, pb.1, trail_w, c);
            }
        }
        if env.captured {
            let (x, y) = l.to_pixel(env.target().pos);
            draw_circle(
                &mut img,
                x,
                y,
                (PROBE_DIST + RADIUS) * ppm,
                (0.04 * ppm).max(1.5),
                CAPTURED_COLOR,
            );
        }
        for (i, robot) in env.robots.iter().enumerate() {
            draw_robot(&mut img, l, robot, color_of(i), (i < k).then_some(i));
        }
        self.draw_header(&mut img, env, asz);
        (img, asz)
    }

    /// Tints each ASZ / captor-region cell; apart from `frame` because it is
    /// the one per-cell loop, and it runs only with `show_asz`.
    fn paint_regions(&self, img: &mut RgbImage, regions: Vec<(usize, u8)>, k: usize) {
        let l = &self.layout;
        let s = l.scale as i64;
        let stride = self.map.stride;
        for (cell, label) in regions {
            let (color, alpha) = if label as usize == k {
                (ASZ_COLOR, ASZ_ALPHA)
            } else {
                (captor_color(label as usize), CAPTOR_REGION_ALPHA)
            };
            let (r, c) = (
                (cell / stride) as i64 - PAD as i64,
                (cell % stride) as i64 - PAD as i64,
            );
            let (x, y) = ((c - l.col0) * s, (r - l.row0) * s + l.header_h as i64);
            if x < 0 || y < l.header_h as i64 || x >= l.width as i64 || y >= l.height as i64 {
                continue;
            }
            for yy in y..(y + s).min(l.height as i64) {
                for xx in x..(x + s).min(l.width as i64) {
                    let p = img.get_pixel_mut(xx as u32, yy as u32);
                    *p = mix(*p, color, alpha);
                }
            }
        }
    }

    /// The header's step line, capture flag and footer; apart so `frame`
    /// reads as map, trails, robots, header.
    fn draw_header(&self, img: &mut RgbImage, env: &TrapEnv, asz: usize) {
        let l = &self.layout;
        let ts = l.text_scale;
        let pad = 4 * ts as i32;
        let line_h = line_height(ts) as i32;
        draw_text(
            img,
            pad,
            pad,
            &head_line(env.steps, env.cfg.episode_length, asz),
            HEADER_TEXT,
            ts,
        );
        if env.captured {
            let (w, _) = text_size(CAPTURED, ts);
            draw_text(
                img,
                l.width as i32 - pad - w as i32,
                pad,
                CAPTURED,
                CAPTURED_COLOR,
                ts,
            );
        }
        draw_text(img, pad, 2 * pad + line_h, &self.footer, HEADER_MUTED, ts);
    }
}

/// One robot: outline, disc, heading nose, and the captor index when it has
/// one; apart from `frame` because the label placement is its own rule.
fn draw_robot(
    img: &mut RgbImage,
    l: &FrameLayout,
    robot: &Robot,
    fill: Rgb<u8>,
    captor: Option<usize>,
) {
    let ppm = l.pixels_per_metre();
    let r_px = RADIUS * ppm;
    let outline = (0.025 * ppm).max(1.0);
    let (x, y) = l.to_pixel(robot.pos);
    let edge = if robot.collided {
        COLLIDED_OUTLINE
    } else {
        OUTLINE
    };
    fill_disc(img, x, y, r_px + outline, edge);
    fill_disc(img, x, y, r_px, fill);
    let (dx, dy) = (robot.theta.cos(), -robot.theta.sin());
    draw_line(
        img,
        x + dx * r_px * 0.3,
        y + dy * r_px * 0.3,
        x + dx * r_px * 1.6,
        y + dy * r_px * 1.6,
        (0.04 * ppm).max(1.0),
        OUTLINE,
    );
    let Some(i) = captor else { return };
    let label = i.to_string();
    let digit_scale = ((r_px / 7.0).floor() as u32).max(1);
    let (tw, th) = text_size(&label, digit_scale);
    if r_px >= 6.0 {
        // Centred in the disc, shifted against the nose.
        let (cx, cy) = (x - dx * r_px * 0.2, y - dy * r_px * 0.2);
        draw_text(
            img,
            (cx - tw as f64 / 2.0).round() as i32,
            (cy - th as f64 / 2.0).round() as i32,
            &label,
            HEADER_TEXT,
            digit_scale,
        );
    } else {
        draw_text(
            img,
            (x + r_px + 2.0) as i32,
            (y - r_px - th as f64) as i32,
            &label,
            OUTLINE,
            1,
        );
    }
}

const CAPTURED: &str = "CAPTURED";

/// First header line: step and |ASZ|.
fn head_line(step: u32, episode_length: u32, asz_cells: usize) -> String {
    format!(
        "step {step}/{episode_length}   |ASZ| = {:.2} m\u{00B2} ({asz_cells} cells)",
        cells_to_m2(asz_cells)
    )
}

/// Width in pixels the header needs.
/// The height of a header line: the font's ascent plus descent.
fn line_height(text_scale: u32) -> u32 {
    text_size("Ag", text_scale).1
}

fn header_width(episode_length: u32, footer: &str, text_scale: u32) -> u32 {
    let pad = 4 * text_scale;
    // Widest first line: the longest step count, a 3-digit area, and the capture flag.
    let head = head_line(episode_length, episode_length, 400 * 400);
    let head_w = text_size(&head, text_scale).0 + 3 * pad + text_size(CAPTURED, text_scale).0;
    head_w.max(text_size(footer, text_scale).0) + 2 * pad
}

fn to_frame(img: RgbImage, delay_ms: u32) -> Frame {
    let rgba: RgbaImage = image::DynamicImage::ImageRgb8(img).into_rgba8();
    Frame::from_parts(rgba, 0, 0, Delay::from_numer_denom_ms(delay_ms, 1))
}

/// Removes the temporaries (`.NAME.tmp-PID`, see `write_file_atomically`)
/// that killed renders left beside `out`; only those of `out`'s own name,
/// and only of processes no longer alive.
pub fn remove_dead_temporaries(out: &Path) {
    let Some(name) = out.file_name().map(|n| n.to_string_lossy().into_owned()) else {
        return;
    };
    let parent = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    let prefix = format!(".{name}.tmp-");
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = file
            .strip_prefix(&prefix)
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// The footer of a frame: map, team sizes, who plays and the speed ratio.
fn footer_line(env: &TrapEnv, captors: &str, target: &str) -> String {
    format!(
        "{}  {}v1  {} vs {}  v_e/v_p = {:.1}",
        env.map().grid.name,
        env.num_captors(),
        captors,
        target,
        env.cfg.speed_ratio()
    )
}

/// Frames of an episode played elsewhere (the Python env's `render()`):
/// the same picture `render_episode` draws, trails included. `record`
/// after every step; `frame` draws the current state.
pub struct LiveRender {
    painter: Painter,
}

impl LiveRender {
    /// Starts drawing `env`'s current episode; `captors` and `target` name
    /// who plays, for the footer.
    pub fn new(env: &TrapEnv, opts: &RenderOptions, captors: &str, target: &str) -> LiveRender {
        LiveRender {
            painter: Painter::new(env, opts, footer_line(env, captors, target)),
        }
    }

    /// Adds the state after a step to the trails.
    pub fn record(&mut self, env: &TrapEnv) {
        self.painter.record(env);
    }

    /// The current state as an RGB image.
    pub fn frame(&mut self, env: &TrapEnv) -> RgbImage {
        self.painter.frame(env).0
    }
}

/// Plays one episode from `seed` with the two controllers and writes it to
/// `out` as a looping GIF (parent folders are created). The environment is
/// left in the episode's final state.
pub fn render_episode(
    env: &mut TrapEnv,
    captors: &mut dyn Controller,
    target: &mut dyn Controller,
    seed: u64,
    opts: &RenderOptions,
    out: &Path,
) -> Result<EpisodeSummary, RenderError> {
    env.reset_state(seed)
        .map_err(|cause| RenderError::Episode { seed, cause })?;
    let gif = |what| move |cause| RenderError::Gif { what, cause };
    captors.reset(env, seed);
    target.reset(env, seed);
    let k = env.num_captors();
    let footer = footer_line(env, &captors.name(), &target.name());
    let mut painter = Painter::new(env, opts, footer);
    let map = painter.map.clone();

    let delay = opts.frame_delay_ms.max(10);
    let every = opts.every.max(1);
    let mut bytes: Vec<u8> = Vec::new();
    let mut frames = 0usize;
    let mut final_asz = 0usize;
    {
        let mut enc = GifEncoder::new_with_speed(&mut bytes, 10);
        enc.set_repeat(Repeat::Infinite)
            .map_err(gif("GIF encoder"))?;
        let mut pending: Option<RgbImage> = None;
        let mut acts = vec![Action::Stop; k + 1];
        let mut rewards = vec![0f32; k + 1];
        loop {
            let done = env.is_done();
            if env.steps.is_multiple_of(every) || done {
                let (img, asz) = painter.frame(env);
                final_asz = asz;
                if let Some(prev) = pending.replace(img) {
                    enc.encode_frame(to_frame(prev, delay))
                        .map_err(gif("encoding a GIF frame"))?;
                }
                frames += 1;
            }
            if done {
                break;
            }
            captors.act(env, Side::Captors, &mut acts[..k]);
            target.act(env, Side::Target, &mut acts[k..]);
            env.step_state(&acts, &mut rewards);
            painter.record(env);
        }
        if let Some(last) = pending {
            enc.encode_frame(to_frame(last, delay.max(FINAL_HOLD_MS)))
                .map_err(gif("encoding a GIF frame"))?;
        }
    } // the encoder writes the GIF trailer when dropped
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|cause| RenderError::Folder {
            folder: parent.to_path_buf(),
            out: out.to_path_buf(),
            cause,
        })?;
    }
    // Written to a temporary sibling, synced and renamed: a render killed
    // while writing leaves the previous GIF (or none), never half of one.
    remove_dead_temporaries(out);
    crate::fs::write_file_atomically(out, &bytes).map_err(|cause| RenderError::Write {
        out: out.to_path_buf(),
        cause,
    })?;
    Ok(EpisodeSummary {
        map: map.grid.name.clone(),
        seed,
        steps: env.steps,
        captured: env.captured,
        final_asz_cells: final_asz,
        final_asz_m2: cells_to_m2(final_asz),
        frames,
        bytes: bytes.len() as u64,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::{EnvConfig, Robot};
    use crate::heuristics::{Heuristic, Still};
    use image::codecs::gif::GifDecoder;
    use image::AnimationDecoder;

    /// A 6 m x 5 m room in the middle of a 16 m world, with a pillar.
    fn room_map() -> Arc<Vec<Arc<PreparedMap>>> {
        let mut g = Grid::blocked("test-room", 320);
        for r in 110..210 {
            for c in 100..220 {
                g.set_free(r, c, true);
            }
        }
        for r in 150..165 {
            for c in 150..160 {
                g.set_free(r, c, false);
            }
        }
        Arc::new(vec![Arc::new(PreparedMap::new(g))])
    }

    fn env(len: u32) -> TrapEnv {
        let cfg = EnvConfig {
            episode_length: len,
            observations: false,
            ..EnvConfig::default()
        };
        TrapEnv::new(cfg, room_map()).unwrap()
    }

    fn decode(path: &Path) -> Vec<RgbaImage> {
        let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        GifDecoder::new(file)
            .unwrap()
            .into_frames()
            .collect_frames()
            .unwrap()
            .into_iter()
            .map(|f| f.into_buffer())
            .collect()
    }

    /// Pixels of exactly `color` within / beyond `r` pixels of (x, y).
    fn count_near(img: &RgbaImage, color: Rgb<u8>, (x, y): (f64, f64), r: f64) -> (usize, usize) {
        let (mut near, mut far) = (0, 0);
        for (px, py, p) in img.enumerate_pixels() {
            if p.0[..3] == color.0 && p.0[3] == 255 {
                let d = (px as f64 + 0.5 - x).hypot(py as f64 + 0.5 - y);
                if d <= r {
                    near += 1;
                } else {
                    far += 1;
                }
            }
        }
        (near, far)
    }

    fn play(
        every: u32,
        seed: u64,
        dir: &Path,
    ) -> (TrapEnv, EpisodeSummary, Vec<RgbaImage>, FrameLayout) {
        let mut env = env(20);
        let mut captors: Box<dyn Controller> = Box::new(Heuristic);
        let mut target: Box<dyn Controller> = Box::new(Heuristic);
        let opts = RenderOptions {
            every,
            ..RenderOptions::default()
        };
        let out = dir.join(format!("sub/ep-{every}.gif"));
        let summary = render_episode(
            &mut env,
            captors.as_mut(),
            target.as_mut(),
            seed,
            &opts,
            &out,
        )
        .unwrap();
        assert_eq!(summary.bytes, std::fs::metadata(&out).unwrap().len());
        let frames = decode(&out);
        let (w, h) = frames[0].dimensions();
        let layout = FrameLayout::new(&env.map().grid, &opts);
        // The header may widen the frame; the map part keeps its rows.
        assert!(
            w >= layout.width && h == layout.height,
            "{w}x{h} vs {}x{}",
            layout.width,
            layout.height
        );
        let layout = FrameLayout::with_min_width(&env.map().grid, &opts, w);
        assert_eq!(layout.width, w);
        (env, summary, frames, layout)
    }

    #[test]
    fn episode_gif_has_one_frame_per_drawn_step_and_shows_the_target() {
        let dir = tempfile::tempdir().unwrap();
        let seed = 7;
        let (mut env, summary, frames, layout) = play(1, seed, dir.path());
        assert!(summary.steps >= 1 && summary.steps <= 20);
        assert_eq!(summary.steps, env.steps);
        assert_eq!(frames.len(), summary.steps as usize + 1);
        assert_eq!(summary.frames, frames.len());
        for f in &frames {
            assert_eq!(f.dimensions(), (layout.width, layout.height));
        }
        // Cropped: the 6 m x 5 m room plus margins, widened for the header.
        assert_eq!(layout.height, (100 + 20) * 2 + layout.header_h);
        assert!(
            layout.width >= 280 && layout.width < 640,
            "{}",
            layout.width
        );
        let footer_w = text_size("test-room  3v1  heuristic vs heuristic  v_e/v_p = 1.0", 1).0;
        assert!(layout.width >= footer_w + 8);

        // The final |ASZ| is the one the environment computes.
        let env_asz = env.asz_cells();
        assert_eq!(summary.final_asz_cells, env_asz);
        assert!(env_asz > 0 || summary.captured);

        // The target's red disc sits where the target is in the last frame...
        let r_px = RADIUS * layout.pixels_per_metre();
        let last_pos = env.target().pos;
        // Independently of `to_pixel`: the target's cell, relative to the crop.
        let (row, col) = env.map().grid.cell_of(last_pos);
        let cell_px = (
            (col as i64 - layout.col0) as f64 * 2.0 + 1.0,
            ((row as i64 - layout.row0) * 2) as f64 + 1.0 + layout.header_h as f64,
        );
        let (n_cell, _) = count_near(frames.last().unwrap(), TARGET_COLOR, cell_px, r_px + 2.5);
        assert!(n_cell as f64 > 0.6 * std::f64::consts::PI * r_px * r_px);
        let (near, far) = count_near(
            frames.last().unwrap(),
            TARGET_COLOR,
            layout.to_pixel(last_pos),
            r_px + 0.8,
        );
        assert!(
            near as f64 > 0.6 * std::f64::consts::PI * r_px * r_px,
            "only {near} red pixels at the target"
        );
        assert_eq!(far, 0, "red pixels away from the target");
        // ... and where it started in the first one.
        env.reset_state(seed).unwrap();
        let first_pos = env.target().pos;
        let (near0, far0) = count_near(
            &frames[0],
            TARGET_COLOR,
            layout.to_pixel(first_pos),
            r_px + 0.8,
        );

        assert!(near0 as f64 > 0.6 * std::f64::consts::PI * r_px * r_px);
        assert_eq!(far0, 0);
        // The captors are drawn in their colours near their positions.
        for i in 0..3 {
            let (n, _) = count_near(
                &frames[0],
                captor_color(i),
                layout.to_pixel(env.robots[i].pos),
                r_px + 0.8,
            );
            assert!(n > 50, "captor {i}: {n} pixels");
        }
        // The ASZ is shaded green (blended over free space) in the first frame.
        let asz_free = mix(FREE_COLOR, ASZ_COLOR, ASZ_ALPHA);
        let green = frames[0]
            .pixels()
            .filter(|p| p.0[..3] == asz_free.0)
            .count();
        assert!(green > 100, "{green} ASZ pixels");
        // The robots moved, so first and last frames differ in the map area.
        assert!(first_pos != last_pos || env.robots.iter().any(|r| r.pos != first_pos));
        assert_ne!(frames[0], *frames.last().unwrap());
    }

    #[test]
    fn every_nth_step_plus_the_last() {
        let dir = tempfile::tempdir().unwrap();
        let (_, summary, frames, _) = play(3, 11, dir.path());
        let s = summary.steps as usize;
        let expected = s / 3 + 1 + usize::from(!s.is_multiple_of(3));
        assert_eq!(frames.len(), expected, "steps {s}");
    }

    #[test]
    fn without_asz_shading_no_green() {
        let dir = tempfile::tempdir().unwrap();
        let mut env = env(3);
        let mut captors: Box<dyn Controller> = Box::new(Still);
        let mut target: Box<dyn Controller> = Box::new(Still);
        let opts = RenderOptions {
            show_asz: false,
            crop: false,
            scale: 1,
            ..RenderOptions::default()
        };
        let out = dir.path().join("plain.gif");
        let summary =
            render_episode(&mut env, captors.as_mut(), target.as_mut(), 1, &opts, &out).unwrap();
        assert_eq!(summary.steps, 3);
        let frames = decode(&out);
        assert_eq!(frames.len(), 4);
        let l = FrameLayout::new(&env.map().grid, &opts);
        assert_eq!((l.rows, l.cols), (320, 320));
        assert_eq!(frames[0].height(), 320 + l.header_h);
        assert!(frames[0].width() >= 320);
        let asz_free = mix(FREE_COLOR, ASZ_COLOR, ASZ_ALPHA);
        assert!(frames[0].pixels().all(|p| p.0[..3] != asz_free.0));
        assert!(summary.final_asz_cells > 0);
    }

    #[test]
    fn drawn_regions_count_the_env_asz() {
        let mut env = env(10);
        let mut fields = AszFields::new();
        let drawn = |fields: &mut AszFields, env: &TrapEnv| {
            let (cells, regions) = asz_regions(fields, env);
            let target_label = env.num_captors() as u8;
            assert_eq!(
                regions.iter().filter(|&&(_, l)| l == target_label).count(),
                cells
            );
            cells
        };
        for seed in 0..5 {
            env.reset_state(seed).unwrap();
            assert_eq!(drawn(&mut fields, &env), env.asz_cells(), "seed {seed}");
        }
        // A target boxed in by captors: small ASZ.
        let t = [0.5, 0.0];
        let robots = vec![
            Robot {
                pos: [0.9, 0.0],
                ..Robot::default()
            },
            Robot {
                pos: [0.1, 0.3],
                ..Robot::default()
            },
            Robot {
                pos: [0.1, -0.3],
                ..Robot::default()
            },
            Robot {
                pos: t,
                ..Robot::default()
            },
        ];
        env.set_robots(0, robots);
        assert_eq!(drawn(&mut fields, &env), env.asz_cells());
    }

    #[test]
    fn layout_maps_world_to_pixels() {
        let maps = room_map();
        let grid = &maps[0].grid;
        let l = FrameLayout::new(
            grid,
            &RenderOptions {
                crop: false,
                scale: 2,
                ..RenderOptions::default()
            },
        );
        // World origin = grid centre = cell boundary 160 -> pixel 320 (+ header).
        assert_eq!(l.to_pixel([0.0, 0.0]), (320.0, 320.0 + l.header_h as f64));
        assert_eq!(l.to_pixel([1.0, 1.0]), (360.0, 280.0 + l.header_h as f64));
        let c = FrameLayout::new(grid, &RenderOptions::default());
        assert_eq!((c.row0, c.rows), (100, 120));
        let (x, _) = c.to_pixel(grid.cell_center(150, 100));
        let (x_full, _) = l.to_pixel(grid.cell_center(150, 100));
        assert_eq!(x_full - x, c.col0 as f64 * 2.0);
    }
}
