//! What `t2e-league status` and `export` read from a league, safe while it
//! runs (the store is read in short queries under WAL). The report's rows
//! and its JSON shape are in report.rs.

use crate::error::Result;
use crate::rules::config::LeagueConfig;
use crate::rules::players::EVALUATOR;
use crate::rules::ratings::{bradley_terry, PairRecord};
use crate::run::folder::layout::LeagueDir;
use crate::store::{
    host_name, now_ms, ExploitRecord, Heartbeat, HeldOutResult, Kind, PairResult, Panel, Player,
    Store,
};
use t2e_core::env::Side;

mod export;
mod plot;
mod report;

pub use export::{best_player, best_validated, export, BestValidated};
pub use plot::{panel_curves, plot, rating_lines, PanelCurve, RatingLine};
pub use report::{
    frozen_label, CrashRow, Curriculum, ExploitRow, LearnerRow, PanelRow, PayoffRow, PlayerRow,
    SeatStatus, StageRow, StatusReport,
};

fn exploit_rows(players: &[Player], records: Vec<ExploitRecord>) -> Vec<ExploitRow> {
    records
        .into_iter()
        .map(|r| {
            let p = players.iter().find(|p| p.id == r.player);
            let (lo, hi) =
                t2e_learners::eval::wilson_interval(r.wins as usize, r.episodes as usize);
            let now_sha = p.and_then(|p| p.checkpoint.as_ref().map(|(_, s)| s.as_str()));
            let outdated = r.player_sha256.is_some() && r.player_sha256.as_deref() != now_sha;
            // Weights that are still the player's are the player's env steps.
            let player_env_steps = r.player_env_steps.or_else(|| {
                p.filter(|_| !outdated && r.player_sha256.is_some())
                    .map(|p| p.env_steps)
            });
            ExploitRow {
                player_sha256: r.player_sha256.clone(),
                player_env_steps,
                outdated,
                player: r.player,
                player_name: p
                    .map(|p| p.name.clone())
                    .unwrap_or_else(|| r.player.to_string()),
                side: p.map(|p| p.side.name().to_string()).unwrap_or_default(),
                best_response: r.best_response,
                budget: r.budget,
                env_steps: r.env_steps,
                train_s: r.train_ms as f64 / 1000.0,
                seed: r.seed,
                maps: r.maps,
                speed_ratio: r.speed_ratio,
                episodes: r.episodes,
                best_response_wins: r.wins,
                win_rate: r.wins as f64 / r.episodes.max(1) as f64,
                win_rate_low: lo,
                win_rate_high: hi,
            }
        })
        .collect()
}

/// The panel rows from the evaluator's payoff and its held-out episodes:
/// the member is the snapshot or learner, the opponent the panel member or
/// held-out controller it played, newest members first, held-out
/// opponents after the league's own.
pub fn panel_rows(
    players: &[Player],
    evaluator_payoff: &[PairResult],
    held_out: &[HeldOutResult],
) -> Vec<PanelRow> {
    let find = |id: i64| players.iter().find(|p| p.id == id);
    let mut rows: Vec<PanelRow> = evaluator_payoff
        .iter()
        .filter_map(|r| {
            let (captor, target) = (find(r.captor)?, find(r.target)?);
            // The panel is made of the heuristics: the other party is the member.
            let (member, opponent, wins) =
                if captor.kind == Kind::Heuristic && target.kind != Kind::Heuristic {
                    (target, captor, r.games - r.captor_wins)
                } else {
                    (captor, target, r.captor_wins)
                };
            let (lo, hi) = t2e_learners::eval::wilson_interval(wins as usize, r.games as usize);
            Some(PanelRow {
                member: member.id,
                member_name: member.name.clone(),
                opponent: opponent.id,
                opponent_name: opponent.name.clone(),
                episodes: r.games,
                member_wins: wins,
                win_rate: wins as f64 / r.games.max(1) as f64,
                win_rate_low: lo,
                win_rate_high: hi,
                held_out: false,
                validation: false,
                mean_steps: None,
            })
        })
        .collect();
    rows.extend(held_out.iter().filter_map(|r| {
        let member = find(r.member)?;
        let wins = match member.side {
            Side::Captors => r.captures,
            Side::Target => r.episodes - r.captures,
        };
        let (lo, hi) = t2e_learners::eval::wilson_interval(wins as usize, r.episodes as usize);
        Some(PanelRow {
            member: member.id,
            member_name: member.name.clone(),
            opponent: 0,
            opponent_name: r.opponent.clone(),
            episodes: r.episodes,
            member_wins: wins,
            win_rate: wins as f64 / r.episodes.max(1) as f64,
            win_rate_low: lo,
            win_rate_high: hi,
            held_out: true,
            validation: r.panel == Panel::Validation,
            mean_steps: Some(r.steps as f64 / r.episodes.max(1) as f64),
        })
    }));
    rows.sort_by(|a, b| {
        (
            std::cmp::Reverse(a.member),
            a.held_out,
            a.validation,
            a.opponent,
            &a.opponent_name,
        )
            .cmp(&(
                std::cmp::Reverse(b.member),
                b.held_out,
                b.validation,
                b.opponent,
                &b.opponent_name,
            ))
    });
    rows
}

/// Opens a league directory for reading only (see `open::open_read_only`).
pub fn open(dir: &LeagueDir) -> Result<(LeagueConfig, Store)> {
    crate::run::folder::open::open_read_only(dir)
}

/// Seconds without a heartbeat after which a process on another machine
/// (whose pid cannot be checked from here) is taken for dead. Learners beat
/// once per iteration and every half second while they wait.
pub const STALE_HEARTBEAT_S: f64 = 600.0;

/// Whether a process of this league still runs, as far as this machine can
/// tell: a pid on this host must exist and be a t2e-league process; a
/// heartbeat from elsewhere must be recent.
pub fn alive(beat: &Heartbeat, age_s: f64) -> bool {
    match &beat.host {
        Some(h) if *h == host_name() => pid_is_league_process(beat.pid),
        _ => age_s < STALE_HEARTBEAT_S,
    }
}

fn pid_is_league_process(pid: i64) -> bool {
    if pid <= 0 {
        return false;
    }
    match std::fs::read(format!("/proc/{pid}/cmdline")) {
        Ok(cmd) => crate::run::processes::child::ChildCommand::is_league_process(&cmd),
        Err(_) => false,
    }
}

/// The state `status` shows: a process that says it is working but is gone
/// is `dead`.
pub fn shown_state(beat: &Heartbeat, age_s: f64) -> String {
    if beat.state.is_working() && !alive(beat, age_s) {
        "dead".into()
    } else {
        beat.state.name().into()
    }
}

/// Everything `status` shows, read from the league's store in one pass.
pub fn report(dir: &LeagueDir) -> Result<StatusReport> {
    let (cfg, store) = open(dir)?;
    let players = store.players_flagged()?;
    let ratings = store.ratings()?;
    let payoff = store.payoff()?;
    let rows = player_rows(&players, &ratings, &payoff);
    let history = stage_rows(store.curriculum_history()?);
    let stage = history.last().map(|h| h.stage).unwrap_or(0);
    let now = now_ms();
    let seats = store.seats()?;
    // Leases are judged by the store's clock, as the workers write them.
    let store_now = if seats.is_empty() {
        now
    } else {
        store.clock_ms().unwrap_or(now)
    };
    let panel_episodes = store.matches_recorded_by(EVALUATOR)? + store.held_out_count()?;
    let panel = panel_rows(
        &players,
        &store.payoff_recorded_by(EVALUATOR)?,
        &store.held_out_results()?,
    );
    let exploits = exploit_rows(&players, store.exploits()?);
    let matches = store.match_count()?;
    let clock = Clock { now, store_now };
    let learners = learner_rows(store.heartbeats()?, &seats, clock, panel_episodes);
    let crashes = store.crashes()?.into_iter().map(crash_row).collect();
    Ok(StatusReport {
        panel,
        exploits,
        league: cfg.name.clone(),
        dir: dir.root.display().to_string(),
        matches,
        players: rows,
        curriculum: Curriculum {
            stage,
            speed_ratio: cfg.curriculum.stages[stage.min(cfg.curriculum.stages.len() - 1)],
            history,
        },
        learners,
        payoff: payoff
            .iter()
            .map(|r| PayoffRow {
                captor: r.captor,
                target: r.target,
                captor_wins: r.captor_wins,
                games: r.games,
            })
            .collect(),
        crashes,
        seats: seats.into_iter().map(|s| seat_row(s, store_now)).collect(),
    })
}

/// Every player's row: its record, live rating and Bradley-Terry Elo (the
/// fit over the whole payoff, so it is computed once for all rows).
fn player_rows(
    players: &[Player],
    ratings: &std::collections::HashMap<i64, crate::rules::ratings::Rating>,
    payoff: &[PairResult],
) -> Vec<PlayerRow> {
    let index = |id: i64| players.iter().position(|p| p.id == id);
    let pairs: Vec<PairRecord> = payoff
        .iter()
        .filter_map(|r| {
            Some(PairRecord {
                a: index(r.captor)?,
                b: index(r.target)?,
                wins: r.captor_wins as f64,
                games: r.games as f64,
            })
        })
        .collect();
    let bt = bradley_terry(players.len(), &pairs);
    players
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let rec = crate::rules::payoff::record(payoff, p.id, p.side, None);
            let rating = ratings.get(&p.id).copied().unwrap_or_default();
            PlayerRow {
                id: p.id,
                name: p.name.clone(),
                side: p.side,
                kind: p.kind,
                parent: p.parent,
                env_steps: p.env_steps,
                curriculum_stage: p.curriculum_stage,
                rating: rating.mu,
                rating_sigma: rating.sigma,
                bt_elo: bt[i],
                games: rec.games,
                wins: rec.wins,
                win_rate: rec.win_rate(),
                quarantined: p.quarantined.clone(),
            }
        })
        .collect()
}

/// The curriculum's stage changes as `status` lists them.
fn stage_rows(history: Vec<crate::store::StageChange>) -> Vec<StageRow> {
    history
        .into_iter()
        .map(|c| StageRow {
            stage: c.stage,
            speed_ratio: c.speed_ratio,
            reason: c.reason,
            at_ms: c.at_ms,
        })
        .collect()
}

/// This machine's clock and the store's, both in ms: heartbeats age by the
/// first, seat leases by the second.
#[derive(Clone, Copy)]
struct Clock {
    now: i64,
    store_now: i64,
}

/// Every process's row from its heartbeat: its state judged alive or dead
/// (by its pid, its heartbeat's age, and on workers its seat's lease).
fn learner_rows(
    beats: Vec<Heartbeat>,
    seats: &[crate::store::SeatRow],
    clock: Clock,
    panel_episodes: u64,
) -> Vec<LearnerRow> {
    beats
        .into_iter()
        .map(|b| {
            let age = (clock.now - b.at_ms) as f64 / 1000.0;
            // The evaluator beats after each pass; the store counts
            // every panel episode the moment it is recorded.
            let env_steps = if b.learner == EVALUATOR {
                panel_episodes
            } else {
                b.env_steps
            };
            // On workers, a process runs only while its worker holds the
            // seat's lease: without one (a worker killed, a seat row
            // deleted) its last heartbeat's "training" is history.
            let seated = seats.is_empty()
                || seats
                    .iter()
                    .any(|s| s.name == b.learner && s.held_at(clock.store_now));
            let state = if b.state.is_working() && !seated {
                "dead".to_string()
            } else {
                shown_state(&b, age)
            };
            LearnerRow {
                state,
                name: b.learner,
                pid: b.pid,
                host: b.host,
                env_steps,
                steps_per_s: b.steps_per_s,
                heartbeat_age_s: age,
            }
        })
        .collect()
}

/// A recorded crash as `status` lists it.
fn crash_row(c: crate::store::Crash) -> CrashRow {
    CrashRow {
        learner: c.learner,
        exit_status: c.exit_status,
        message: c.message,
        at_ms: c.at_ms,
    }
}

/// A seat as `status` lists it: its host and lease only while it is held.
fn seat_row(s: crate::store::SeatRow, store_now: i64) -> SeatStatus {
    SeatStatus {
        state: s.state.name().into(),
        host: s.held_at(store_now).then(|| s.host.clone()).flatten(),
        lease_left_s: s
            .held_at(store_now)
            .then(|| (s.lease_until_ms - store_now) as f64 / 1000.0),
        claims: s.claims,
        reason: s.reason,
        name: s.name,
    }
}

#[cfg(test)]
mod tests {
    use super::plot::short_steps;
    use super::*;

    #[test]
    fn two_exploits_of_one_player_name_their_weights_and_the_older_is_marked() {
        let learner = Player {
            id: 1,
            name: "captors-main".into(),
            side: Side::Captors,
            kind: Kind::Learner,
            parent: None,
            created_at_ms: 0,
            env_steps: 9_600,
            curriculum_stage: 0,
            checkpoint: Some(("learners/captors-main/checkpoints/x".into(), "b".repeat(64))),
            quarantined: None,
        };
        let record = |key: &str, sha: char| ExploitRecord {
            exploit_key: key.into(),
            player: 1,
            player_sha256: Some(sha.to_string().repeat(64)),
            player_env_steps: None,
            best_response: "target ippo".into(),
            budget: "2000 env steps".into(),
            env_steps: 2_000,
            train_ms: 1_000,
            seed: 0,
            maps: "small".into(),
            num_captors: 2,
            speed_ratio: 1.0,
            episodes: 10,
            episode_length: 40,
            wins: 3,
        };
        let rows = exploit_rows(
            std::slice::from_ref(&learner),
            vec![record("k1", 'a'), record("k2", 'b')],
        );
        assert_eq!(
            rows[0].player_sha256.as_deref(),
            Some("a".repeat(64).as_str())
        );
        assert!(
            rows[0].outdated,
            "made against weights the player no longer has"
        );
        assert_eq!(rows[0].player_env_steps, None, "not recorded, not guessed");
        assert!(!rows[1].outdated);
        assert_eq!(
            rows[1].player_env_steps,
            Some(9_600),
            "the current weights'"
        );
        let json = serde_json::to_value(&rows[0]).unwrap();
        assert_eq!(json["outdated"], true);
        assert!(json["player_sha256"].is_string() && json.get("player_env_steps").is_some());
        let text: Vec<String> = rows.iter().map(frozen_label).collect();
        assert_eq!(text, ["aaaaaaaaaaaa @?", "bbbbbbbbbbbb @9600"]);
    }

    fn player(id: i64, name: &str, kind: &str, parent: Option<i64>, env_steps: u64) -> PlayerRow {
        PlayerRow {
            id,
            name: name.into(),
            side: if name.starts_with("captors") || name.starts_with("expert") {
                Side::Captors
            } else {
                Side::Target
            },
            kind: Kind::try_from(kind.to_string()).unwrap(),
            parent,
            env_steps,
            curriculum_stage: 0,
            rating: 25.0,
            rating_sigma: 8.0,
            bt_elo: 0.0,
            games: 1,
            wins: 0,
            win_rate: None,
            quarantined: None,
        }
    }

    #[test]
    fn panel_curves_follow_each_learner_and_opponent_over_env_steps() {
        let players = vec![
            player(1, "expert-captors", "heuristic", None, 0),
            player(2, "rule-based-target", "heuristic", None, 0),
            player(3, "captors-main", "learner", None, 900_000),
            player(4, "target-main", "learner", None, 900_000),
            player(5, "target-snap-400", "snapshot", Some(4), 400_000),
            player(6, "captors-snap-200", "snapshot", Some(3), 200_000),
            player(7, "captors-snap-600", "snapshot", Some(3), 600_000),
        ];
        let row = |member: i64, opponent: &str, held_out: bool, win_rate: f64| PanelRow {
            member,
            member_name: String::new(),
            opponent: if held_out { 0 } else { 2 },
            opponent_name: opponent.into(),
            episodes: 20,
            member_wins: (20.0 * win_rate) as u64,
            win_rate,
            win_rate_low: 0.0,
            win_rate_high: 1.0,
            held_out,
            validation: false,
            mean_steps: None,
        };
        // Newest first, as panel_rows gives them; an unknown member is skipped.
        let panel = vec![
            row(7, "rule-based-target", false, 0.5),
            row(6, "rule-based-target", false, 0.25),
            row(5, "greedy:2", true, 0.125),
            row(5, "expert-captors", false, 0.75),
            row(99, "rule-based-target", false, 1.0),
        ];
        let curves = panel_curves(&players, &panel);
        assert_eq!(
            curves,
            vec![
                PanelCurve {
                    label: "captors-main vs rule-based-target".into(),
                    points: vec![(200_000.0, 25.0), (600_000.0, 50.0)],
                },
                PanelCurve {
                    label: "target-main vs expert-captors".into(),
                    points: vec![(400_000.0, 75.0)],
                },
                PanelCurve {
                    label: "target-main vs greedy:2 (held out)".into(),
                    points: vec![(400_000.0, 12.5)],
                },
            ]
        );
        assert!(panel_curves(&players, &[]).is_empty());
    }

    #[test]
    fn every_rating_line_is_labelled_and_snapshots_follow_their_learner() {
        let players = vec![
            player(1, "expert-captors", "heuristic", None, 0),
            player(2, "rule-based-target", "heuristic", None, 0),
            player(3, "captors-main", "learner", None, 240_000),
            player(4, "target-main", "learner", None, 240_000),
            player(5, "captors-main-snap-160000", "snapshot", Some(3), 160_000),
            player(6, "captors-main-snap-80000", "snapshot", Some(3), 80_000),
            player(7, "target-main-snap-80000", "snapshot", Some(4), 80_000),
            player(8, "captors-main-snap-240000", "snapshot", Some(3), 240_000),
        ];
        let mut drawn = vec![true; players.len()];
        drawn[1] = false; // no rating points yet: no line
        let lines = rating_lines(&players, &drawn);
        let labels: Vec<&str> = lines.iter().map(|l| l.label.as_str()).collect();
        assert_eq!(
            labels,
            [
                "expert-captors",
                "captors-main",
                "captors-main @80k",
                "captors-main @160k",
                "captors-main @240k",
                "target-main",
                "target-main @80k",
            ]
        );
        let group_of = |name: &str| lines.iter().find(|l| l.label == name).unwrap().group;
        assert_eq!(group_of("captors-main @80k"), group_of("captors-main"));
        assert_eq!(group_of("target-main @80k"), group_of("target-main"));
        assert_ne!(group_of("captors-main"), group_of("target-main"));
        assert_ne!(group_of("captors-main"), group_of("expert-captors"));
        // The learner in full colour, its oldest snapshot lightest.
        let light = |name: &str| lines.iter().find(|l| l.label == name).unwrap().lightness;
        assert_eq!(light("captors-main"), 0.0);
        assert!(light("captors-main @80k") > light("captors-main @160k"));
        assert!(light("captors-main @160k") > light("captors-main @240k"));
        assert!(light("captors-main @240k") > 0.0);
    }

    #[test]
    fn a_crowded_legend_folds_each_learners_snapshots_into_one_entry() {
        let mut players = vec![player(1, "captors-main", "learner", None, 0)];
        for k in 0..20u64 {
            players.push(player(
                2 + k as i64,
                &format!("captors-main-snap-{}", (k + 1) * 80_000),
                "snapshot",
                Some(1),
                (k + 1) * 80_000,
            ));
        }
        let lines = rating_lines(&players, &vec![true; players.len()]);
        assert_eq!(lines.len(), 21, "every player still gets its line");
        let labelled: Vec<&str> = lines
            .iter()
            .map(|l| l.label.as_str())
            .filter(|l| !l.is_empty())
            .collect();
        assert_eq!(labelled, ["captors-main", "captors-main snapshots (20)"]);
        assert!(lines.iter().all(|l| l.group == 0));
    }

    #[test]
    fn panel_rows_credit_the_member_whichever_side_it_plays() {
        use crate::store::Player;
        let member = |id: i64, name: &str, side: Side, kind: Kind| Player {
            id,
            name: name.into(),
            side,
            kind,
            parent: None,
            created_at_ms: 0,
            checkpoint: None,
            env_steps: 0,
            curriculum_stage: 0,
            quarantined: None,
        };
        let players = vec![
            member(1, "expert-captors", Side::Captors, Kind::Heuristic),
            member(2, "rule-based-target", Side::Target, Kind::Heuristic),
            member(3, "captors-main-snap-80000", Side::Captors, Kind::Snapshot),
            member(4, "target-main-snap-80000", Side::Target, Kind::Snapshot),
        ];
        let payoff = vec![
            // The captors' snapshot caught the rule-based target 5 of 20 times.
            PairResult {
                captor: 3,
                target: 2,
                captor_wins: 5,
                games: 20,
            },
            // The expert captors caught the target's snapshot 15 of 20 times.
            PairResult {
                captor: 1,
                target: 4,
                captor_wins: 15,
                games: 20,
            },
        ];
        let held_out = vec![
            // greedy:2 captors (held out) caught the target's snapshot 3 of 4 times.
            HeldOutResult {
                member: 4,
                panel: Panel::HeldOut,
                opponent: "greedy:2".into(),
                captures: 3,
                episodes: 4,
                steps: 400,
            },
            // The captors' snapshot caught a still target 4 of 4 times.
            HeldOutResult {
                member: 3,
                panel: Panel::HeldOut,
                opponent: "still".into(),
                captures: 4,
                episodes: 4,
                steps: 200,
            },
        ];
        let all = panel_rows(&players, &payoff, &held_out);
        assert_eq!(all.len(), 4);
        let shown: Vec<_> = all
            .iter()
            .map(|r| {
                (
                    r.member,
                    r.opponent_name.as_str(),
                    r.held_out,
                    r.member_wins,
                )
            })
            .collect();
        assert_eq!(
            shown,
            vec![
                (4, "expert-captors", false, 5),
                (4, "greedy:2", true, 1),
                (3, "rule-based-target", false, 5),
                (3, "still", true, 4),
            ]
        );
        assert_eq!(all[1].opponent, 0);
        let rows = panel_rows(&players, &payoff, &[]);
        assert_eq!(rows.len(), 2);
        let target = &rows[0];
        assert_eq!((target.member, target.opponent), (4, 1));
        assert_eq!((target.member_wins, target.episodes), (5, 20));
        let captors = &rows[1];
        assert_eq!((captors.member, captors.opponent), (3, 2));
        assert_eq!(captors.member_wins, 5);
        assert!((captors.win_rate - 0.25).abs() < 1e-12);
        // Wilson 95% for 5 of 20: [0.112, 0.469].
        assert!(
            (captors.win_rate_low - 0.1119).abs() < 1e-3,
            "{}",
            captors.win_rate_low
        );
        assert!(
            (captors.win_rate_high - 0.4687).abs() < 1e-3,
            "{}",
            captors.win_rate_high
        );
    }

    #[test]
    fn steps_are_shortened_for_labels() {
        assert_eq!(short_steps(999), "999");
        assert_eq!(short_steps(240_000), "240k");
        assert_eq!(short_steps(1_500_000), "1.5M");
        assert_eq!(short_steps(2_000_000), "2M");
        assert_eq!(short_steps(1_234_567), "1.23M");
    }
}
