//! The league's evaluator, its own process (`t2e-league league-evaluator`,
//! spawned by the manager): every snapshot plays a fixed panel, the other
//! side's heuristic member and the held-out opponents the config names, for
//! a set number of greedy episodes at the first curriculum stage, so every
//! member has a row that compares with every other's whatever the
//! matchmaker chose for it. Held-out opponents are controllers, not
//! members: their episodes go to their own table (`store::held_out`), never
//! to the matches the ratings and the matchmaker read. Bounded to a share of one
//! core: after each episode it sleeps in proportion to the episode's time.

use crate::error::{LeagueError, Result, ResultExt};
use crate::rules::config::LeagueConfig;
use crate::rules::players::{heuristic_name, learner_name, Seat, EVALUATOR};
use crate::rules::supervision::Outcome;
use crate::run::evaluation::panels::{load_panels, Panels};
use crate::run::evaluation::preflight::check_maps_apart;
use crate::run::folder::layout::LeagueDir;
use crate::store::{BeatState, HeldOutEpisode, Kind, MatchRecord, Panel, Player, Store};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use t2e_core::env::{CaptureRule, Side};
use t2e_core::map::PreparedMap;
use t2e_learners::controllers::ControllerSpec;
use t2e_learners::eval::{play_episode, EvalSetting};

/// Who a snapshot plays on the panel.
enum PanelOpponent<'a> {
    /// The other side's heuristic member: a match, in the payoff.
    Member(&'a Player),
    /// A controller that is not a member (held out or validation): its
    /// episodes are kept apart from the matches.
    Controller(Panel, &'a str, &'a ControllerSpec),
}

/// The store key of a member's episode against a controller of a panel.
pub fn panel_episode_key(panel: Panel, member: &str, opponent: &str, episode: usize) -> String {
    format!("evaluator/{}/{member}/{opponent}/{episode}", panel.name())
}

/// Plays the panel games no one has recorded yet; returns how many it played.
fn evaluate_pending(
    dir: &LeagueDir,
    cfg: &LeagueConfig,
    panels: &Panels,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
    store: &Store,
    stop: &AtomicBool,
    done_before: u64,
) -> Result<usize> {
    let players = store.players()?;
    let pass = Pass {
        cfg,
        store,
        stop,
        done_before,
    };
    let mut played = 0;
    for (member, validates) in panel_queue(&players) {
        let opponents = panel_opponents(&players, member, validates, panels);
        let (rel, _) = member
            .checkpoint
            .as_ref()
            .ok_or_else(|| LeagueError::Pool("snapshot without a checkpoint".into()))?;
        let spec = ControllerSpec::Checkpoint(t2e_learners::controllers::CheckpointSpec::new(
            dir.root.join(rel),
        ));
        for opponent in &opponents {
            let other = match opponent {
                PanelOpponent::Member(_) => ControllerSpec::Heuristic,
                PanelOpponent::Controller(_, _, s) => (*s).clone(),
            };
            let (captors, target) = match member.side {
                Side::Captors => (spec.clone(), other),
                Side::Target => (other, spec.clone()),
            };
            // Validation plays its own maps and the evaluation's episode
            // length (the test's), so its Time compares with the test's.
            let (panel_maps, episode_length) = match opponent {
                PanelOpponent::Controller(Panel::Validation, ..) => (
                    &panels.validation_maps,
                    EvalSetting::default().episode_length,
                ),
                _ => (maps, cfg.episode_length),
            };
            let setting = EvalSetting {
                captors,
                target,
                num_captors: cfg.num_captors,
                speed_ratio: cfg.curriculum.stages[0],
                episodes: cfg.evaluator.episodes,
                episode_length,
                seed: cfg.seed ^ 0xE7A1,
                capture_rule: CaptureRule::Fast,
                soa_every: 0,
            };
            match pass.play(member, opponent, &setting, panel_maps, &mut played)? {
                Next::Opponent => {}
                Next::Member => break,
                Next::Stop => return Ok(played),
            }
        }
    }
    Ok(played)
}

/// Who `member` plays on the panel: the other side's heuristic member,
/// then the held-out teams and (for a main learner's snapshot, `validates`)
/// the validation teams of its side.
fn panel_opponents<'a>(
    players: &'a [Player],
    member: &Player,
    validates: bool,
    panels: &'a Panels,
) -> Vec<PanelOpponent<'a>> {
    let mut opponents: Vec<PanelOpponent> = players
        .iter()
        .filter(|p| p.name == heuristic_name(member.side.other()))
        .map(PanelOpponent::Member)
        .collect();
    for (panel, list) in [
        (Panel::HeldOut, &panels.held_out),
        (Panel::Validation, &panels.validation),
    ] {
        if panel == Panel::Validation && !validates {
            continue;
        }
        for (side, specs) in list {
            if *side == member.side {
                opponents.extend(
                    specs
                        .iter()
                        .map(|(n, s)| PanelOpponent::Controller(panel, n, s)),
                );
            }
        }
    }
    opponents
}

/// What one pass of the evaluator plays with: the league, its store, the
/// stop flag and the episodes counted before the pass (for heartbeats).
struct Pass<'a> {
    cfg: &'a LeagueConfig,
    store: &'a Store,
    stop: &'a AtomicBool,
    done_before: u64,
}

/// Where the pass goes after one opponent's episodes.
enum Next {
    /// On to the member's next opponent.
    Opponent,
    /// The member could not be played (quarantined): on to the next member.
    Member,
    /// Stopped: the pass ends.
    Stop,
}

impl Pass<'_> {
    /// Plays `member`'s unrecorded episodes against `opponent`, recording
    /// each at once (`played` counts them over the pass).
    fn play(
        &self,
        member: &Player,
        opponent: &PanelOpponent,
        setting: &EvalSetting,
        panel_maps: &Arc<Vec<Arc<PreparedMap>>>,
        played: &mut usize,
    ) -> Result<Next> {
        let (cfg, store) = (self.cfg, self.store);
        let mut asz_fields = t2e_core::asz::AszFields::new();
        for episode in 0..cfg.evaluator.episodes {
            if self.stop.load(Ordering::SeqCst) {
                return Ok(Next::Stop);
            }
            let recorded = match opponent {
                PanelOpponent::Member(panel) => store.has_match(&format!(
                    "evaluator/{}/{}/{episode}",
                    member.name, panel.name
                ))?,
                PanelOpponent::Controller(panel, name, _) => {
                    store.has_held_out(&panel_episode_key(*panel, &member.name, name, episode))?
                }
            };
            if recorded {
                continue;
            }
            let started = Instant::now();
            let record = match play_episode(setting, panel_maps, episode, &mut asz_fields) {
                Ok(r) => r,
                Err(e) => {
                    store.quarantine(member.id, &format!("evaluator could not play it: {e:#}"))?;
                    return Ok(Next::Member);
                }
            };
            self.record(member, opponent, setting, episode, record)?;
            *played += 1;
            // A heartbeat per episode: a backlog of snapshots can take
            // this loop longer than the silence after which `status`
            // calls a process on another host dead.
            store.heartbeat(
                EVALUATOR,
                BeatState::Evaluating,
                self.done_before + *played as u64,
                None,
            )?;
            let busy = started.elapsed().as_secs_f64();
            let idle = busy * (1.0 - cfg.evaluator.cpu_share) / cfg.evaluator.cpu_share;
            std::thread::sleep(Duration::from_secs_f64(idle.min(10.0)));
        }
        Ok(Next::Opponent)
    }

    /// Records one panel episode: a match against the heuristic member, a
    /// held-out episode against any other panel team.
    fn record(
        &self,
        member: &Player,
        opponent: &PanelOpponent,
        setting: &EvalSetting,
        episode: usize,
        record: t2e_learners::eval::EpisodeRecord,
    ) -> Result<()> {
        match opponent {
            PanelOpponent::Member(panel) => {
                let (captor_player, target_player) = match member.side {
                    Side::Captors => (member.id, panel.id),
                    Side::Target => (panel.id, member.id),
                };
                self.store.record_match(&MatchRecord {
                    key: format!("evaluator/{}/{}/{episode}", member.name, panel.name),
                    captor_player,
                    target_player,
                    map: record.map,
                    num_captors: self.cfg.num_captors,
                    speed_ratio: setting.speed_ratio,
                    seed: record.seed,
                    captured: record.captured,
                    steps: record.steps,
                    final_asz_m2: None,
                    recorded_by: EVALUATOR.into(),
                })?;
            }
            PanelOpponent::Controller(panel, name, _) => {
                self.store.record_held_out(&HeldOutEpisode {
                    key: panel_episode_key(*panel, &member.name, name, episode),
                    panel: *panel,
                    member: member.id,
                    opponent: name.to_string(),
                    map: record.map,
                    speed_ratio: setting.speed_ratio,
                    seed: record.seed,
                    captured: record.captured,
                    steps: record.steps,
                })?;
            }
        }
        Ok(())
    }
}

/// The snapshots the evaluator plays, in order, each with whether it plays
/// the validation panel. The main learners' snapshots come first: their
/// validation chooses what `export --best` exports, and should not wait
/// behind a backlog of exploiter snapshots (a target exploiter that never
/// resets adds one every `snapshots.every_env_steps`). Only they play the
/// validation panel, since nothing reads any other snapshot's validation;
/// every snapshot plays the heuristic member (its rating) and the held-out
/// panel.
pub fn panel_queue(players: &[Player]) -> Vec<(&Player, bool)> {
    let mains: Vec<i64> = [Side::Captors, Side::Target]
        .iter()
        .filter_map(|side| players.iter().find(|p| p.name == learner_name(*side)))
        .map(|p| p.id)
        .collect();
    let mut queue: Vec<(&Player, bool)> = players
        .iter()
        .filter(|p| p.kind == Kind::Snapshot && p.quarantined.is_none())
        .map(|p| (p, p.parent.is_some_and(|parent| mains.contains(&parent))))
        .collect();
    // Stable: each group keeps the store's order (oldest first).
    queue.sort_by_key(|(_, main_line)| !main_line);
    queue
}

/// The league's maps and its panels, a league whose validation maps are
/// training maps refused: errors here are `CannotStart`, since a restart
/// would load the same files.
fn load_maps_and_panels(
    dir: &LeagueDir,
    cfg: &LeagueConfig,
) -> Result<(Arc<Vec<Arc<PreparedMap>>>, Panels)> {
    let maps = t2e_core::map::catalog::load_prepared(&cfg.maps)
        .with_context(|| format!("maps = \"{}\"", cfg.maps))
        .map_err(LeagueError::cannot_start)?;
    let panels = load_panels(cfg)
        .and_then(|panels| {
            // A league stored before maps were compared by content is
            // refused here rather than validated on its training maps.
            check_maps_apart(
                "evaluator.validation_maps",
                cfg.evaluator.validation_maps.as_deref().unwrap_or(""),
                &panels.validation_maps,
                &cfg.maps,
                &maps,
            )?;
            Ok(panels)
        })
        .map_err(|e| {
            LeagueError::cannot_start(
                LeagueError::from(e).context(dir.config_path().display().to_string()),
            )
        })?;
    Ok((maps, panels))
}

/// Runs until Ctrl-C / SIGINT (`Outcome::Stopped`), or until both learners
/// are done and every snapshot has its panel games (`Outcome::Done`).
pub fn run_evaluator(dir: &LeagueDir, stop: &AtomicBool) -> Result<Outcome> {
    let opened = crate::run::folder::open::open_process(dir).map_err(LeagueError::cannot_start)?;
    let (cfg, store) = (opened.cfg, opened.store);
    if !cfg.evaluator.enabled {
        return Err(LeagueError::cannot_start(LeagueError::Refused(format!(
            "{}: this league has no evaluator ([evaluator] enabled = false)",
            dir.config_path().display()
        ))));
    }
    // Done when every learner of the league is: the main learners and any
    // exploiters, whose snapshots need their panel games as much.
    let mut learners: Vec<String> = [Side::Captors, Side::Target]
        .iter()
        .map(|s| learner_name(*s))
        .collect();
    for side in [Side::Captors, Side::Target] {
        if cfg.exploiters.enabled(side) {
            learners.push(Seat::exploiter(side).name());
        }
    }
    tch::set_num_threads(1);
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global();
    let (maps, panels) = load_maps_and_panels(dir, &cfg)?;
    // The count covers every evaluator process of this league, not only this one.
    let mut total = store.matches_recorded_by(EVALUATOR)? + store.held_out_count()?;
    store.heartbeat(EVALUATOR, BeatState::Evaluating, total, None)?;
    while !stop.load(Ordering::SeqCst) {
        let played = evaluate_pending(dir, &cfg, &panels, &maps, &store, stop, total)?;
        total += played as u64;
        if played == 0 {
            let beats = store.heartbeats()?;
            let done = learners.iter().all(|name| {
                beats
                    .iter()
                    .any(|b| b.learner == *name && b.state == BeatState::Done)
            });
            if done {
                // One more pass: a last snapshot may have landed since.
                if evaluate_pending(dir, &cfg, &panels, &maps, &store, stop, total)? == 0 {
                    break;
                }
                continue;
            }
            std::thread::sleep(Duration::from_secs(2));
        }
        store.heartbeat(EVALUATOR, BeatState::Evaluating, total, None)?;
    }
    let outcome = if stop.load(Ordering::SeqCst) {
        Outcome::Stopped
    } else {
        Outcome::Done
    };
    let state = match outcome {
        Outcome::Done => BeatState::Done,
        Outcome::Stopped => BeatState::Stopped,
    };
    store.heartbeat(EVALUATOR, state, total, None)?;
    tracing::info!("evaluator: {state}, {total} panel episodes played in this league");
    Ok(outcome)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::test_player as player;

    #[test]
    fn main_line_snapshots_come_first_and_alone_play_the_validation_panel() {
        use Side::*;
        let mut players = vec![
            player(1, "expert-captors", Captors, Kind::Heuristic, None, 0),
            player(2, "rule-based-target", Target, Kind::Heuristic, None, 0),
            player(3, "captors-main", Captors, Kind::Learner, None, 300),
            player(4, "target-main", Target, Kind::Learner, None, 300),
            player(5, "target-exploiter", Target, Kind::Exploiter, None, 300),
            player(
                6,
                "target-exploiter-snap-100",
                Target,
                Kind::Snapshot,
                Some(5),
                100,
            ),
            player(7, "captors-snap-100", Captors, Kind::Snapshot, Some(3), 100),
            player(8, "coop", Captors, Kind::Snapshot, None, 900),
            player(9, "target-snap-200", Target, Kind::Snapshot, Some(4), 200),
            player(
                10,
                "target-exploiter-snap-200",
                Target,
                Kind::Snapshot,
                Some(5),
                200,
            ),
            player(
                11,
                "captors-snap-200",
                Captors,
                Kind::Snapshot,
                Some(3),
                200,
            ),
        ];
        players[10].quarantined = Some("files gone".into());
        let queue: Vec<(i64, bool)> = panel_queue(&players)
            .into_iter()
            .map(|(p, validates)| (p.id, validates))
            .collect();
        // The main lines' snapshots, oldest first, with validation; then the
        // exploiter's and the permanent member's, without; never the
        // quarantined one, the learners or the heuristics.
        assert_eq!(
            queue,
            [(7, true), (9, true), (6, false), (8, false), (10, false)]
        );
    }
}
