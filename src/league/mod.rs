//! The league: captor and target learners that train against pools of each
//! other's checkpoints (AlphaStar's league, adapted), with ratings on one
//! scale and a curriculum over the target's speed.
//!
//! - `store`: the SQLite store (players, matches, ratings, curriculum,
//!   heartbeats, crashes, config), sqlx kept inside it.
//! - `matchmaking`: PFSP opponent draws, pure and seeded.
//! - `ratings`: live Weng-Lin ratings and a batch Bradley-Terry fit.
//! - `curriculum`: the speed-ratio stages and when to move on.

pub mod curriculum;
pub mod matchmaking;
pub mod ratings;
pub mod store;
