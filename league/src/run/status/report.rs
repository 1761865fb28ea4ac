//! The report `status` prints, row by row.
//!
//! `status --json` prints `StatusReport` as JSON. Its shape is stable:
//! fields are only ever added, never renamed or removed.
//! ```text
//! { "league": str, "dir": str, "matches": int,
//!   "players": [{ "id", "name", "side": "captors"|"target",
//!                 "kind": "learner"|"snapshot"|"heuristic"|"exploiter",
//!                 "parent": int|null, "env_steps", "curriculum_stage",
//!                 "rating": float, "rating_sigma": float,   // live Weng-Lin
//!                 "bt_elo": float,                          // Bradley-Terry fit
//!                 "games", "wins", "win_rate": float|null,
//!                 "quarantined": str|null }],
//!   "curriculum": { "stage", "speed_ratio",
//!                   "history": [{ "stage", "speed_ratio", "reason", "at_ms" }] },
//!   "learners": [{ "name", "pid", "host": str|null, "state", "env_steps",
//!                  "steps_per_s", "heartbeat_age_s" }],   // state "dead": it said it was
//!                                          // working, but its process is gone
//!                                          // (or silent for 10 min elsewhere);
//!                                          // the evaluator's env_steps counts
//!                                          // the league's panel episodes
//!   "payoff": [{ "captor", "target", "captor_wins", "games" }],
//!   "crashes": [{ "learner", "exit_status", "message", "at_ms" }],
//!   "seats": [{ "name", "state": "open"|"done"|"failed", "host": str|null,
//!               "lease_left_s": float|null, "claims", "reason": str|null }],
//!                                          // leagues on workers only
//!   "panel": [{ "member", "member_name", "opponent", "opponent_name",
//!               "episodes", "member_wins", "win_rate",
//!               "win_rate_low", "win_rate_high",   // evaluator's episodes, 95% Wilson
//!               "held_out": bool }],   // a held-out opponent: "opponent" 0,
//!                                      // "opponent_name" its controller
//!   "exploits": [{ "player", "player_name", "player_sha256": str|null,
//!                  "player_env_steps": int|null,   // the frozen weights
//!                  "outdated": bool,   // the player's weights are newer now
//!                  "side", "best_response", "budget",
//!                  "env_steps", "train_s", "seed", "maps", "speed_ratio",
//!                  "episodes", "best_response_wins", "win_rate",
//!                  "win_rate_low", "win_rate_high" }] }  // `exploit`: a fresh
//!                                          // best response's wins against the
//!                                          // frozen player, 95% Wilson
//! ```

use crate::store::Kind;
use serde::Serialize;
use t2e_core::env::Side;

#[derive(Clone, Debug, Serialize)]
pub struct PlayerRow {
    pub id: i64,
    pub name: String,
    pub side: Side,
    pub kind: Kind,
    pub parent: Option<i64>,
    pub env_steps: u64,
    pub curriculum_stage: usize,
    pub rating: f64,
    pub rating_sigma: f64,
    pub bt_elo: f64,
    pub games: u64,
    pub wins: u64,
    pub win_rate: Option<f64>,
    pub quarantined: Option<String>,
}

#[derive(Clone, Debug, Serialize)]
pub struct StageRow {
    pub stage: usize,
    pub speed_ratio: f64,
    pub reason: String,
    pub at_ms: i64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Curriculum {
    pub stage: usize,
    pub speed_ratio: f64,
    pub history: Vec<StageRow>,
}

#[derive(Clone, Debug, Serialize)]
pub struct LearnerRow {
    pub name: String,
    pub pid: i64,
    /// The host it runs on (its pid is that host's).
    pub host: Option<String>,
    pub state: String,
    pub env_steps: u64,
    pub steps_per_s: f64,
    pub heartbeat_age_s: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct PayoffRow {
    pub captor: i64,
    pub target: i64,
    pub captor_wins: u64,
    pub games: u64,
}

#[derive(Clone, Debug, Serialize)]
pub struct CrashRow {
    pub learner: String,
    pub exit_status: String,
    pub message: String,
    pub at_ms: i64,
}

#[derive(Clone, Debug, Serialize)]
pub struct StatusReport {
    pub league: String,
    pub dir: String,
    pub matches: u64,
    pub players: Vec<PlayerRow>,
    pub curriculum: Curriculum,
    pub learners: Vec<LearnerRow>,
    pub payoff: Vec<PayoffRow>,
    pub crashes: Vec<CrashRow>,
    /// Seats as leases, for a league whose seats run on workers (empty
    /// otherwise).
    pub seats: Vec<SeatStatus>,
    /// The evaluator's panel, per member: only its episodes, so members
    /// compare whatever the matchmaker chose for them.
    pub panel: Vec<PanelRow>,
    /// Approximate best responses (`t2e-league exploit`), oldest first.
    pub exploits: Vec<ExploitRow>,
}

/// One map set of one exploit: how often a fresh best response beat the
/// frozen player.
#[derive(Clone, Debug, Serialize)]
pub struct ExploitRow {
    pub player: i64,
    pub player_name: String,
    /// SHA-256 of the frozen weights' meta.json (null for a heuristic).
    pub player_sha256: Option<String>,
    /// The player's env steps when it was frozen (null when unknown: an
    /// exploit recorded before they were, of a player trained on since).
    pub player_env_steps: Option<u64>,
    /// The result is against an older version of the player: its checkpoint
    /// now is not the one frozen (a main learner that trained on).
    pub outdated: bool,
    pub side: String,
    pub best_response: String,
    pub budget: String,
    pub env_steps: u64,
    pub train_s: f64,
    pub seed: u64,
    pub maps: String,
    pub speed_ratio: f64,
    pub episodes: u64,
    pub best_response_wins: u64,
    pub win_rate: f64,
    pub win_rate_low: f64,
    pub win_rate_high: f64,
}

/// The frozen weights of an exploit, as a table cell: the hash's first 12
/// digits and the player's env steps then (`?` when not recorded).
pub fn frozen_label(e: &ExploitRow) -> String {
    match &e.player_sha256 {
        None => "heuristic".into(),
        Some(sha) => format!(
            "{} @{}",
            &sha[..sha.len().min(12)],
            e.player_env_steps
                .map(|n| n.to_string())
                .unwrap_or_else(|| "?".into())
        ),
    }
}

/// One member's results against one panel opponent.
#[derive(Clone, Debug, Serialize)]
pub struct PanelRow {
    pub member: i64,
    pub member_name: String,
    pub opponent: i64,
    pub opponent_name: String,
    pub episodes: u64,
    /// Episodes the member won (captured as captors, escaped as target).
    pub member_wins: u64,
    pub win_rate: f64,
    /// 95% Wilson interval of the win rate.
    pub win_rate_low: f64,
    pub win_rate_high: f64,
    /// The opponent is held out: a controller the league never plays
    /// (`[evaluator] held_out_*` or `validation_*`); `opponent` is
    /// then 0 (no player) and `opponent_name` its controller.
    pub held_out: bool,
    /// The opponent is on the validation panel (`[evaluator]
    /// validation_*`, on the validation maps): what `export --best` reads.
    pub validation: bool,
    /// Mean episode length in steps (Time), where recorded (not for the
    /// matches against members).
    pub mean_steps: Option<f64>,
}

impl PanelRow {
    /// The opponent as a table shows it, with its panel.
    pub fn opponent_label(&self) -> String {
        if self.validation {
            format!("{} (validation)", self.opponent_name)
        } else if self.held_out {
            format!("{} (held out)", self.opponent_name)
        } else {
            self.opponent_name.clone()
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct SeatStatus {
    pub name: String,
    /// open, done or failed.
    pub state: String,
    /// The host of the worker holding it while its lease is live.
    pub host: Option<String>,
    pub lease_left_s: Option<f64>,
    /// How many times a worker has taken it.
    pub claims: u64,
    pub reason: Option<String>,
}
