//! Drawing maps, episodes and plots to images. Maps and episodes are the
//! core's (`t2e_core::render`), re-exported here; plots and the payoff heat
//! map are drawn with plotters.
pub mod canvas;
pub mod font;
pub mod heat_map;
pub mod plot;

pub use t2e_core::render::{episode, map_image, raster};
