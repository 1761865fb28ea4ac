//! Small raster helpers for the renderers: 8x8 bitmap text (font8x8) and
//! filled rectangles, discs, rings and thick lines. Every helper takes signed
//! or fractional coordinates and clips to the image, so shapes that stick out
//! of the picture (or lie wholly outside it) are drawn in part or not at all,
//! never panicking.
//!
//! Pixel (x, y) covers [x, x+1) x [y, y+1); shapes given in continuous
//! coordinates colour the pixels whose centres (x + 0.5, y + 0.5) they cover.

use font8x8::{UnicodeFonts, BASIC_FONTS, LATIN_FONTS};
use image::{Rgb, RgbImage};

/// Glyph cell size in font pixels.
pub const GLYPH: u32 = 8;

/// The 8x8 bitmap of `c` (rows top to bottom, bit 0 = leftmost pixel):
/// ASCII, then Latin-1 (so `²`, `°`, `±`, `×` work). `None` if the font lacks it.
pub fn glyph(c: char) -> Option<[u8; 8]> {
    if c == '\u{00B2}' {
        // font8x8 0.3 lists U+00B2 three times (², ³ and ¹ share the code
        // point); draw the superscript two ourselves.
        return Some([0x0E, 0x18, 0x0C, 0x06, 0x1E, 0x00, 0x00, 0x00]);
    }
    BASIC_FONTS.get(c).or_else(|| LATIN_FONTS.get(c))
}

/// (width, height) in pixels of `text` drawn at `scale` (one line).
pub fn text_size(text: &str, scale: u32) -> (u32, u32) {
    let s = scale.max(1);
    (text.chars().count() as u32 * GLYPH * s, GLYPH * s)
}

/// Sets one pixel if it lies inside the image.
#[inline]
pub fn put(img: &mut RgbImage, x: i64, y: i64, color: Rgb<u8>) {
    if x >= 0 && y >= 0 && (x as u64) < img.width() as u64 && (y as u64) < img.height() as u64 {
        img.put_pixel(x as u32, y as u32, color);
    }
}

/// `alpha * color + (1 - alpha) * under`, per channel, rounded.
#[inline]
pub fn mix(under: Rgb<u8>, color: Rgb<u8>, alpha: f32) -> Rgb<u8> {
    let a = alpha.clamp(0.0, 1.0);
    let m = |u: u8, c: u8| {
        (u as f32 + (c as f32 - u as f32) * a)
            .round()
            .clamp(0.0, 255.0) as u8
    };
    Rgb([
        m(under.0[0], color.0[0]),
        m(under.0[1], color.0[1]),
        m(under.0[2], color.0[2]),
    ])
}

/// Blends `color` over one pixel with opacity `alpha` (0..1); clipped.
#[inline]
pub fn blend(img: &mut RgbImage, x: i64, y: i64, color: Rgb<u8>, alpha: f32) {
    if x >= 0 && y >= 0 && (x as u64) < img.width() as u64 && (y as u64) < img.height() as u64 {
        let p = img.get_pixel_mut(x as u32, y as u32);
        *p = mix(*p, color, alpha);
    }
}

/// Clipped pixel range [lo, hi) along one axis of length `len` for the span [a, a + w).
#[inline]
fn clip_span(a: i64, w: i64, len: u32) -> (u32, u32) {
    let lo = a.clamp(0, len as i64);
    let hi = a.saturating_add(w.max(0)).clamp(0, len as i64);
    (lo as u32, hi as u32)
}

/// Fills the `w x h` rectangle whose top-left pixel is (x, y); clipped.
pub fn fill_rect(img: &mut RgbImage, x: i64, y: i64, w: i64, h: i64, color: Rgb<u8>) {
    let (x0, x1) = clip_span(x, w, img.width());
    let (y0, y1) = clip_span(y, h, img.height());
    for yy in y0..y1 {
        for xx in x0..x1 {
            img.put_pixel(xx, yy, color);
        }
    }
}

/// Blends `color` with opacity `alpha` over a rectangle; clipped.
pub fn blend_rect(img: &mut RgbImage, x: i64, y: i64, w: i64, h: i64, color: Rgb<u8>, alpha: f32) {
    let (x0, x1) = clip_span(x, w, img.width());
    let (y0, y1) = clip_span(y, h, img.height());
    for yy in y0..y1 {
        for xx in x0..x1 {
            let p = img.get_pixel_mut(xx, yy);
            *p = mix(*p, color, alpha);
        }
    }
}

/// One-pixel outline of the `w x h` rectangle at (x, y); clipped.
pub fn draw_rect(img: &mut RgbImage, x: i64, y: i64, w: i64, h: i64, color: Rgb<u8>) {
    if w <= 0 || h <= 0 {
        return;
    }
    fill_rect(img, x, y, w, 1, color);
    fill_rect(img, x, y + h - 1, w, 1, color);
    fill_rect(img, x, y, 1, h, color);
    fill_rect(img, x + w - 1, y, 1, h, color);
}

/// Clipped inclusive pixel range whose centres can lie within [c - r, c + r].
#[inline]
fn pixel_range(c: f64, r: f64, len: u32) -> Option<(u32, u32)> {
    let lo = (c - r - 0.5).floor().max(0.0);
    let hi = (c + r - 0.5).ceil().min(len as f64 - 1.0);
    (lo.is_finite() && hi.is_finite() && lo <= hi).then_some((lo as u32, hi as u32))
}

/// Fills the pixels whose centres lie within `r` of (cx, cy); a disc smaller
/// than one pixel still colours the pixel holding its centre.
pub fn fill_disc(img: &mut RgbImage, cx: f64, cy: f64, r: f64, color: Rgb<u8>) {
    if !(cx.is_finite() && cy.is_finite() && r.is_finite()) || r < 0.0 {
        return;
    }
    let (Some((x0, x1)), Some((y0, y1))) = (
        pixel_range(cx, r, img.width()),
        pixel_range(cy, r, img.height()),
    ) else {
        return;
    };
    let mut any = false;
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
            if dx * dx + dy * dy <= r * r {
                img.put_pixel(x, y, color);
                any = true;
            }
        }
    }
    if !any {
        put(img, cx.floor() as i64, cy.floor() as i64, color);
    }
}

/// A ring: the pixels whose centres lie between `r - thickness / 2` and
/// `r + thickness / 2` from (cx, cy).
pub fn draw_circle(img: &mut RgbImage, cx: f64, cy: f64, r: f64, thickness: f64, color: Rgb<u8>) {
    if !(cx.is_finite() && cy.is_finite() && r.is_finite() && thickness.is_finite()) || r < 0.0 {
        return;
    }
    let half = (thickness / 2.0).max(0.5);
    let (r_in, r_out) = ((r - half).max(0.0), r + half);
    let (Some((x0, x1)), Some((y0, y1))) = (
        pixel_range(cx, r_out, img.width()),
        pixel_range(cy, r_out, img.height()),
    ) else {
        return;
    };
    for y in y0..=y1 {
        for x in x0..=x1 {
            let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
            let d2 = dx * dx + dy * dy;
            if d2 <= r_out * r_out && d2 >= r_in * r_in {
                img.put_pixel(x, y, color);
            }
        }
    }
}

/// A straight segment from (x0, y0) to (x1, y1) with round ends: the pixels
/// whose centres lie within `thickness / 2` (at least 0.5, so a thin line
/// has no gaps) of the segment.
pub fn draw_line(
    img: &mut RgbImage,
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    thickness: f64,
    color: Rgb<u8>,
) {
    line_pixels(img, x0, y0, x1, y1, thickness, |img, x, y| {
        img.put_pixel(x, y, color)
    });
}

fn line_pixels(
    img: &mut RgbImage,
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    thickness: f64,
    mut f: impl FnMut(&mut RgbImage, u32, u32),
) {
    if ![x0, y0, x1, y1, thickness].iter().all(|v| v.is_finite()) {
        return;
    }
    let half = (thickness / 2.0).max(0.5);
    let (w, h) = img.dimensions();
    let (Some((px0, px1)), Some((py0, py1))) = (
        pixel_range((x0 + x1) / 2.0, (x1 - x0).abs() / 2.0 + half, w),
        pixel_range((y0 + y1) / 2.0, (y1 - y0).abs() / 2.0 + half, h),
    ) else {
        return;
    };
    let (dx, dy) = (x1 - x0, y1 - y0);
    let len2 = dx * dx + dy * dy;
    for y in py0..=py1 {
        for x in px0..=px1 {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let t = if len2 > 0.0 {
                (((px - x0) * dx + (py - y0) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let (ex, ey) = (px - (x0 + t * dx), py - (y0 + t * dy));
            if ex * ex + ey * ey <= half * half {
                f(img, x, y);
            }
        }
    }
}

/// Writes `text` left to right with its top-left corner at (x, y), each font
/// pixel a `scale x scale` block; clipped. Characters the font lacks are
/// left blank (but take their place). Returns the width drawn over, in pixels.
pub fn draw_text(
    img: &mut RgbImage,
    x: i32,
    y: i32,
    text: &str,
    color: Rgb<u8>,
    scale: u32,
) -> u32 {
    let s = scale.max(1) as i64;
    let mut n = 0i64;
    for ch in text.chars() {
        if let Some(rows) = glyph(ch) {
            let cx = x as i64 + n * GLYPH as i64 * s;
            for (dy, bits) in rows.iter().enumerate() {
                for dx in 0..8i64 {
                    if bits & (1 << dx) != 0 {
                        fill_rect(img, cx + dx * s, y as i64 + dy as i64 * s, s, s, color);
                    }
                }
            }
        }
        n += 1;
    }
    (n * GLYPH as i64 * s) as u32
}

/// Writes `text` turned a quarter turn counter-clockwise (reading bottom to
/// top, as a y-axis label); (x, y) is the top-left corner of the turned
/// block, which is `8 * scale` wide and `text_size(text).0` tall.
pub fn draw_text_up(img: &mut RgbImage, x: i32, y: i32, text: &str, color: Rgb<u8>, scale: u32) {
    let s = scale.max(1) as i64;
    let (len, _) = text_size(text, scale);
    let bottom = y as i64 + len as i64; // the text's start
    for (k, ch) in text.chars().enumerate() {
        let Some(rows) = glyph(ch) else { continue };
        for (gy, bits) in rows.iter().enumerate() {
            for gx in 0..8i64 {
                if bits & (1 << gx) != 0 {
                    // Glyph column gx runs upwards, glyph row gy runs rightwards.
                    let px = x as i64 + gy as i64 * s;
                    let py = bottom - (k as i64 * 8 + gx + 1) * s;
                    fill_rect(img, px, py, s, s, color);
                }
            }
        }
    }
}

/// Writes `text` centred horizontally on `cx`, top at `y`.
pub fn draw_text_centered(
    img: &mut RgbImage,
    cx: i32,
    y: i32,
    text: &str,
    color: Rgb<u8>,
    scale: u32,
) {
    let (w, _) = text_size(text, scale);
    draw_text(img, cx - (w / 2) as i32, y, text, color, scale);
}

#[cfg(test)]
mod tests {
    use super::*;

    const BG: Rgb<u8> = Rgb([0, 0, 0]);
    const FG: Rgb<u8> = Rgb([255, 255, 255]);

    fn lit(img: &RgbImage) -> Vec<(u32, u32)> {
        img.enumerate_pixels()
            .filter(|(_, _, p)| **p != BG)
            .map(|(x, y, _)| (x, y))
            .collect()
    }

    #[test]
    fn text_lands_in_its_box() {
        let mut img = RgbImage::from_pixel(100, 40, BG);
        let w = draw_text(&mut img, 10, 5, "Hi", FG, 2);
        assert_eq!(w, 32);
        let px = lit(&img);
        assert!(px.len() > 20, "only {} pixels lit", px.len());
        for &(x, y) in &px {
            assert!(
                (10..42).contains(&x) && (5..21).contains(&y),
                "pixel ({x}, {y}) outside the text box"
            );
        }
        // 'H' has both vertical strokes: lit pixels in its left and right halves.
        assert!(px.iter().any(|&(x, _)| x < 18) && px.iter().any(|&(x, _)| (18..26).contains(&x)));
        // Glyph check against the font: pixel (row 3, col 0) of 'H' is set and maps to (10..12, 11..13).
        assert!(glyph('H').unwrap()[3] & 1 != 0);
        assert_eq!(*img.get_pixel(10, 11), FG);
        assert_eq!(*img.get_pixel(11, 12), FG);
    }

    #[test]
    fn text_clips_at_borders_without_panicking() {
        let mut img = RgbImage::from_pixel(20, 10, BG);
        draw_text(&mut img, -5, -3, "WWWW", FG, 3);
        draw_text(&mut img, 15, 8, "mmm", FG, 2);
        draw_text(&mut img, i32::MAX - 4, i32::MIN, "x", FG, 9);
        assert!(!lit(&img).is_empty());
        let mut tiny = RgbImage::new(0, 0);
        draw_text(&mut tiny, 0, 0, "a", FG, 1);
        draw_text_up(&mut tiny, 0, 0, "a", FG, 1);
    }

    #[test]
    fn turned_text_is_the_text_rotated_counter_clockwise() {
        let mut flat = RgbImage::from_pixel(24, 8, BG);
        draw_text(&mut flat, 0, 0, "Ab2", FG, 1);
        let expected = image::imageops::rotate270(&flat);
        let mut up = RgbImage::from_pixel(8, 24, BG);
        draw_text_up(&mut up, 0, 0, "Ab2", FG, 1);
        assert_eq!(up, expected);
        assert!(!lit(&up).is_empty());
        assert!(glyph('\u{00B2}').unwrap().iter().any(|&r| r != 0));
    }

    #[test]
    fn disc_is_round_and_clipped() {
        let mut img = RgbImage::from_pixel(30, 30, BG);
        fill_disc(&mut img, 15.0, 15.0, 5.0, FG);
        assert_eq!(*img.get_pixel(15, 15), FG);
        assert_eq!(*img.get_pixel(15, 11), FG);
        assert_eq!(*img.get_pixel(15, 21), BG);
        assert_eq!(*img.get_pixel(19, 19), BG); // corner of the bounding box
        let n = lit(&img).len() as f64;
        assert!((n - std::f64::consts::PI * 25.0).abs() < 10.0, "{n}");
        fill_disc(&mut img, -3.0, 29.0, 6.0, FG);
        assert_eq!(*img.get_pixel(0, 29), FG);
        fill_disc(&mut img, 1e300, f64::NAN, 3.0, FG);
        let mut img2 = RgbImage::from_pixel(5, 5, BG);
        fill_disc(&mut img2, 2.3, 2.6, 0.1, FG);
        assert_eq!(lit(&img2), vec![(2, 2)]);
    }

    #[test]
    fn lines_have_no_gaps_and_clip() {
        let mut img = RgbImage::from_pixel(50, 50, BG);
        draw_line(&mut img, 2.5, 2.5, 47.5, 30.5, 1.0, FG);
        for x in 2..48 {
            assert!(
                (0..50).any(|y| *img.get_pixel(x, y) == FG),
                "gap at column {x}"
            );
        }
        assert_eq!(*img.get_pixel(49, 49), BG);
        let mut thick = RgbImage::from_pixel(50, 50, BG);
        draw_line(&mut thick, 10.0, 25.0, 40.0, 25.0, 5.0, FG);
        assert_eq!(*thick.get_pixel(25, 23), FG);
        assert_eq!(*thick.get_pixel(25, 27), FG);
        assert_eq!(*thick.get_pixel(25, 29), BG);
        draw_line(&mut thick, -100.0, -100.0, 1e9, 1e9, 3.0, FG);
        assert_eq!(*thick.get_pixel(45, 45), FG);
        draw_line(&mut thick, f64::NAN, 0.0, 1.0, 1.0, 1.0, FG);
    }

    #[test]
    fn rects_and_blending() {
        let mut img = RgbImage::from_pixel(10, 10, BG);
        fill_rect(&mut img, -2, -2, 4, 4, FG);
        assert_eq!(lit(&img).len(), 4);
        draw_rect(&mut img, 5, 5, 10, 10, FG);
        assert_eq!(*img.get_pixel(5, 9), FG);
        assert_eq!(*img.get_pixel(7, 7), BG);
        blend_rect(&mut img, 6, 6, 2, 2, Rgb([200, 100, 0]), 0.5);
        assert_eq!(*img.get_pixel(6, 6), Rgb([100, 50, 0]));
        assert_eq!(
            mix(Rgb([10, 20, 30]), Rgb([110, 120, 130]), 0.25),
            Rgb([35, 45, 55])
        );
    }
}
