//! The one font every plot and render writes with: DejaVu Sans, embedded so
//! that a machine without fonts (a cluster node, a container) draws the same
//! text. Its licence is in assets/LICENSE-DejaVu.txt.
//!
//! Text is laid out here with ab_glyph (kerning, each glyph at its own
//! bearing) and drawn by `draw_text` for renders and by the learners'
//! plotters backend (`Canvas`) for plots.

use ab_glyph::{point, Font, FontRef, OutlinedGlyph, PxScale, ScaleFont};
use image::{Rgb, RgbImage};
use std::sync::OnceLock;

/// The font's file, for libraries that take a font as bytes (plotters).
pub const DEJAVU_SANS: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

fn font() -> &'static FontRef<'static> {
    static FONT: OnceLock<FontRef<'static>> = OnceLock::new();
    FONT.get_or_init(|| {
        FontRef::try_from_slice(DEJAVU_SANS).expect("the embedded DejaVu Sans parses")
    })
}

/// One line of text laid out at a pixel size, its box's top-left corner at
/// (0, 0): the box is the advance width by ascent plus descent.
pub struct Line {
    glyphs: Vec<OutlinedGlyph>,
    pub width: u32,
    pub height: u32,
}

/// Lays out `text` as one line at `px` pixels per em.
pub fn layout(text: &str, px: f64) -> Line {
    let scale = PxScale::from(px.clamp(1.0, 4096.0) as f32);
    let scaled = font().as_scaled(scale);
    let ascent = scaled.ascent();
    let (mut caret, mut last, mut glyphs) = (0.0f32, None, Vec::new());
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(last) = last {
            caret += scaled.kern(last, id);
        }
        let glyph = id.with_scale_and_position(scale, point(caret, ascent));
        caret += scaled.h_advance(id);
        last = Some(id);
        glyphs.extend(font().outline_glyph(glyph));
    }
    Line {
        glyphs,
        width: caret.ceil().max(0.0) as u32,
        height: (ascent - scaled.descent()).ceil().max(0.0) as u32,
    }
}

impl Line {
    /// Calls `pixel(x, y, coverage)` for every pixel the glyphs cover, in
    /// the box's coordinates.
    pub fn for_each_pixel(&self, mut pixel: impl FnMut(i32, i32, f32)) {
        for g in &self.glyphs {
            let b = g.px_bounds();
            g.draw(|x, y, coverage| {
                if coverage > 0.0 {
                    pixel(
                        b.min.x as i32 + x as i32,
                        b.min.y as i32 + y as i32,
                        coverage.min(1.0),
                    );
                }
            });
        }
    }
}

/// The pixel size of render text at `scale` (1 for frames under 1000 pixels).
fn pixel_size(scale: u32) -> f64 {
    11.0 * scale.max(1) as f64
}

/// (width, height) in pixels of `text` written at `scale` (one line).
pub fn text_size(text: &str, scale: u32) -> (u32, u32) {
    let line = layout(text, pixel_size(scale));
    (line.width, line.height)
}

/// Writes `text` with its top-left corner at (x, y), clipped to the image,
/// in its one colour: a pixel is the text's where the glyph covers at least
/// half of it. Renders keep few flat colours so that a GIF's palette holds
/// them exactly; anti-aliased edges would add hundreds and make the encoder
/// quantise every colour of the frame. Returns the text's width in pixels.
pub fn draw_text(
    img: &mut RgbImage,
    x: i32,
    y: i32,
    text: &str,
    color: Rgb<u8>,
    scale: u32,
) -> u32 {
    let line = layout(text, pixel_size(scale));
    let (w, h) = (img.width() as i64, img.height() as i64);
    line.for_each_pixel(|dx, dy, coverage| {
        let (px, py) = (x as i64 + dx as i64, y as i64 + dy as i64);
        if coverage >= 0.5 && px >= 0 && py >= 0 && px < w && py < h {
            img.put_pixel(px as u32, py as u32, color);
        }
    });
    line.width
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_lands_in_its_box_and_clips_at_borders() {
        const BG: Rgb<u8> = Rgb([0, 0, 0]);
        const FG: Rgb<u8> = Rgb([255, 255, 255]);
        let mut img = RgbImage::from_pixel(100, 40, BG);
        let w = draw_text(&mut img, 10, 5, "Hi", FG, 2);
        let (tw, th) = text_size("Hi", 2);
        assert_eq!(w, tw);
        let lit: Vec<(u32, u32)> = img
            .enumerate_pixels()
            .filter(|(_, _, p)| **p != BG)
            .map(|(x, y, _)| (x, y))
            .collect();
        assert!(lit.len() > 20, "only {} pixels lit", lit.len());
        for &(x, y) in &lit {
            assert!(
                (10..10 + tw).contains(&x) && (5..5 + th).contains(&y),
                "pixel ({x}, {y}) outside the {tw}x{th} text box"
            );
        }
        // Only the text's colour is written (no blended edges), and 'H' has
        // two stems: pixels in its left and right thirds.
        assert!(img.pixels().all(|p| *p == BG || *p == FG));
        let full: Vec<u32> = img
            .enumerate_pixels()
            .filter(|(_, _, p)| **p == FG)
            .map(|(x, _, _)| x)
            .collect();
        let h_w = text_size("H", 2).0;
        assert!(full.iter().any(|&x| x < 10 + h_w / 3));
        assert!(full.iter().any(|&x| x > 10 + h_w * 2 / 3 && x < 10 + h_w));
        // Longer text is wider; a bigger scale is taller; kerning and
        // bearings keep a word's width below the sum of its letters'.
        assert!(text_size("Hi there", 1).0 > text_size("Hi", 1).0);
        assert!(text_size("Hi", 2).1 > text_size("Hi", 1).1);
        assert!(text_size("AV", 2).0 < text_size("A", 2).0 + text_size("V", 2).0);
        // Clipped, never a panic.
        let mut small = RgbImage::from_pixel(20, 10, BG);
        draw_text(&mut small, -5, -3, "WWWW", FG, 3);
        draw_text(&mut small, i32::MAX - 4, i32::MIN, "x", FG, 9);
        assert!(small.pixels().any(|p| *p != BG));
        draw_text(&mut RgbImage::new(0, 0), 0, 0, "a", FG, 1);
    }
}
