//! Every question whose answer depends on a seat's role, answered here
//! and nowhere else: its row in the store, whether the config runs it,
//! when it snapshots and whether it then starts again, whose name its
//! snapshots carry, and its training run's config; and the pacing rule
//! between the two main learners. One row per seat (`SeatRules::of`),
//! held by a table test.

use crate::data::{BeatState, Kind};
use crate::rules::config::LeagueConfig;
use crate::rules::players::{Seat, SeatRole};
use t2e_core::env::Side;
use t2e_learners::learn::train::TrainConfig;

/// A seat's answers under one config.
#[derive(Clone, Debug)]
pub struct SeatRules {
    pub seat: Seat,
    /// Its player row's kind.
    pub kind: Kind,
    /// Whether the config runs it (main learners always; an exploiter
    /// where `[exploiters]` turns its side on).
    pub enabled: bool,
    /// When it adds a snapshot of itself to the pool.
    pub snapshot: SnapshotRule,
    /// Whether it goes back to its initial weights after each snapshot: an
    /// exploiter does, unless it is the target exploiter and
    /// `target_resets = false`.
    pub resets_after_snapshot: bool,
    /// The owner its snapshots are named by (`OWNER-snap-STEPS`): the side
    /// for a main learner, the seat's own name for an exploiter.
    pub snapshot_owner: String,
}

impl SeatRules {
    pub fn of(cfg: &LeagueConfig, seat: Seat) -> SeatRules {
        let exploiter = seat.role == SeatRole::Exploiter;
        let resets_after_snapshot =
            exploiter && (seat.side == Side::Captors || cfg.exploiters.target_resets);
        let every_env_steps = cfg.snapshots.every_env_steps;
        let (win_rate, timeout_env_steps) = match seat.role {
            SeatRole::Main => (cfg.snapshots.win_rate, cfg.snapshots.timeout_env_steps),
            // One that never resets has no attempt to end: it snapshots on
            // a clock, winning or not.
            SeatRole::Exploiter if !resets_after_snapshot => (0.0, every_env_steps),
            SeatRole::Exploiter => (cfg.exploiters.win_rate, cfg.exploiters.timeout_env_steps),
        };
        SeatRules {
            seat,
            kind: if exploiter {
                Kind::Exploiter
            } else {
                Kind::Learner
            },
            enabled: !exploiter || cfg.exploiters.enabled(seat.side),
            snapshot: SnapshotRule {
                every_env_steps,
                win_rate,
                timeout_env_steps,
            },
            resets_after_snapshot,
            snapshot_owner: snapshot_owner(seat),
        }
    }

    /// Its training run: the side's, and for an exploiter its own name and
    /// seed (its own initial weights and episodes), and the target
    /// exploiter's prior where `exploiters.target_prior` is set. The other
    /// side is played per world by opponents the league draws.
    pub fn train_config(&self, cfg: &LeagueConfig) -> TrainConfig {
        let mut t = cfg.train_config(self.seat.side);
        if self.seat.role == SeatRole::Exploiter {
            t.name = self.seat.name();
            t.seed ^= 0xE7_0000;
            if let (Side::Target, Some(prior)) = (self.seat.side, cfg.exploiters.target_prior) {
                // Its own prior in place of the main target's, planner and
                // all: the rule-based target's at that weight, or none.
                t.target.net.heuristic_prior = prior;
                t.target.net.prior_teacher = None;
            }
        }
        t
    }

    /// The player name of its snapshot at `env_steps`.
    pub fn snapshot_name(&self, env_steps: u64) -> String {
        snapshot_name(self.seat, env_steps)
    }
}

/// Whose name a seat's snapshots carry: the side for a main learner, the
/// seat's own name for an exploiter. No setting changes it.
fn snapshot_owner(seat: Seat) -> String {
    match seat.role {
        SeatRole::Main => seat.side.name().to_string(),
        SeatRole::Exploiter => seat.name(),
    }
}

/// The player name of `seat`'s snapshot at `env_steps`.
pub fn snapshot_name(seat: Seat, env_steps: u64) -> String {
    format!("{}-snap-{env_steps:012}", snapshot_owner(seat))
}

/// The seat a learner's player row stands for (a main learner or an
/// exploiter of its side); None for any other kind.
pub fn seat_of_row(side: Side, kind: Kind) -> Option<Seat> {
    match kind {
        Kind::Learner => Some(Seat::main(side)),
        Kind::Exploiter => Some(Seat::exploiter(side)),
        _ => None,
    }
}

/// Whether a main learner at `mine` env steps waits for the other main
/// learner, given the other's last heartbeat (state, env steps, age in ms;
/// None before its first): it does while it is more than `lead` ahead of a
/// learner that is still training. A learner that is done, stopped or
/// silent for two minutes (crashed, restarting) is not waited for.
pub fn should_wait(mine: u64, other: Option<(BeatState, u64, i64)>, lead: u64) -> bool {
    if lead == 0 {
        return false;
    }
    match other {
        None => mine > lead,
        Some((state, steps, age_ms)) => {
            matches!(state, BeatState::Training | BeatState::Waiting)
                && age_ms < 120_000
                && mine > steps.saturating_add(lead)
        }
    }
}

/// When a learner adds a snapshot of itself to the pool.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnapshotRule {
    /// At least this many env steps since its last snapshot...
    pub every_env_steps: u64,
    /// ...and winning at least this share of its games since then...
    pub win_rate: f64,
    /// ...or this many env steps since its last snapshot, winning or not.
    pub timeout_env_steps: u64,
}

/// Whether a learner `since` env steps past its last snapshot, having won
/// `wins` of `games` since, snapshots now (AlphaStar's rule: when it beats
/// its opponents, or at a timeout so the pool keeps moving).
pub fn should_snapshot(since: u64, wins: u64, games: u64, rule: SnapshotRule) -> bool {
    let winning = games > 0 && wins as f64 / games as f64 >= rule.win_rate;
    (since >= rule.every_env_steps && winning) || since >= rule.timeout_env_steps
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The role table: each seat's answers under one config, written out
    /// by hand.
    #[test]
    fn every_seat_answers_its_role_questions_from_one_row() {
        let cfg = LeagueConfig::parse(
            "seed = 7\n[snapshots]\nevery_env_steps = 50_000\nwin_rate = 0.55\ntimeout_env_steps = 90_000\n\
             [exploiters]\ncaptors = true\ntarget = false\nwin_rate = 0.7\ntimeout_env_steps = 120_000\n",
        )
        .unwrap();
        // seat, kind, enabled, resets, (every, win rate, timeout), owner
        let table = [
            (
                Seat::main(Side::Captors),
                Kind::Learner,
                true,
                false,
                (50_000, 0.55, 90_000),
                "captors",
            ),
            (
                Seat::main(Side::Target),
                Kind::Learner,
                true,
                false,
                (50_000, 0.55, 90_000),
                "target",
            ),
            (
                Seat::exploiter(Side::Captors),
                Kind::Exploiter,
                true,
                true,
                (50_000, 0.7, 120_000),
                "captors-exploiter",
            ),
            (
                Seat::exploiter(Side::Target),
                Kind::Exploiter,
                false,
                true,
                (50_000, 0.7, 120_000),
                "target-exploiter",
            ),
        ];
        for (seat, kind, enabled, resets, (every, win, timeout), owner) in table {
            let r = SeatRules::of(&cfg, seat);
            assert_eq!(r.kind, kind, "{}", seat.name());
            assert_eq!(r.enabled, enabled, "{}", seat.name());
            assert_eq!(r.resets_after_snapshot, resets, "{}", seat.name());
            assert_eq!(
                r.snapshot,
                SnapshotRule {
                    every_env_steps: every,
                    win_rate: win,
                    timeout_env_steps: timeout
                },
                "{}",
                seat.name()
            );
            assert_eq!(r.snapshot_owner, owner);
            assert_eq!(
                r.snapshot_name(806_400),
                format!("{owner}-snap-000000806400")
            );
            assert_eq!(seat_of_row(seat.side, kind), Some(seat));
            let t = r.train_config(&cfg);
            let side = cfg.train_config(seat.side);
            match seat.role {
                SeatRole::Main => assert_eq!(t.hash(), side.hash()),
                SeatRole::Exploiter => {
                    assert_eq!((t.name, t.seed), (seat.name(), side.seed ^ 0xE7_0000))
                }
            }
        }
        assert_eq!(seat_of_row(Side::Target, Kind::Snapshot), None);
    }

    #[test]
    fn a_learner_snapshots_when_it_wins_or_at_the_timeout() {
        let rule = SnapshotRule {
            every_env_steps: 40_000,
            win_rate: 0.55,
            timeout_env_steps: 80_000,
        };
        assert!(
            should_snapshot(40_000, 11, 20, rule),
            "55% after 40 k steps"
        );
        assert!(!should_snapshot(40_000, 10, 20, rule), "50% is under 55%");
        assert!(
            !should_snapshot(39_999, 20, 20, rule),
            "winning, but too soon"
        );
        assert!(
            !should_snapshot(60_000, 0, 0, rule),
            "no games: not winning"
        );
        assert!(
            should_snapshot(80_000, 0, 0, rule),
            "the timeout, winning or not"
        );
        assert!(should_snapshot(80_000, 0, 20, rule));
    }

    #[test]
    fn a_target_exploiter_that_keeps_learning_snapshots_on_the_clock_and_never_resets() {
        let text = "[snapshots]\nevery_env_steps = 50_000\nwin_rate = 0.55\ntimeout_env_steps = 90_000\n\
                    [exploiters]\ncaptors = true\ntarget = true\nwin_rate = 0.7\ntimeout_env_steps = 120_000\n";
        let resetting = LeagueConfig::parse(text).unwrap();
        let keeping = LeagueConfig::parse(&format!("{text}target_resets = false\n")).unwrap();
        let (captors_x, target_x) = (
            Seat::exploiter(Side::Captors),
            Seat::exploiter(Side::Target),
        );
        // Which seats reset, in each league.
        for (cfg, target_resets) in [(&resetting, true), (&keeping, false)] {
            let r = |seat| SeatRules::of(cfg, seat).resets_after_snapshot;
            assert!(!r(Seat::main(Side::Captors)) && !r(Seat::main(Side::Target)));
            assert!(r(captors_x));
            assert_eq!(r(target_x), target_resets);
        }
        // The resetting exploiter: its own win rate and timeout.
        let rule = SeatRules::of(&resetting, target_x).snapshot;
        assert!(!should_snapshot(50_000, 13, 20, rule), "65% is under 70%");
        assert!(should_snapshot(50_000, 14, 20, rule));
        assert!(!should_snapshot(119_999, 0, 20, rule));
        // The one that keeps learning: every 50 k env steps, losing or not.
        let rule = SeatRules::of(&keeping, target_x).snapshot;
        assert!(!should_snapshot(49_999, 20, 20, rule));
        assert!(should_snapshot(50_000, 0, 20, rule));
        assert!(should_snapshot(50_000, 0, 0, rule));
        // Nothing else moves: the captor exploiter and the main learners.
        for seat in [
            captors_x,
            Seat::main(Side::Captors),
            Seat::main(Side::Target),
        ] {
            assert_eq!(
                SeatRules::of(&keeping, seat).snapshot,
                SeatRules::of(&resetting, seat).snapshot
            );
        }
        assert_eq!(
            SeatRules::of(&keeping, captors_x)
                .snapshot
                .timeout_env_steps,
            120_000
        );
        // Left out, the stored config does not name it (its hash is unchanged);
        // without a target exploiter it is refused, named.
        assert!(!toml::to_string(&resetting)
            .unwrap()
            .contains("target_resets"));
        let err = LeagueConfig::parse("[exploiters]\ntarget_resets = false\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("exploiters.target_resets") && err.contains("no target exploiter"),
            "{err}"
        );
    }

    #[test]
    fn a_learner_waits_only_for_a_live_learner_it_is_far_ahead_of() {
        assert!(
            !should_wait(50_000, Some((BeatState::Training, 0, 10)), 0),
            "0: never"
        );
        assert!(should_wait(
            30_001,
            Some((BeatState::Training, 10_000, 1_000)),
            20_000
        ));
        assert!(
            !should_wait(30_000, Some((BeatState::Training, 10_000, 1_000)), 20_000),
            "exactly the lead"
        );
        assert!(should_wait(
            30_001,
            Some((BeatState::Waiting, 10_000, 1_000)),
            20_000
        ));
        assert!(
            !should_wait(90_000, Some((BeatState::Done, 10_000, 1_000)), 20_000),
            "done: nothing to wait for"
        );
        assert!(!should_wait(
            90_000,
            Some((BeatState::Stopped, 10_000, 1_000)),
            20_000
        ));
        assert!(
            !should_wait(90_000, Some((BeatState::Training, 10_000, 130_000)), 20_000),
            "silent: crashed"
        );
        assert!(should_wait(20_001, None, 20_000), "not started yet");
        assert!(!should_wait(5_000, None, 20_000));
    }
}
