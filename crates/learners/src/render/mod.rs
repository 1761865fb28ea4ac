//! Drawing maps and episodes to images.
pub mod canvas;
pub mod episode;
pub mod font;
pub mod heat_map;
pub mod map_image;
pub mod plot;
pub mod raster;
