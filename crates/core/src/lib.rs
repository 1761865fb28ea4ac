//! t2e-core: the T2E target-trapping environment without libtorch or a
//! database — maps, the ASZ, the environment, the rule-based robots, the
//! evaluation protocols, and the file-system code every writer shares.
//! The learners and the league build on it (the `t2e` crate re-exports
//! these modules under the same names).
pub mod algorithm;
pub mod asz;
pub mod env;
pub mod error;
pub mod fs;
pub mod heuristics;
pub mod map;
pub mod protocol;
pub mod render;
pub mod util;

/// The project's root folder (where `maps/` and `../shared` are found
/// when the working folder is elsewhere).
pub const PROJECT_ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
