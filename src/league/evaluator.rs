//! The league's evaluator, its own process (`t2e-league league-evaluator`,
//! spawned by the manager): every snapshot plays a fixed panel, the other
//! side's heuristic member, for a set number of greedy episodes at the first
//! curriculum stage, so every member has a row that compares with every
//! other's whatever the matchmaker chose for it. Bounded to a share of one
//! core: after each episode it sleeps in proportion to the episode's time.

use super::config::LeagueConfig;
use super::dir::LeagueDir;
use super::players::{heuristic_name, learner_name, Seat};
use super::store::{BeatState, Kind, MatchRecord, Store};
use super::supervision::{CannotStart, Outcome};
use crate::controllers::ControllerSpec;
use crate::env::{CaptureRule, Side};
use crate::eval::{play_episode, EvalSetting};
use crate::map::PreparedMap;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EvaluatorConfig {
    /// Run the evaluator process at all.
    pub enabled: bool,
    /// Episodes each snapshot plays against each panel member.
    pub episodes: usize,
    /// Share of one core the evaluator may use (it sleeps the rest).
    pub cpu_share: f64,
}

impl Default for EvaluatorConfig {
    fn default() -> Self {
        EvaluatorConfig {
            enabled: true,
            episodes: 20,
            cpu_share: 0.25,
        }
    }
}

impl EvaluatorConfig {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.cpu_share.is_finite() && self.cpu_share > 0.0 && self.cpu_share <= 1.0) {
            return Err(format!("cpu_share = {}: must be in (0, 1]", self.cpu_share));
        }
        if self.enabled && self.episodes == 0 {
            return Err(
                "episodes = 0: every snapshot must play at least one panel episode (or set enabled = false)"
                    .into(),
            );
        }
        if self.episodes > 100_000 {
            return Err(format!("episodes = {}: at most 100000", self.episodes));
        }
        Ok(())
    }
}

/// Plays the panel games no one has recorded yet; returns how many it played.
fn evaluate_pending(
    dir: &LeagueDir,
    cfg: &LeagueConfig,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
    store: &Store,
    stop: &AtomicBool,
) -> Result<usize> {
    let players = store.players()?;
    let mut played = 0;
    for member in players
        .iter()
        .filter(|p| p.kind == Kind::Snapshot && p.quarantined.is_none())
    {
        let Some(panel) = players
            .iter()
            .find(|p| p.name == heuristic_name(member.side.other()))
        else {
            continue;
        };
        let (rel, _) = member
            .checkpoint
            .as_ref()
            .context("snapshot without a checkpoint")?;
        let spec =
            ControllerSpec::Checkpoint(crate::controllers::CheckpointSpec::new(dir.root.join(rel)));
        let (captors, target) = match member.side {
            Side::Captors => (spec.clone(), ControllerSpec::Heuristic),
            Side::Target => (ControllerSpec::Heuristic, spec.clone()),
        };
        let setting = EvalSetting {
            captors,
            target,
            num_captors: cfg.num_captors,
            speed_ratio: cfg.curriculum.stages[0],
            episodes: cfg.evaluator.episodes,
            episode_length: cfg.episode_length,
            seed: cfg.seed ^ 0xE7A1,
            capture_rule: CaptureRule::Fast,
            soa_every: 0,
        };
        let mut marching = crate::asz::FastMarching::new();
        for episode in 0..cfg.evaluator.episodes {
            if stop.load(Ordering::SeqCst) {
                return Ok(played);
            }
            let key = format!("evaluator/{}/{}/{episode}", member.name, panel.name);
            if store.has_match(&key)? {
                continue;
            }
            let started = Instant::now();
            let record = match play_episode(&setting, maps, episode, &mut marching) {
                Ok(r) => r,
                Err(e) => {
                    store.quarantine(member.id, &format!("evaluator could not play it: {e:#}"))?;
                    break;
                }
            };
            let (captor_player, target_player) = match member.side {
                Side::Captors => (member.id, panel.id),
                Side::Target => (panel.id, member.id),
            };
            store.record_match(&MatchRecord {
                key,
                captor_player,
                target_player,
                map: record.map,
                num_captors: cfg.num_captors,
                speed_ratio: setting.speed_ratio,
                seed: record.seed,
                captured: record.captured,
                steps: record.steps,
                final_asz_m2: None,
                recorded_by: "evaluator".into(),
            })?;
            played += 1;
            let busy = started.elapsed().as_secs_f64();
            let idle = busy * (1.0 - cfg.evaluator.cpu_share) / cfg.evaluator.cpu_share;
            std::thread::sleep(Duration::from_secs_f64(idle.min(10.0)));
        }
    }
    Ok(played)
}

/// Runs until Ctrl-C / SIGINT (`Outcome::Stopped`), or until both learners
/// are done and every snapshot has its panel games (`Outcome::Done`).
pub fn run_evaluator(dir: &LeagueDir, stop: &AtomicBool) -> Result<Outcome> {
    let opened = super::open::open_process(dir)
        .map_err(|e| anyhow::Error::new(CannotStart(format!("{e:#}"))))?;
    let (cfg, store) = (opened.cfg, opened.store);
    if !cfg.evaluator.enabled {
        return Err(anyhow::Error::new(CannotStart(format!(
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
    let maps = crate::map::catalog::load_prepared(&cfg.maps)
        .with_context(|| format!("maps = \"{}\"", cfg.maps))
        .map_err(|e| anyhow::Error::new(CannotStart(format!("{e:#}"))))?;
    // The count covers every evaluator process of this league, not only this one.
    let mut total = store.matches_recorded_by("evaluator")?;
    store.heartbeat("evaluator", BeatState::Evaluating, total, None)?;
    while !stop.load(Ordering::SeqCst) {
        let played = evaluate_pending(dir, &cfg, &maps, &store, stop)?;
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
                if evaluate_pending(dir, &cfg, &maps, &store, stop)? == 0 {
                    break;
                }
                continue;
            }
            std::thread::sleep(Duration::from_secs(2));
        }
        store.heartbeat("evaluator", BeatState::Evaluating, total, None)?;
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
    store.heartbeat("evaluator", state, total, None)?;
    eprintln!("evaluator: {state}, {total} panel episodes played in this league");
    Ok(outcome)
}
