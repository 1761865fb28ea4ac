pub mod asz;
pub mod env;
pub mod heuristics;
pub mod map;
