//! The league's data: players, matches, ratings, seats, panels, as named
//! types the rules compute with and the store reads and writes by column
//! name (`sqlx::FromRow`), and the enums its text columns hold. A value the program does not know
//! (a side, kind or state written by a newer build) is an error when read,
//! never taken for a default.

use t2e_core::env::Side;

/// What kind of member a player is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A main learner (its row holds its latest checkpoint).
    Learner,
    /// A frozen checkpoint of a learner, in the pool.
    Snapshot,
    /// A rule-based controller, a permanent pool member.
    Heuristic,
    /// A main exploiter.
    Exploiter,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::Learner => "learner",
            Kind::Snapshot => "snapshot",
            Kind::Heuristic => "heuristic",
            Kind::Exploiter => "exploiter",
        }
    }
}

/// A stored value this program cannot read back: a column holding a name
/// it does not know, or a row that breaks the store's rules.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum RowError {
    #[error("unknown {what} {value:?}")]
    Unknown { what: &'static str, value: String },
    #[error("player {player} names the checkpoint {path:?}, outside the league's pool folder; refusing it")]
    CheckpointOutsidePool { player: String, path: String },
}

fn unknown(what: &'static str, value: String) -> RowError {
    RowError::Unknown { what, value }
}

impl TryFrom<String> for Kind {
    type Error = RowError;
    fn try_from(s: String) -> Result<Kind, RowError> {
        [
            Kind::Learner,
            Kind::Snapshot,
            Kind::Heuristic,
            Kind::Exploiter,
        ]
        .into_iter()
        .find(|k| k.name() == s)
        .ok_or_else(|| unknown("player kind", s))
    }
}

pub(super) fn side_name(side: Side) -> &'static str {
    match side {
        Side::Captors => "captors",
        Side::Target => "target",
    }
}

/// A side as the store writes it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct StoredSide(pub Side);

impl TryFrom<String> for StoredSide {
    type Error = RowError;
    fn try_from(s: String) -> Result<StoredSide, RowError> {
        match s.as_str() {
            "captors" => Ok(StoredSide(Side::Captors)),
            "target" => Ok(StoredSide(Side::Target)),
            _ => Err(unknown("side", s)),
        }
    }
}

/// What a learner (or the evaluator) says it is doing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BeatState {
    /// Waiting for the other side to catch up (pacing).
    Waiting,
    Training,
    Evaluating,
    /// Reached its budget.
    Done,
    /// Stopped before its budget, on request.
    Stopped,
}

impl BeatState {
    pub fn name(self) -> &'static str {
        match self {
            BeatState::Waiting => "waiting",
            BeatState::Training => "training",
            BeatState::Evaluating => "evaluating",
            BeatState::Done => "done",
            BeatState::Stopped => "stopped",
        }
    }

    /// A process in this state should be alive and heartbeating.
    pub fn is_working(self) -> bool {
        matches!(
            self,
            BeatState::Waiting | BeatState::Training | BeatState::Evaluating
        )
    }
}

impl TryFrom<String> for BeatState {
    type Error = RowError;
    fn try_from(s: String) -> Result<BeatState, RowError> {
        [
            BeatState::Waiting,
            BeatState::Training,
            BeatState::Evaluating,
            BeatState::Done,
            BeatState::Stopped,
        ]
        .into_iter()
        .find(|k| k.name() == s)
        .ok_or_else(|| unknown("heartbeat state", s))
    }
}

impl std::fmt::Display for BeatState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A player as written.
#[derive(Clone, Debug, PartialEq)]
pub struct NewPlayer {
    pub name: String,
    pub side: Side,
    pub kind: Kind,
    pub parent: Option<i64>,
    pub env_steps: u64,
    pub curriculum_stage: usize,
    /// Checkpoint folder relative to the league directory, and the SHA-256
    /// of its `meta.json`.
    pub checkpoint: Option<(String, String)>,
}

/// A player as read back.
#[derive(Clone, Debug, PartialEq)]
pub struct Player {
    pub id: i64,
    pub name: String,
    pub side: Side,
    pub kind: Kind,
    pub parent: Option<i64>,
    pub created_at_ms: i64,
    pub env_steps: u64,
    pub curriculum_stage: usize,
    pub checkpoint: Option<(String, String)>,
    /// Why it no longer plays (missing or corrupt files), if it does not.
    pub quarantined: Option<String>,
}

/// The players for an error message: every one but the snapshots by name,
/// the snapshots counted (a league keeps hundreds; `status` lists them).
pub fn player_names(players: &[Player]) -> String {
    let mut names: Vec<String> = players
        .iter()
        .filter(|p| p.kind != Kind::Snapshot)
        .map(|p| p.name.clone())
        .collect();
    let snapshots = players.len() - names.len();
    match snapshots {
        0 => {}
        1 => names.push("1 snapshot (`status` lists it)".into()),
        n => names.push(format!("{n} snapshots (`status` lists them)")),
    }
    names.join(", ")
}

/// A player as the pure rules' tests build them: no checkpoint, stage 0,
/// created at time 0, playing.
#[cfg(test)]
pub fn test_player(
    id: i64,
    name: &str,
    side: Side,
    kind: Kind,
    parent: Option<i64>,
    env_steps: u64,
) -> Player {
    Player {
        id,
        name: name.into(),
        side,
        kind,
        parent,
        created_at_ms: 0,
        env_steps,
        curriculum_stage: 0,
        checkpoint: None,
        quarantined: None,
    }
}

/// The `players` row as stored.
#[derive(Clone, sqlx::FromRow)]
pub(super) struct PlayerRow {
    id: i64,
    name: String,
    #[sqlx(try_from = "String")]
    side: StoredSide,
    #[sqlx(try_from = "String")]
    kind: Kind,
    parent: Option<i64>,
    created_at_ms: i64,
    #[sqlx(try_from = "i64")]
    env_steps: u64,
    #[sqlx(try_from = "i64")]
    curriculum_stage: usize,
    checkpoint_path: Option<String>,
    checkpoint_sha256: Option<String>,
    quarantined: Option<String>,
}

/// A checkpoint path as the store may hold it: relative to the league's
/// pool folder and inside it (no `..`, not absolute). The pool folder is
/// the only path hosts share, so a row naming anything else is refused.
pub fn inside_pool(rel: &str) -> bool {
    use std::path::Component;
    let path = std::path::Path::new(rel);
    !rel.is_empty() && path.components().all(|c| matches!(c, Component::Normal(_)))
}

impl PlayerRow {
    /// The row as a player, a checkpoint path outside the pool dropped and
    /// said in `quarantined`: for a report, where one bad row must not hide
    /// the whole league.
    pub(super) fn flagged(self) -> Player {
        let name = self.name.clone();
        match Player::try_from(self.clone()) {
            Ok(p) => p,
            Err(why) => Player {
                id: self.id,
                name,
                side: self.side.0,
                kind: self.kind,
                parent: self.parent,
                created_at_ms: self.created_at_ms,
                env_steps: self.env_steps,
                curriculum_stage: self.curriculum_stage,
                checkpoint: None,
                quarantined: Some(why.to_string()),
            },
        }
    }
}

impl TryFrom<PlayerRow> for Player {
    type Error = RowError;
    fn try_from(r: PlayerRow) -> Result<Player, RowError> {
        if let Some(path) = r.checkpoint_path.as_deref().filter(|p| !inside_pool(p)) {
            return Err(RowError::CheckpointOutsidePool {
                player: r.name,
                path: path.to_string(),
            });
        }
        Ok(Player {
            id: r.id,
            name: r.name,
            side: r.side.0,
            kind: r.kind,
            parent: r.parent,
            created_at_ms: r.created_at_ms,
            env_steps: r.env_steps,
            curriculum_stage: r.curriculum_stage,
            checkpoint: r.checkpoint_path.zip(r.checkpoint_sha256),
            quarantined: r.quarantined,
        })
    }
}

/// One finished episode between a captor team and a target.
#[derive(Clone, Debug, PartialEq)]
pub struct MatchRecord {
    /// Names the episode: the same key is recorded once.
    pub key: String,
    pub captor_player: i64,
    pub target_player: i64,
    pub map: String,
    pub num_captors: usize,
    pub speed_ratio: f64,
    pub seed: u64,
    pub captured: bool,
    pub steps: u32,
    pub final_asz_m2: Option<f64>,
    pub recorded_by: String,
}

/// Wins and games of the captor team `captor` against the target `target`.
#[derive(Clone, Copy, Debug, PartialEq, sqlx::FromRow)]
pub struct PairResult {
    pub captor: i64,
    pub target: i64,
    #[sqlx(try_from = "i64")]
    pub captor_wins: u64,
    #[sqlx(try_from = "i64")]
    pub games: u64,
}

/// A learner's (or the evaluator's) latest heartbeat.
#[derive(Clone, Debug, PartialEq, sqlx::FromRow)]
pub struct Heartbeat {
    pub learner: String,
    pub pid: i64,
    /// The machine it runs on (its pid means something only there).
    pub host: Option<String>,
    #[sqlx(try_from = "String")]
    pub state: BeatState,
    #[sqlx(try_from = "i64")]
    pub env_steps: u64,
    pub steps_per_s: f64,
    pub at_ms: i64,
}

/// A learner process that exited unasked.
#[derive(Clone, Debug, PartialEq, sqlx::FromRow)]
pub struct Crash {
    pub learner: String,
    pub exit_status: String,
    pub message: String,
    pub at_ms: i64,
}

/// A curriculum stage change.
#[derive(Clone, Debug, PartialEq, sqlx::FromRow)]
pub struct StageChange {
    #[sqlx(try_from = "i64")]
    pub stage: usize,
    pub speed_ratio: f64,
    pub reason: String,
    pub at_ms: i64,
}

/// One live rating, as the history keeps it.
#[derive(Clone, Copy, Debug, PartialEq, sqlx::FromRow)]
pub struct RatingEntry {
    /// The match that moved it (None for a rating set by hand).
    pub match_id: Option<i64>,
    pub mu: f64,
    pub sigma: f64,
    pub at_ms: i64,
}

/// Where a seat stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeatState {
    /// To be run (held by a worker while its lease is live).
    Open,
    /// Reached its budget.
    Done,
    /// Cannot run (a worker found it cannot start); the league stops.
    Failed,
}

impl SeatState {
    pub fn name(self) -> &'static str {
        match self {
            SeatState::Open => "open",
            SeatState::Done => "done",
            SeatState::Failed => "failed",
        }
    }
}

impl TryFrom<String> for SeatState {
    type Error = RowError;
    fn try_from(s: String) -> Result<SeatState, RowError> {
        [SeatState::Open, SeatState::Done, SeatState::Failed]
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| unknown("seat state", s))
    }
}

/// A seat the manager defined: a main learner, an exploiter or the
/// evaluator, run by whichever worker holds its lease.
#[derive(Clone, Debug, PartialEq, sqlx::FromRow)]
pub struct SeatRow {
    pub name: String,
    #[sqlx(try_from = "String")]
    pub state: SeatState,
    /// The worker holding it (its lease may have expired).
    pub holder: Option<String>,
    pub host: Option<String>,
    pub lease_until_ms: i64,
    /// How many times a worker has taken it.
    #[sqlx(try_from = "i64")]
    pub claims: u64,
    pub reason: Option<String>,
}

impl SeatRow {
    /// Why the league stops, if one of `seats` failed.
    pub fn first_failure(seats: &[SeatRow]) -> Option<String> {
        seats
            .iter()
            .find(|s| s.state == SeatState::Failed)
            .map(|f| {
                format!(
                    "seat {} failed: {}",
                    f.name,
                    f.reason.as_deref().unwrap_or("no reason recorded")
                )
            })
    }

    /// Held by a worker whose lease has not expired at `now_ms`.
    pub fn held_at(&self, now_ms: i64) -> bool {
        self.holder.is_some() && self.lease_until_ms >= now_ms
    }
}

/// The evaluator's panels of controllers that are not members.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Panel {
    /// `[evaluator] held_out_captors / held_out_targets` on the training maps.
    HeldOut,
    /// `[evaluator] validation_*` on the validation maps: chooses `export --best`.
    Validation,
}

impl Panel {
    pub fn name(self) -> &'static str {
        match self {
            Panel::HeldOut => "held-out",
            Panel::Validation => "validation",
        }
    }
}

/// One finished panel episode of a member against a held-out opponent.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldOutEpisode {
    /// Names the episode: the same key is recorded once.
    pub key: String,
    pub panel: Panel,
    pub member: i64,
    /// The opponent's controller, as the config names it.
    pub opponent: String,
    pub map: String,
    pub speed_ratio: f64,
    pub seed: u64,
    pub captured: bool,
    pub steps: u32,
}

/// A member's episodes against one opponent of one panel.
#[derive(Clone, Debug, PartialEq)]
pub struct HeldOutResult {
    pub member: i64,
    pub panel: Panel,
    pub opponent: String,
    pub captures: u64,
    pub episodes: u64,
    /// Steps of all its episodes together (Time is steps / episodes).
    pub steps: u64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn player_names_names_all_but_snapshots_and_counts_those() {
        let p = |id, name: &str, kind| test_player(id, name, Side::Target, kind, None, 0);
        let mut players = vec![
            p(1, "target-main", Kind::Learner),
            p(2, "rule-based-target", Kind::Heuristic),
            p(3, "target-exploiter", Kind::Exploiter),
        ];
        assert_eq!(
            player_names(&players),
            "target-main, rule-based-target, target-exploiter"
        );
        players.push(p(4, "target-snap-000000051200", Kind::Snapshot));
        assert_eq!(
            player_names(&players),
            "target-main, rule-based-target, target-exploiter, 1 snapshot (`status` lists it)"
        );
        players.push(p(5, "target-snap-000000102400", Kind::Snapshot));
        assert_eq!(
            player_names(&players),
            "target-main, rule-based-target, target-exploiter, 2 snapshots (`status` lists them)"
        );
    }
}
