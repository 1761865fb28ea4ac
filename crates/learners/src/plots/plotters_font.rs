//! The core's embedded DejaVu Sans (`t2e_core::render::font`), registered
//! with plotters, which
//! measures legends and label areas with it. plotters' own ab_glyph drawing
//! drops the glyphs' left bearings and puts the baseline half an em below
//! the anchor, so its text looked spaced ("cap tors") and sat too high:
//! `Canvas` draws text with the core's layout instead.

use std::sync::Once;
use t2e_core::render::font::DEJAVU_SANS;

/// The family name plots ask plotters for.
pub const FAMILY: &str = "sans-serif";

/// Registers the embedded font with plotters (once per process).
pub fn register() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        plotters::style::register_font(FAMILY, plotters::style::FontStyle::Normal, DEJAVU_SANS)
            .unwrap_or_else(|_| panic!("the embedded DejaVu Sans does not parse"));
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use t2e_core::render::font::layout;

    #[test]
    fn plotters_measures_with_the_embedded_font() {
        use plotters::prelude::*;
        register();
        let font: TextStyle = (FAMILY, 20).into_font().into();
        let (w, _) = font.font.box_size("captors").unwrap();
        assert!(w.abs_diff(layout("captors", 20.0).width) <= 1, "{w}");
    }
}
