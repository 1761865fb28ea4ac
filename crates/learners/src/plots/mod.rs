//! Plots to images, drawn with plotters: line plots (learning curves, mean
//! |ASZ| over time) and the payoff heat map. Maps and episodes are drawn by
//! the core (`t2e_core::render`), which needs no plotting library.
pub mod canvas;
pub mod heat_map;
pub mod line;
pub mod plotters_font;
