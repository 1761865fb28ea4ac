//! Which snapshot to export: the main learner's snapshot whose worst
//! result over the validation panel (`[evaluator] validation_*`, on the
//! validation maps) is best. The league keeps every snapshot; the last one is not always the
//! best for teams it never met (a target can drift towards beating only the
//! captors it trains against), and the test panel must not choose, or its
//! figures would be tuned to it. The worst case, not the mean, because a
//! target that departs from the rule-based one can escape one team more
//! and be caught by another far more (the single-model lookahead target:
//! never caught by its model, caught 86% by the ASZ planner); a mean over
//! the panel would trade the second for the first. Pure: the store's rows
//! in, a choice out.

use crate::data::{HeldOutResult, Kind, Panel, Player};
use crate::rules::players::learner_name;
use t2e_core::env::Side;

/// One snapshot's validation result: its lowest win rate over the
/// validation teams, and the means over them of the win rate and of the
/// episodes' length.
#[derive(Clone, Debug, PartialEq)]
pub struct Validated {
    pub player: Player,
    /// The snapshot's win rate against the validation team it did worst
    /// against.
    pub worst_win_rate: f64,
    /// That team.
    pub worst_opponent: String,
    /// Mean over the validation opponents of the snapshot's win rate
    /// (escapes for a target, captures for captors).
    pub win_rate: f64,
    /// Mean over the validation opponents of the mean episode length.
    pub mean_steps: f64,
    pub episodes: u64,
}

/// Why no snapshot can be chosen.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NoChoice {
    #[error("the league has no validation panel for its {side}: its [evaluator] {field} is empty (set it, with validation_maps, in the league's config)")]
    NoPanel {
        side: &'static str,
        field: &'static str,
    },
    #[error("none of {learner}'s {snapshots} snapshots has finished its validation games yet ({episodes} episodes against each of {opponents}); wait for the evaluator, or export a player by name")]
    NoneComplete {
        learner: String,
        snapshots: usize,
        episodes: u64,
        opponents: String,
    },
}

/// The main learner of `side`'s snapshots that have played every
/// validation opponent `episodes` times, best first: highest worst-case
/// win rate; at an equal worst case, the higher mean win rate; then the
/// episodes' length in the snapshot's favour (a target
/// that lasts longer, captors that capture sooner); then the later
/// snapshot. A snapshot whose validation is unfinished (the evaluator was
/// stopped or killed mid-way) is not ranked, so a half result never
/// chooses.
// Long on purpose: the export rule read as one piece, which the hand-computed tests pin: keep the finished, score them, order by score and its tie-breaks.
pub fn rank_validated(
    players: &[Player],
    results: &[HeldOutResult],
    side: Side,
    opponents: &[String],
    episodes: u64,
) -> Result<Vec<Validated>, NoChoice> {
    if opponents.is_empty() {
        return Err(NoChoice::NoPanel {
            side: side.name(),
            field: match side {
                Side::Captors => "validation_targets",
                Side::Target => "validation_captors",
            },
        });
    }
    let learner = learner_name(side);
    let Some(main) = players.iter().find(|p| p.name == learner) else {
        return Err(NoChoice::NoneComplete {
            learner,
            snapshots: 0,
            episodes,
            opponents: opponents.join(", "),
        });
    };
    let snapshots: Vec<&Player> = players
        .iter()
        .filter(|p| {
            p.kind == Kind::Snapshot
                && p.side == side
                && p.parent == Some(main.id)
                && p.quarantined.is_none()
        })
        .collect();
    let mut ranked: Vec<Validated> = snapshots
        .iter()
        .filter_map(|p| {
            let rows: Vec<&HeldOutResult> = opponents
                .iter()
                .map(|o| {
                    results.iter().find(|r| {
                        r.member == p.id && r.panel == Panel::Validation && &r.opponent == o
                    })
                })
                .collect::<Option<_>>()?;
            if rows.iter().any(|r| r.episodes < episodes) {
                return None;
            }
            let n = rows.len() as f64;
            let rates: Vec<f64> = rows
                .iter()
                .map(|r| {
                    let wins = match side {
                        Side::Captors => r.captures,
                        Side::Target => r.episodes - r.captures,
                    };
                    wins as f64 / r.episodes as f64
                })
                .collect();
            let win_rate = rates.iter().sum::<f64>() / n;
            // The first of equal worst results, in the panel's order.
            let (worst, worst_win_rate) =
                rates
                    .iter()
                    .copied()
                    .enumerate()
                    .fold(
                        (0, f64::INFINITY),
                        |best, (i, r)| if r < best.1 { (i, r) } else { best },
                    );
            let mean_steps = rows
                .iter()
                .map(|r| r.steps as f64 / r.episodes as f64)
                .sum::<f64>()
                / n;
            Some(Validated {
                player: (*p).clone(),
                worst_win_rate,
                worst_opponent: rows[worst].opponent.clone(),
                win_rate,
                mean_steps,
                episodes: rows.iter().map(|r| r.episodes).sum(),
            })
        })
        .collect();
    if ranked.is_empty() {
        return Err(NoChoice::NoneComplete {
            learner,
            snapshots: snapshots.len(),
            episodes,
            opponents: opponents.join(", "),
        });
    }
    // A target wants long episodes, captors short ones.
    let steps_sign = match side {
        Side::Target => 1.0,
        Side::Captors => -1.0,
    };
    ranked.sort_by(|a, b| {
        b.worst_win_rate
            .total_cmp(&a.worst_win_rate)
            .then(b.win_rate.total_cmp(&a.win_rate))
            .then((steps_sign * b.mean_steps).total_cmp(&(steps_sign * a.mean_steps)))
            .then(b.player.env_steps.cmp(&a.player.env_steps))
    });
    Ok(ranked)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::test_player as player;

    fn result(
        member: i64,
        panel: Panel,
        opponent: &str,
        captures: u64,
        episodes: u64,
        steps: u64,
    ) -> HeldOutResult {
        HeldOutResult {
            member,
            panel,
            opponent: opponent.into(),
            captures,
            episodes,
            steps,
        }
    }

    fn league() -> Vec<Player> {
        vec![
            player(1, "expert-captors", Side::Captors, Kind::Heuristic, None, 0),
            player(
                2,
                "rule-based-target",
                Side::Target,
                Kind::Heuristic,
                None,
                0,
            ),
            player(3, "captors-main", Side::Captors, Kind::Learner, None, 900),
            player(4, "target-main", Side::Target, Kind::Learner, None, 900),
            player(
                5,
                "target-main-200",
                Side::Target,
                Kind::Snapshot,
                Some(4),
                200,
            ),
            player(
                6,
                "target-main-400",
                Side::Target,
                Kind::Snapshot,
                Some(4),
                400,
            ),
            player(
                7,
                "target-main-600",
                Side::Target,
                Kind::Snapshot,
                Some(4),
                600,
            ),
            player(
                8,
                "target-exploiter",
                Side::Target,
                Kind::Learner,
                None,
                300,
            ),
            player(
                9,
                "target-exploiter-300",
                Side::Target,
                Kind::Snapshot,
                Some(8),
                300,
            ),
        ]
    }

    #[test]
    fn the_target_snapshot_caught_least_by_the_validation_teams_is_chosen() {
        let opponents = vec!["expert:1".to_string(), "expert:2".to_string()];
        let v = Panel::Validation;
        let results = vec![
            // 200: caught 8/10 and 6/10 -> escapes 0.2 and 0.4, mean 0.30.
            result(5, v, "expert:1", 8, 10, 1000),
            result(5, v, "expert:2", 6, 10, 2000),
            // 400: caught 5/10 and 5/10 -> mean escape 0.50: the best.
            result(6, v, "expert:1", 5, 10, 3000),
            result(6, v, "expert:2", 5, 10, 3000),
            // 600: caught 9/10 and 9/10 -> 0.10.
            result(7, v, "expert:1", 9, 10, 900),
            result(7, v, "expert:2", 9, 10, 900),
            // The exploiter's snapshot is better still, but not the main learner's.
            result(9, v, "expert:1", 0, 10, 5000),
            result(9, v, "expert:2", 0, 10, 5000),
            // The held-out panel never chooses: 600 escapes it always.
            result(7, Panel::HeldOut, "greedy:2", 0, 10, 5000),
        ];
        let ranked = rank_validated(&league(), &results, Side::Target, &opponents, 10).unwrap();
        let names: Vec<_> = ranked.iter().map(|r| r.player.name.as_str()).collect();
        assert_eq!(
            names,
            ["target-main-400", "target-main-200", "target-main-600"]
        );
        assert!((ranked[0].win_rate - 0.5).abs() < 1e-12);
        assert!((ranked[1].win_rate - 0.3).abs() < 1e-12);
        // Mean of 100 and 200 steps per episode.
        assert!((ranked[1].mean_steps - 150.0).abs() < 1e-12);
        assert_eq!(ranked[0].episodes, 20);
    }

    #[test]
    fn the_worst_team_decides_before_the_mean() {
        let opponents = vec!["expert:1".to_string(), "greedy:4".to_string()];
        let v = Panel::Validation;
        let results = vec![
            // 200: escapes 9/10 and 1/10 -> mean 0.50, worst 0.10 (greedy:4).
            result(5, v, "expert:1", 1, 10, 4000),
            result(5, v, "greedy:4", 9, 10, 1000),
            // 400: escapes 4/10 and 4/10 -> mean 0.40, worst 0.40: chosen.
            result(6, v, "expert:1", 6, 10, 3000),
            result(6, v, "greedy:4", 6, 10, 3000),
            // 600: escapes 3/10 and 8/10 -> mean 0.55, worst 0.30 (expert:1).
            result(7, v, "expert:1", 7, 10, 2000),
            result(7, v, "greedy:4", 2, 10, 4000),
        ];
        let ranked = rank_validated(&league(), &results, Side::Target, &opponents, 10).unwrap();
        let names: Vec<_> = ranked.iter().map(|r| r.player.name.as_str()).collect();
        assert_eq!(
            names,
            ["target-main-400", "target-main-600", "target-main-200"]
        );
        assert!((ranked[0].worst_win_rate - 0.4).abs() < 1e-12);
        assert!((ranked[1].worst_win_rate - 0.3).abs() < 1e-12);
        assert_eq!(ranked[1].worst_opponent, "expert:1");
        assert!((ranked[1].win_rate - 0.55).abs() < 1e-12);
        assert_eq!(ranked[2].worst_opponent, "greedy:4");
        // Equal worst cases: the higher mean first (400's worst raised to 0.30).
        let mut equal = results.clone();
        equal[2] = result(6, v, "expert:1", 7, 10, 3000);
        equal[3] = result(6, v, "greedy:4", 7, 10, 3000);
        let ranked = rank_validated(&league(), &equal, Side::Target, &opponents, 10).unwrap();
        assert_eq!(ranked[0].player.name, "target-main-600");
        assert_eq!(ranked[1].player.name, "target-main-400");
    }

    #[test]
    fn an_unfinished_validation_never_chooses() {
        let opponents = vec!["expert:1".to_string(), "expert:2".to_string()];
        let v = Panel::Validation;
        let results = vec![
            result(5, v, "expert:1", 8, 10, 1000),
            result(5, v, "expert:2", 8, 10, 1000),
            // 400 escaped every game so far, but played 3 of 10 against one
            // team and never met the other: killed mid-way.
            result(6, v, "expert:1", 0, 3, 1500),
            // 600 played only one of the two teams.
            result(7, v, "expert:1", 0, 10, 5000),
        ];
        let ranked = rank_validated(&league(), &results, Side::Target, &opponents, 10).unwrap();
        assert_eq!(ranked.len(), 1);
        assert_eq!(ranked[0].player.name, "target-main-200");
        let none = rank_validated(&league(), &results[2..], Side::Target, &opponents, 10);
        assert_eq!(
            none,
            Err(NoChoice::NoneComplete {
                learner: "target-main".into(),
                snapshots: 3,
                episodes: 10,
                opponents: "expert:1, expert:2".into()
            })
        );
        assert_eq!(
            rank_validated(&league(), &results, Side::Target, &[], 10),
            Err(NoChoice::NoPanel {
                side: "target",
                field: "validation_captors"
            })
        );
    }

    #[test]
    fn ties_go_to_the_longer_game_for_a_target_and_the_shorter_for_captors() {
        let mut players = league();
        players.push(player(
            10,
            "captors-main-100",
            Side::Captors,
            Kind::Snapshot,
            Some(3),
            100,
        ));
        players.push(player(
            11,
            "captors-main-200",
            Side::Captors,
            Kind::Snapshot,
            Some(3),
            200,
        ));
        let v = Panel::Validation;
        let opponents = vec!["random".to_string()];
        let results = vec![
            result(5, v, "random", 5, 10, 2000),
            result(6, v, "random", 5, 10, 3000),
            result(7, v, "random", 5, 10, 3000),
            result(10, v, "random", 5, 10, 2000),
            result(11, v, "random", 5, 10, 3000),
        ];
        let target = rank_validated(&players, &results, Side::Target, &opponents, 10).unwrap();
        // 400 and 600 tie on rate and length: the later one first.
        let names: Vec<_> = target.iter().map(|r| r.player.name.as_str()).collect();
        assert_eq!(
            names,
            ["target-main-600", "target-main-400", "target-main-200"]
        );
        let captors = rank_validated(&players, &results, Side::Captors, &opponents, 10).unwrap();
        assert_eq!(captors[0].player.name, "captors-main-100");
    }
}
