//! Drawing maps and episodes to images: map PNGs, episode GIFs and single
//! frames of a running episode, with the embedded font (no libtorch, so the
//! Python package renders too). Plots live with the learners.
pub mod episode;
pub mod font;
pub mod map_image;
pub mod raster;
