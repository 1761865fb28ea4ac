//! The league: captor and target learners that train against pools of each
//! other's checkpoints (AlphaStar's league, adapted), with ratings on one
//! scale and a curriculum over the target's speed.
//!
//! Three floors, each a folder, each importing only the ones below it:
//!
//! - `data`: the league's data types (players, matches, ratings, seats,
//!   panels), which the rules compute with and the store keeps.
//! - `rules/`: pure and seeded, no store, no process:
//!   - `config`: the league's TOML; `evaluator_config`: its `[evaluator]`;
//!   - `players`: who plays, by name (`Seat`, main and heuristic names);
//!   - `members`: the permanent heuristic members, the default ones and
//!     the extra ones a config adds (`[members]`);
//!   - `matchmaking`: PFSP opponent draws; `payoff`: the payoff table;
//!   - `ratings`: live Weng-Lin ratings and a batch Bradley-Terry fit;
//!   - `curriculum`: the speed-ratio stages and when to move on;
//!   - `roles`: every answer that depends on a seat's role (one row per
//!     seat), the snapshot rule and the pacing of the main learners;
//!   - `selection`: the validation-best snapshot `export --best` exports;
//!   - `supervision`: the one outcome of every process exit, the crash
//!     budget.
//! - `store/`: the store (players, matches, ratings, curriculum,
//!   heartbeats, crashes, seats, config) on SQLite or PostgreSQL, sqlx kept
//!   inside it; its migrations are in `league/migrations`.
//! - `run/`: the league's processes and folders:
//!   - `dir`: the league directory's layout; `open`: opening one, every
//!     check before any write (identity, store, config); `preflight`: the
//!     checks of a new league's config that need its maps or checkpoints
//!     loaded;
//!   - `pool`: snapshot folders and their rows (written once, adopted,
//!     quarantined, never deleted);
//!   - `child`: the league's child processes as one typed command, which
//!     the parents spawn and the CLI reads back;
//!   - `process`: spawning a seat's process, per-host locks, logs;
//!   - `manager` (`t2e-league run`) and `manager_lease`; `worker`
//!     (`t2e-league worker`); `seats`: the manager's side of a league
//!     whose seats run on workers; `supervisor`: the one loop the three
//!     run, each as a small policy;
//!   - `learner`: one main learner's process; `opponents`: the opponents
//!     it plays per world;
//!   - `evaluator` and `panels`: every snapshot against a fixed panel;
//!   - `exploit`: a fresh best response against one frozen player;
//!   - `status`: what `status` and `export` read from a league;
//!   - `view`: what the manager and `exploit` show while they run, as
//!     calls on a `View` the caller implements (the CLI's progress bars).
//!
//! Users keep the modules' short paths (`league::config`, `league::store`,
//! `league::learner`) through the re-exports below; inside the crate each
//! file names the floor it imports from (`crate::rules::config`,
//! `t2e_core::env`), so its arrows can be read from its imports.

pub mod data;
pub mod rules;
pub mod run;
pub mod store;

pub use rules::{
    config, curriculum, evaluator_config, matchmaking, members, payoff, players, ratings, roles,
    selection, supervision,
};
pub use run::{
    child, dir, evaluator, exploit, exploit_key, learner, manager, manager_lease, open, opponents,
    panels, pool, preflight, process, seats, status, supervisor, view, worker,
};
