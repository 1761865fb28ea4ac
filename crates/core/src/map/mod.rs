//! Maps: the working grid, PNG loading, map sets and the floor-plan generator.
pub mod catalog;
pub mod fingerprint;
pub mod generate;
pub mod gibson_source;
pub mod grid;
pub mod load;
pub mod prepared;
pub mod ray_steps;
pub mod rays;
pub mod reach;
pub mod testset;

pub use catalog::{resolve, MapEntry};
pub use grid::{Grid, SizeClass, CELL_AREA, CELL_SIZE};
pub use load::{load_png, save_png, MapError};
pub use prepared::PreparedMap;
