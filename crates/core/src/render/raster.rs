//! Small raster helpers for the episode and map renderers: filled
//! rectangles, discs, rings and thick lines (text is `font`'s). Every helper takes signed
//! or fractional coordinates and clips to the image, so shapes that stick out
//! of the picture (or lie wholly outside it) are drawn in part or not at all,
//! never panicking.
//!
//! Pixel (x, y) covers [x, x+1) x [y, y+1); shapes given in continuous
//! coordinates colour the pixels whose centres (x + 0.5, y + 0.5) they cover.

use image::{Rgb, RgbImage};

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
        fill_rect(&mut img, 5, 5, 10, 10, FG);
        assert_eq!(*img.get_pixel(9, 9), FG);
        assert_eq!(*img.get_pixel(4, 4), BG);
        assert_eq!(
            mix(Rgb([10, 20, 30]), Rgb([110, 120, 130]), 0.25),
            Rgb([35, 45, 55])
        );
    }
}
