//! A map drawn as an RGB image: free space light, obstacles dark, the cells
//! where robots may be placed lightly tinted, a 1 m grid and a scale bar.
//! Episode renderers start from this picture and draw robots on top.

use super::font::{draw_text, text_size};
use super::raster::fill_rect;
use crate::map::{Grid, PreparedMap, CELL_SIZE};
use image::{Rgb, RgbImage};

/// Free cells.
pub const FREE_COLOR: Rgb<u8> = Rgb([250, 250, 247]);
/// Free cells more than 0.4 m from any obstacle (where robots are placed).
pub const SPAWN_COLOR: Rgb<u8> = Rgb([222, 236, 250]);
/// Obstacle cells and everything outside the house.
pub const OBSTACLE_COLOR: Rgb<u8> = Rgb([44, 46, 54]);
/// Scale bar and its label.
pub const SCALE_BAR_COLOR: Rgb<u8> = Rgb([255, 255, 255]);
/// Grid lines darken or lighten the pixels they cross by this share.
const GRID_LINE_MIX: f32 = 0.12;

/// Draws `grid` with `scale` pixels per cell (at least 1). Computes the
/// grid's spawn cells; use [`map_image_prepared`] when a `PreparedMap` exists.
pub fn map_image(grid: &Grid, scale: u32) -> RgbImage {
    map_image_prepared(&PreparedMap::new(grid.clone()), scale)
}

/// Draws a prepared map with `scale` pixels per cell (at least 1).
pub fn map_image_prepared(map: &PreparedMap, scale: u32) -> RgbImage {
    let grid = &map.grid;
    let scale = scale.max(1);
    let side = grid.side();
    let mut spawn = vec![false; side * side];
    for &i in &map.spawn_cells {
        spawn[i as usize] = true;
    }
    let px = side as u32 * scale;
    let mut img = RgbImage::from_fn(px, px, |x, y| {
        let (r, c) = ((y / scale) as usize, (x / scale) as usize);
        if !grid.is_free(r as isize, c as isize) {
            OBSTACLE_COLOR
        } else if spawn[r * side + c] {
            SPAWN_COLOR
        } else {
            FREE_COLOR
        }
    });
    if scale >= 2 {
        draw_metre_grid(&mut img, side, scale);
    }
    draw_scale_bar(&mut img, scale);
    img
}

/// Pixels per metre at `scale` pixels per cell.
pub fn pixels_per_metre(scale: u32) -> f64 {
    scale as f64 / CELL_SIZE
}

/// One-pixel lines every metre, aligned with the world origin at the grid
/// centre (whole metres fall on cell boundaries for even-sided grids).
fn draw_metre_grid(img: &mut RgbImage, side: usize, scale: u32) {
    let cells_per_metre = (1.0 / CELL_SIZE).round() as i64;
    let centre = (side / 2) as i64;
    let first = centre - (centre / cells_per_metre) * cells_per_metre;
    let (w, h) = img.dimensions();
    let mut cell = first;
    while cell <= side as i64 {
        let p = (cell as u32 * scale).min(w - 1);
        for t in 0..h {
            shade(img, p, t);
            if p != t {
                shade(img, t, p.min(h - 1));
            }
        }
        cell += cells_per_metre;
    }
}

/// Moves a pixel a little towards the opposite end of the grey scale, so grid
/// lines show on both free space and obstacles.
fn shade(img: &mut RgbImage, x: u32, y: u32) {
    let p = img.get_pixel_mut(x, y);
    let light = p.0.iter().map(|&v| v as u32).sum::<u32>() > 3 * 128;
    for v in p.0.iter_mut() {
        let f = *v as f32;
        *v = if light {
            f * (1.0 - GRID_LINE_MIX)
        } else {
            f + (255.0 - f) * GRID_LINE_MIX * 2.0
        } as u8;
    }
}

/// A 1 m bar with a "1 m" label on a dark box in the bottom-left corner.
fn draw_scale_bar(img: &mut RgbImage, scale: u32) {
    let metre = pixels_per_metre(scale).round() as u32;
    let text_scale = scale.div_ceil(2);
    let pad = 2 * text_scale + 2;
    let label = "1 m";
    let label_w = text_size(label, text_scale).0;
    let box_w = metre.max(label_w) + 2 * pad;
    let box_h = 8 * text_scale + 3 * pad + scale.max(2);
    let (w, h) = img.dimensions();
    if box_w + 4 > w || box_h + 4 > h {
        return; // too small an image for a legend
    }
    let (x0, y0) = (4, h - 4 - box_h);
    let (x0, y0) = (x0 as i64, y0 as i64);
    fill_rect(img, x0, y0, box_w as i64, box_h as i64, OBSTACLE_COLOR);
    draw_text(
        img,
        (x0 + pad as i64) as i32,
        (y0 + pad as i64) as i32,
        label,
        SCALE_BAR_COLOR,
        text_scale,
    );
    let bar_y = y0 + (2 * pad + 8 * text_scale) as i64;
    fill_rect(
        img,
        x0 + pad as i64,
        bar_y,
        metre as i64,
        scale.max(2) as i64,
        SCALE_BAR_COLOR,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    fn room_grid() -> Grid {
        // Free rows 100..160, cols 80..200: 3 m x 6 m.
        let mut g = Grid::blocked("room", 320);
        for r in 100..160 {
            for c in 80..200 {
                g.set_free(r, c, true);
            }
        }
        g
    }

    #[test]
    fn cells_get_their_colours() {
        let img = map_image(&room_grid(), 2);
        assert_eq!(img.dimensions(), (640, 640));
        // Cell (5, 5): obstacle; cell (101, 81): free, within 0.4 m of the wall;
        // cell (130, 141): room centre, a spawn cell. Pixel (2c+1, 2r+1) avoids grid lines.
        assert_eq!(*img.get_pixel(11, 11), OBSTACLE_COLOR);
        assert_eq!(*img.get_pixel(163, 203), FREE_COLOR);
        assert_eq!(*img.get_pixel(283, 261), SPAWN_COLOR);
    }

    #[test]
    fn metre_lines_pass_through_the_origin() {
        let img = map_image(&room_grid(), 2);
        // The world origin is at cell boundary 160, pixel 320: a shaded line.
        let on_line = *img.get_pixel(320, 261);
        assert_ne!(on_line, SPAWN_COLOR);
        assert!(on_line.0[0] < SPAWN_COLOR.0[0]);
        // Scale 1 draws no grid lines.
        let small = map_image(&room_grid(), 1);
        assert_eq!(*small.get_pixel(160, 130), SPAWN_COLOR);
    }
}
