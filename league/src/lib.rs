//! The league: captor and target learners that train against pools of each
//! other's checkpoints (AlphaStar's league, adapted), with ratings on one
//! scale and a curriculum over the target's speed.
//!
//! Three floors, each a folder, each importing only the ones below it,
//! beside `error`, the crate's one error type (`LeagueError`) that every
//! floor above the store returns:
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
//! - `run/`: the league's processes and folders, one folder per role:
//!   - `folder/`: the league directory's layout (`layout`), its snapshot
//!     pool (`pool`: written once, adopted, quarantined, never deleted),
//!     and opening a league, every check before any write (`open`);
//!   - `evaluation/`: every snapshot against a fixed panel (`evaluator`),
//!     the panels (`panels`), and the panel checks of a new league that
//!     need its maps or checkpoints loaded (`preflight`);
//!   - `seat/`: one main learner's process (`learner`) and the opponents
//!     it plays per world (`opponents`);
//!   - `processes/`: the manager (`t2e-league run`) and its lease, the
//!     workers, the manager's side of seats run on workers (`seats`), the
//!     one loop the three supervise in (`supervising_loop`), the child
//!     processes as one typed command (`child`) and spawning them with
//!     per-host locks and logs (`spawn`);
//!   - `exploit/`: a fresh best response against one frozen player;
//!   - `status/`: what `status` and `export` read from a league;
//!   - `view`: what the manager and `exploit` show while they run, as
//!     calls on a `View` the caller implements (the CLI's progress bars).
//!
//! Every module has one path, the one its file has: `league::rules::config`,
//! `league::run::seat::learner`, so a path says which floor a name lives
//! on, and a file's imports show its arrows.

pub mod data;
pub mod error;
pub mod rules;
pub mod run;
pub mod store;
