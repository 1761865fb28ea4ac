//! Drawing maps and episodes to images.
pub mod episode;
pub mod map_image;
pub mod plot;
pub mod text;
