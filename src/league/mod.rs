//! The league: captor and target learners that train against pools of each
//! other's checkpoints (AlphaStar's league, adapted), with ratings on one
//! scale and a curriculum over the target's speed.
//!
//! - `config`: the league's TOML.
//! - `dir`: the league directory's layout.
//! - `open`: opening a league directory, every check before any write
//!   (identity, store, config).
//! - `players`: who plays, by name (`Seat`, main and heuristic names).
//! - `members`: the permanent heuristic members, the default ones and the
//!   extra ones a config adds (`[members]`).
//! - `pool`: snapshot folders and their rows (written once, adopted,
//!   quarantined, never deleted).
//! - `supervision`: the one outcome of every process exit, the crash budget.
//! - `store`: the store (players, matches, ratings, curriculum, heartbeats,
//!   crashes, seats, config) on SQLite or PostgreSQL, sqlx kept inside it.
//! - `process`: spawning a seat's process, per-host locks, logs.
//! - `worker`: `t2e-league worker`: runs seats taken from the store.
//! - `seats`: the manager's side of a league whose seats run on workers.
//! - `matchmaking`: PFSP opponent draws, pure and seeded.
//! - `ratings`: live Weng-Lin ratings and a batch Bradley-Terry fit.
//! - `curriculum`: the speed-ratio stages and when to move on.
//! - `learner`: one main learner's process: opponents per world, batched
//!   network opponents, matches, snapshots.
//! - `evaluator`: its own process: every snapshot plays a fixed panel
//!   (members, held-out teams, validation teams on validation maps).
//! - `panels`: the evaluator's held-out and validation teams and maps, as
//!   the config names them, loaded and checked.
//! - `preflight`: the checks of a new league's config that need its maps
//!   or checkpoints loaded (maps and checkpoints compared by content), run
//!   before anything is written.
//! - `selection`: the validation-best snapshot `export --best` exports.
//! - `manager`: `t2e-league run`: spawns and supervises the learners and
//!   the evaluator.
//! - `exploit`: `t2e-league exploit`: a fresh best response trained against
//!   one frozen player, its win rate recorded in the store.
//! - `status`: what `status` and `export` read from a league.

pub mod config;
pub mod curriculum;
pub mod dir;
pub mod evaluator;
pub mod evaluator_config;
pub mod exploit;
pub mod learner;
pub mod manager;
pub mod manager_lease;
pub mod matchmaking;
pub mod members;
pub mod open;
pub mod opponents;
pub mod panels;
pub mod payoff;
pub mod players;
pub mod pool;
pub mod preflight;
pub mod process;
pub mod ratings;
pub mod seats;
pub mod selection;
pub mod status;
pub mod store;
pub mod supervision;
pub mod worker;
