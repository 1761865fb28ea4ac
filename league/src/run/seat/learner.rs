//! One main learner of the league, as its own process (`t2e-league
//! league-learner`, spawned by the manager). It trains like `train` does,
//! except that every world draws its opponent when its episode starts:
//! a snapshot of the other side by PFSP, the other side's latest snapshot
//! (its main learner), or a heuristic member. Heuristic opponents play
//! inside the vector env; network opponents are batched, one forward pass
//! per distinct opponent over the rows of the worlds that play it. Every
//! finished episode is recorded in the store (once), and the learner adds
//! frozen copies of itself to the pool.

use crate::error::{LeagueError, Result, ResultExt};
use crate::rules::config::LeagueConfig;
use crate::rules::curriculum::Curriculum;
use crate::rules::matchmaking::{
    choose_opponent, draw_seed, pick_slot, slot_seed, Candidate, Fixed, MatchmakingConfig, Opponent,
};
use crate::rules::players::{learner_name, Seat};
use crate::rules::roles::{seat_of_row, should_snapshot, should_wait, SeatRules};
use crate::rules::supervision::Outcome;
use crate::run::folder::layout::LeagueDir;
use crate::run::folder::pool::{add_snapshot, SnapshotOutcome};
use crate::run::seat::opponents::{OpponentNets, WorldOpponent};
use crate::store::{BeatState, Kind, MatchRecord, NewPlayer, Player, Store};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use t2e_core::env::{Action, Side, VecEnv};
use t2e_learners::error::LearnError;
use t2e_learners::learn::train::{RolloutHooks, Trainer};

pub struct LeagueHooks<'a> {
    store: &'a Store,
    dir: &'a LeagueDir,
    cfg: &'a LeagueConfig,
    side: Side,
    learner_id: i64,
    learner_name: String,
    /// Its seat: what it draws and whether it moves the curriculum.
    seat: Seat,
    matchmaking: MatchmakingConfig,
    /// The other side's playable members, and this learner's record against each.
    members: Vec<Player>,
    candidates: Vec<Candidate>,
    /// The other side's extra heuristic members (`[members]`), by id.
    extras: Vec<i64>,
    main: Option<i64>,
    target_exploiter: Option<i64>,
    worlds: Vec<WorldOpponent>,
    /// The other side's networks in play: loaded, stacked, run.
    pub nets: OpponentNets,
    /// This window's opponent slots (`MatchmakingConfig::slots`), the window
    /// they were drawn for, and vector-env steps so far (windows count them).
    slots: Vec<Opponent>,
    slots_window: Option<u64>,
    pub vector_steps: u64,
    rng: ChaCha8Rng,
    pub curriculum: Curriculum,
    pub wins: u64,
    pub games: u64,
    pub matches_recorded: u64,
}

impl<'a> LeagueHooks<'a> {
    pub fn new(
        store: &'a Store,
        dir: &'a LeagueDir,
        cfg: &'a LeagueConfig,
        seat: Seat,
        learner_id: i64,
    ) -> Result<LeagueHooks<'a>> {
        let side = seat.side;
        let mut matchmaking = cfg.matchmaking.clone();
        if seat.draws_main_line_only() {
            // Always the main learner once it has a snapshot; the pool
            // (heuristics first) until then.
            matchmaking.main_share = 1.0;
            matchmaking.members_share = 0.0;
        }
        let mut hooks = LeagueHooks {
            store,
            dir,
            cfg,
            side,
            learner_id,
            learner_name: seat.name(),
            seat,
            matchmaking,
            members: Vec::new(),
            candidates: Vec::new(),
            extras: Vec::new(),
            main: None,
            target_exploiter: None,
            worlds: Vec::new(),
            nets: OpponentNets::new(side.other(), cfg.opponent_cache, cfg.greedy_opponents),
            slots: Vec::new(),
            slots_window: None,
            vector_steps: 0,
            rng: ChaCha8Rng::seed_from_u64(cfg.seed ^ learner_id as u64 ^ 0x0990),
            curriculum: Curriculum::new(),
            wins: 0,
            games: 0,
            matches_recorded: 0,
        };
        hooks.refresh()?;
        if seat.drives_curriculum() {
            // The window survives restarts: rebuilt from the matches the
            // store holds since the current stage began.
            let since = store
                .curriculum_history()?
                .last()
                .map(|c| c.at_ms)
                .unwrap_or(0);
            let speed = hooks.curriculum.speed(&cfg.curriculum);
            let recent = store.recent_outcomes(learner_id, speed, since, cfg.curriculum.window)?;
            hooks.curriculum.recent = recent.into();
        }
        Ok(hooks)
    }

    fn other(&self) -> Side {
        self.side.other()
    }

    fn seat(&self) -> Seat {
        self.seat
    }

    /// Re-reads the pool, this learner's record and the curriculum stage.
    pub fn refresh(&mut self) -> Result<()> {
        let playable = crate::run::folder::pool::playable(&self.store.players()?, self.seat());
        self.members = playable.members;
        self.main = playable.main;
        // Only the main captors draw the target exploiter (`target_exploiter_share`);
        // without it, the share falls to PFSP. An exploiter's `playable` has none.
        self.target_exploiter = playable.exploiter.filter(|_| self.side == Side::Captors);
        let extra_names = self.cfg.members.extra_names(self.side.other());
        self.extras = self
            .members
            .iter()
            .filter(|m| extra_names.contains(&m.name))
            .map(|m| m.id)
            .collect();
        let payoff = self.store.payoff()?;
        self.candidates = self
            .members
            .iter()
            .map(|m| {
                let rec =
                    crate::rules::payoff::record(&payoff, self.learner_id, self.side, Some(m.id));
                Candidate {
                    player: m.id,
                    wins: rec.wins as f64,
                    games: rec.games as f64,
                }
            })
            .collect();
        if let Some(change) = self.store.curriculum_history()?.last() {
            if change.stage != self.curriculum.stage {
                self.curriculum.stage = change.stage;
                self.curriculum.recent.clear();
            }
        }
        Ok(())
    }

    /// Draws opponents for every world (a fresh start or a resumed run).
    pub fn assign_all(&mut self, venv: &mut VecEnv) -> Result<()> {
        self.worlds.clear();
        for e in 0..venv.num_envs() {
            let w = self.draw(venv, e)?;
            self.worlds.push(w);
        }
        Ok(())
    }

    /// The opponent drawn with `seed`: by PFSP for this world alone, or
    /// from this window's slots (drawn again when a new window starts).
    fn pick(&mut self, seed: u64) -> Option<Opponent> {
        let mm = &self.matchmaking;
        let fixed = Fixed {
            main: self.main,
            extras: &self.extras,
            target_exploiter: self.target_exploiter,
        };
        if mm.slots == 0 {
            return choose_opponent(&self.candidates, fixed, mm, seed);
        }
        let window = self.vector_steps / self.cfg.episode_length as u64;
        if self.slots_window != Some(window) {
            self.slots = (0..mm.slots)
                .filter_map(|s| {
                    let seed = slot_seed(self.cfg.seed, self.learner_id, s, window);
                    choose_opponent(&self.candidates, fixed, mm, seed)
                })
                .collect();
            self.slots_window = Some(window);
        }
        self.slots.get(pick_slot(self.slots.len(), seed)).copied()
    }

    /// Draws world `e`'s opponent and speed for its current episode and sets
    /// the world up for them.
    /// The opponent networks the worlds play now, which loading another
    /// must not evict.
    fn networks_in_use(&self) -> Vec<i64> {
        self.worlds.iter().filter_map(|w| w.network).collect()
    }

    fn draw(&mut self, venv: &mut VecEnv, e: usize) -> Result<WorldOpponent> {
        let other = self.other();
        let seed = draw_seed(self.cfg.seed, self.learner_id, e, venv.env(e).seed);
        let player = match self.pick(seed) {
            Some(Opponent::Main) => self.main.expect("main drawn only when there is one"),
            Some(Opponent::Member(id)) => id,
            None => {
                return Err(LeagueError::Pool(format!(
                    "the {} pool is empty: the heuristic member is missing",
                    other.name()
                )))
            }
        };
        let Some(member) = self.members.iter().find(|m| m.id == player).cloned() else {
            if self.slots_window.is_some() {
                // A slot's member left the pool (quarantined): draw the slots again.
                self.slots_window = None;
                return self.draw(venv, e);
            }
            return Err(LeagueError::Pool(format!(
                "drawn member {player} is not in the pool"
            )));
        };
        let u: f64 = ChaCha8Rng::seed_from_u64(seed ^ 0x5BEED).gen();
        let speed = self
            .curriculum
            .sample_speed(&self.cfg.curriculum, self.side, u);
        venv.set_world_speeds(e, 1.0, speed)?;
        let network = match member.kind {
            Kind::Heuristic => {
                let Some(spec) = self.cfg.members.spec_of(other, &member.name) else {
                    return Err(LeagueError::UnnamedHeuristic(member.name.clone()));
                };
                venv.script_world(e, other, Some(spec.build(other)?));
                None
            }
            _ => match self
                .nets
                .load(&self.dir.root, &member, &self.networks_in_use())
            {
                Ok(hidden) => {
                    venv.script_world(e, other, None);
                    Some((member.id, hidden))
                }
                Err(err) => {
                    // A member whose files are gone or corrupt leaves the pool; the league goes on.
                    let why = err.chain();
                    tracing::warn!("quarantining {}: {why}", member.name);
                    self.store.quarantine(member.id, &why)?;
                    self.refresh()?;
                    self.slots_window = None;
                    return self.draw(venv, e);
                }
            },
        };
        let team = other.agents(self.cfg.num_captors).len();
        Ok(WorldOpponent {
            player,
            hidden: vec![0.0; network.map(|(_, h)| h).unwrap_or(0) * team],
            network: network.map(|(id, _)| id),
            speed,
        })
    }
}

impl RolloutHooks for LeagueHooks<'_> {
    fn before_step(&mut self, venv: &mut VecEnv, actions: &mut [Action]) -> Result<(), LearnError> {
        self.vector_steps += 1;
        self.nets
            .act(
                venv,
                &mut self.worlds,
                self.cfg.num_captors,
                &mut self.rng,
                actions,
            )
            .map_err(LearnError::hooks)
    }

    fn after_step(&mut self, venv: &mut VecEnv) -> Result<(), LearnError> {
        self.record_finished(venv).map_err(LearnError::hooks)
    }
}

impl LeagueHooks<'_> {
    /// After a step: records the episodes that ended and draws their
    /// worlds' next opponents.
    fn record_finished(&mut self, venv: &mut VecEnv) -> Result<()> {
        let finished = venv.finished.clone();
        for s in &finished {
            let w = self.worlds[s.env].clone();
            let (captor_player, target_player) = match self.side {
                Side::Captors => (self.learner_id, w.player),
                Side::Target => (w.player, self.learner_id),
            };
            let recorded = self.store.record_match(&MatchRecord {
                key: format!("{}/{:016x}", self.learner_name, s.seed),
                captor_player,
                target_player,
                map: s.map.clone(),
                num_captors: self.cfg.num_captors,
                speed_ratio: w.speed,
                seed: s.seed,
                captured: s.captured,
                steps: s.steps,
                final_asz_m2: None,
                recorded_by: self.learner_name.clone(),
            })?;
            self.matches_recorded += recorded as u64;
            let won = match self.side {
                Side::Captors => s.captured,
                Side::Target => !s.captured,
            };
            self.games += 1;
            self.wins += won as u64;
            if self.seat.drives_curriculum() {
                if let Some(stage) =
                    self.curriculum
                        .record(&self.cfg.curriculum, w.speed, s.captured)
                {
                    let speed = self.curriculum.speed(&self.cfg.curriculum);
                    self.store.push_curriculum(
                        stage,
                        speed,
                        &format!(
                            "main captors won at least {:.0}% of their last {} matches at the previous stage",
                            100.0 * self.cfg.curriculum.promote_at,
                            self.cfg.curriculum.window
                        ),
                    )?;
                    tracing::info!("curriculum: stage {stage}, speed ratio {speed}");
                }
            }
            let next = self.draw(venv, s.env)?;
            self.worlds[s.env] = next;
        }
        Ok(())
    }
}

/// Waits (heartbeating "waiting") while `should_wait`; returns the seconds waited.
fn wait_for_other_main(
    store: &Store,
    seat: Seat,
    mine: u64,
    lead: u64,
    stop: &AtomicBool,
) -> Result<f64> {
    let other = learner_name(match seat.side {
        Side::Captors => Side::Target,
        Side::Target => Side::Captors,
    });
    let started = Instant::now();
    let mut announced = false;
    let mut next_warning = 60;
    while !stop.load(Ordering::SeqCst) {
        let beats = store.heartbeats()?;
        let now = crate::store::now_ms();
        let theirs = beats
            .iter()
            .find(|b| b.learner == other)
            .map(|b| (b.state, b.env_steps, now - b.at_ms));
        if !should_wait(mine, theirs, lead) {
            break;
        }
        if !announced {
            tracing::info!(
                "{}: {} env steps ahead of {other} by more than {lead}: waiting for it",
                seat.name(),
                mine
            );
            announced = true;
        }
        // Said again every minute: a seat nobody runs is waited for
        // forever, and the one line above scrolls away.
        let waited = started.elapsed().as_secs();
        if waited >= next_warning {
            next_warning += 60;
            let why = match theirs {
                None => format!("{other} has never run: no process or worker has taken its seat (start a `worker` on the league's store, or give `run --workers` one per seat)"),
                Some((state, steps, _)) => format!("{other} is {state:?} at {steps} env steps"),
            };
            tracing::warn!("{}: waiting {waited} s for {other}; {why}", seat.name());
        }
        store.heartbeat(&seat.name(), BeatState::Waiting, mine, None)?;
        std::thread::sleep(std::time::Duration::from_millis(500));
    }
    Ok(started.elapsed().as_secs_f64())
}

/// Runs one learner (main or exploiter) until its budget is spent or `stop`
/// is set; checkpoints its own state and adds snapshots of itself to the
/// pool (an exploiter then starts again from its initial weights). Errors
/// before the first iteration are `CannotStart`.
pub fn run_learner(dir: &LeagueDir, seat: Seat, stop: &AtomicBool) -> Result<Outcome> {
    let opened = crate::run::folder::open::open_process(dir).map_err(LeagueError::cannot_start)?;
    let (cfg, store, league_id) = (opened.cfg, opened.store, opened.league_id);
    if !SeatRules::of(&cfg, seat).enabled {
        return Err(LeagueError::cannot_start(LeagueError::Refused(format!(
            "{}: this league has no {} (exploiters.{} = false in {})",
            dir.root.display(),
            seat.name(),
            seat.side.name(),
            dir.config_path().display()
        ))));
    }
    let threads = dir.threads_per_learner(&cfg);
    tch::set_num_threads(threads as i32);
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global();
    let started = start_learner(dir, &cfg, &store, seat).map_err(LeagueError::cannot_start)?;
    train_learner(dir, &cfg, &store, &league_id, seat, started, stop)
}

/// A learner ready to train: its trainer at its resume point.
struct Started {
    trainer: Trainer,
    learner_id: i64,
}

fn start_learner(
    dir: &LeagueDir,
    cfg: &LeagueConfig,
    store: &Store,
    seat: Seat,
) -> Result<Started> {
    let name = seat.name();
    let learner_id = store.add_player(&NewPlayer {
        name: name.clone(),
        side: seat.side,
        kind: SeatRules::of(cfg, seat).kind,
        parent: None,
        env_steps: 0,
        curriculum_stage: 0,
        checkpoint: None,
    })?;
    let row = store
        .players()?
        .into_iter()
        .find(|p| p.id == learner_id)
        .ok_or_else(|| LeagueError::Pool("the learner's own row vanished".into()))?;
    let maps = t2e_core::map::catalog::load_prepared(&cfg.maps)
        .with_context(|| format!("maps = \"{}\"", cfg.maps))?;
    let tcfg = SeatRules::of(cfg, seat).train_config(cfg);
    let run_dir = dir.seat_dir(seat);
    let trainer = match resume_point(dir, store, &row, &tcfg)? {
        ResumePoint::Fresh => {
            std::fs::create_dir_all(&run_dir)
                .map_err(|e| LeagueError::io(format!("cannot create {}", run_dir.display()), e))?;
            Trainer::new(tcfg, maps)?
        }
        ResumePoint::State => {
            let t = Trainer::resume(tcfg, maps, &run_dir)?;
            tracing::info!("{name}: resuming at {} env steps", t.env_steps);
            t
        }
    };
    Ok(Started {
        trainer,
        learner_id,
    })
}

/// Where a learner starts: from nothing, or from what its `state.json`
/// names (rebuilt first from the checkpoint the store names, if the file
/// was lost). Never from nothing when the store or the disk shows that it
/// trained before.
enum ResumePoint {
    Fresh,
    State,
}

fn resume_point(
    dir: &LeagueDir,
    store: &Store,
    row: &crate::store::Player,
    tcfg: &t2e_learners::learn::train::TrainConfig,
) -> Result<ResumePoint> {
    use t2e_learners::learn::persist::{Recovery, RunDir};
    let seat = seat_of_row(row.side, row.kind)
        .ok_or_else(|| LeagueError::Pool(format!("{} is no learner's row", row.name)))?;
    let run = RunDir::new(dir.seat_dir(seat));
    let state_path = run.state_path();
    let rejected = match run.recover(row.side, &tcfg.hash(), row.env_steps)? {
        Recovery::Kept { env_steps } if env_steps < row.env_steps => {
            return Err(LeagueError::Folder(format!(
                "{}: at {} env steps, but the store ({}) recorded {} at {} env steps; it would train again over steps it already played. Put the newer state.json back",
                state_path.display(),
                env_steps,
                store.url(),
                row.name,
                row.env_steps
            )))
        }
        Recovery::Kept { .. } => return Ok(ResumePoint::State),
        Recovery::Rebuilt {
            checkpoint,
            env_steps,
        } => {
            tracing::warn!(
                "{}: {} was missing; rebuilt from {}, its newest checkpoint that verifies ({} env steps)",
                row.name,
                state_path.display(),
                checkpoint.display(),
                env_steps
            );
            return Ok(ResumePoint::State);
        }
        Recovery::Empty if row.env_steps == 0 && row.checkpoint.is_none() => {
            return Ok(ResumePoint::Fresh)
        }
        Recovery::Empty => Vec::new(),
        Recovery::Unusable(rejected) => rejected,
    };
    Err(LeagueError::Folder(format!(
        "{}: missing, and no checkpoint in {} can stand in for it (the store ({}) records {} at {} env steps{}); refusing to start it over. Put state.json back",
        state_path.display(),
        run.checkpoints_dir().display(),
        store.url(),
        row.name,
        row.env_steps,
        if rejected.is_empty() {
            String::new()
        } else {
            format!("; {}", rejected.join("; "))
        }
    )))
}

/// Trains the seat's learner to the league's budget, or until `stop`.
fn train_learner(
    dir: &LeagueDir,
    cfg: &LeagueConfig,
    store: &Store,
    league_id: &str,
    seat: Seat,
    started: Started,
    stop: &AtomicBool,
) -> Result<Outcome> {
    let mut run = LearnerRun::start(dir, cfg, store, league_id, seat, started)?;
    while run.trainer.env_steps < cfg.env_steps_per_learner && !stop.load(Ordering::SeqCst) {
        if !run.step(stop)? {
            break;
        }
    }
    run.finish()
}

/// One run of a main learner in its seat, from its process's start to its
/// end: `start` (the pool and the resets it may have missed), `step` (one
/// iteration, then a snapshot or a checkpoint), `snapshot`, `reset`,
/// `finish` (its checkpoint, last heartbeat and figures).
struct LearnerRun<'a> {
    dir: &'a LeagueDir,
    cfg: &'a LeagueConfig,
    store: &'a Store,
    league_id: &'a str,
    seat: Seat,
    name: String,
    rules: SeatRules,
    trainer: Trainer,
    learner_id: i64,
    hooks: LeagueHooks<'a>,
    /// What every reset returns to.
    initial: PathBuf,
    /// Env steps, wins and games at the last snapshot.
    last_snapshot: u64,
    wins_at_snapshot: u64,
    games_at_snapshot: u64,
    segment_start: Instant,
    steps_at_start: u64,
    own_inference: f64,
    waited: f64,
}

impl<'a> LearnerRun<'a> {
    fn start(
        dir: &'a LeagueDir,
        cfg: &'a LeagueConfig,
        store: &'a Store,
        league_id: &'a str,
        seat: Seat,
        started: Started,
    ) -> Result<LearnerRun<'a>> {
        let name = seat.name();
        let Started {
            mut trainer,
            learner_id,
        } = started;
        let initial = dir.seat_dir(seat).join("initial");
        let rules = SeatRules::of(cfg, seat);
        if rules.resets_after_snapshot && !initial.join("meta.json").is_file() {
            // What every reset returns to (written once, before any training).
            trainer.side(seat.side)?.save(&initial)?;
        }
        // A snapshot of its own whose row it did not live to add (killed
        // between the folder and the row): into the pool before anything
        // counts snapshots.
        for (rel, adopted) in
            crate::run::folder::pool::adopt_unrecorded(dir, store, league_id, Some(&name))?
        {
            match adopted {
                Ok(()) => tracing::warn!(
                    "{name}: adopted {rel}, a snapshot whose row it did not live to add"
                ),
                Err(e) => tracing::warn!("{name}: left {rel} out of the pool ({})", e.chain()),
            }
        }
        let mut hooks = LeagueHooks::new(store, dir, cfg, seat, learner_id)?;
        hooks.vector_steps = trainer.env_steps / cfg.num_envs as u64;
        let last_snapshot = store
            .players()?
            .iter()
            .filter(|p| p.parent == Some(learner_id))
            .map(|p| p.env_steps)
            .max()
            .unwrap_or(0);
        let mut run = LearnerRun {
            dir,
            cfg,
            store,
            league_id,
            seat,
            name,
            rules,
            trainer,
            learner_id,
            hooks,
            initial,
            last_snapshot,
            wins_at_snapshot: 0,
            games_at_snapshot: 0,
            segment_start: Instant::now(),
            steps_at_start: 0,
            own_inference: 0.0,
            waited: 0.0,
        };
        if run.rules.resets_after_snapshot
            && run.last_snapshot == run.trainer.env_steps
            && run.trainer.env_steps > 0
        {
            // Killed between its snapshot and its reset: reset now, or it
            // would go on training the weights it just added to the pool.
            run.reset()?;
            tracing::info!(
                "{}: back to its initial weights (its last snapshot is its resume point)",
                run.name
            );
        }
        run.hooks.assign_all(run.trainer.venv_mut())?;
        run.store
            .heartbeat(&run.name, BeatState::Training, run.trainer.env_steps, None)?;
        (run.segment_start, run.steps_at_start) = (Instant::now(), run.trainer.env_steps);
        Ok(run)
    }

    /// One iteration (after waiting for the other main learner when it
    /// keeps pace), then a snapshot when the rule says so, else a
    /// checkpoint when one is due. False: stopped while waiting.
    fn step(&mut self, stop: &AtomicBool) -> Result<bool> {
        if self.seat.keeps_pace() {
            self.waited += wait_for_other_main(
                self.store,
                self.seat,
                self.trainer.env_steps,
                self.cfg.pace_env_steps,
                stop,
            )?;
            if stop.load(Ordering::SeqCst) {
                return Ok(false);
            }
        }
        let started = Instant::now();
        let m = self.trainer.iterate_with(&mut self.hooks)?;
        self.own_inference += m.time_inference;
        let since = self.trainer.env_steps.saturating_sub(self.last_snapshot);
        let (w, g) = (
            self.hooks.wins - self.wins_at_snapshot,
            self.hooks.games - self.games_at_snapshot,
        );
        if should_snapshot(since, w, g, self.rules.snapshot) {
            self.snapshot()?;
            if self.rules.resets_after_snapshot {
                self.reset()?;
                tracing::info!("{}: back to its initial weights", self.name);
            }
        } else if self
            .trainer
            .iteration
            .is_multiple_of(self.cfg.checkpoint_every)
        {
            self.checkpoint()?;
        }
        self.hooks.refresh()?;
        let steps = (self.cfg.num_envs * self.cfg.rollout_steps) as f64;
        self.store.heartbeat(
            &self.name,
            BeatState::Training,
            self.trainer.env_steps,
            Some(steps / started.elapsed().as_secs_f64()),
        )?;
        Ok(true)
    }

    /// Its weights now into the pool as a new member.
    fn snapshot(&mut self) -> Result<()> {
        // The learner's own checkpoint first: a restart then resumes at or
        // after this snapshot, so it never takes one under a name the pool
        // already holds.
        self.checkpoint()?;
        let name = &self.name;
        match add_snapshot(
            &mut self.trainer,
            self.store,
            self.dir,
            self.league_id,
            self.seat,
            self.learner_id,
            self.hooks.curriculum.stage,
        )? {
            SnapshotOutcome::Added(snap) => {
                tracing::info!("{name}: snapshot {snap} joins the pool")
            }
            SnapshotOutcome::AlreadyInPool(snap) => tracing::info!(
                "{name}: {snap} is already in the pool (recorded before a restart); it stays as recorded"
            ),
            SnapshotOutcome::Blocked(snap) => tracing::warn!(
                "{name}: cannot add the snapshot {snap}: {} exists and is not a recorded member (put there by hand?); left alone, this snapshot is skipped",
                self.dir.players_dir().join(&snap).display()
            ),
        }
        self.last_snapshot = self.trainer.env_steps;
        self.wins_at_snapshot = self.hooks.wins;
        self.games_at_snapshot = self.hooks.games;
        Ok(())
    }

    /// Back to its initial weights. The reset is the new resume point: a
    /// restart must not bring back the weights just snapshotted.
    fn reset(&mut self) -> Result<()> {
        self.trainer.side(self.seat.side)?.reset_to(&self.initial)?;
        self.checkpoint()
    }

    fn checkpoint(&self) -> Result<()> {
        save_learner(
            &self.trainer,
            self.store,
            self.dir,
            self.seat,
            self.learner_id,
        )
    }

    /// Its checkpoint, its last heartbeat (done or stopped) and this run's
    /// figures.
    fn finish(self) -> Result<Outcome> {
        self.checkpoint()?;
        let (cfg, name, trainer, hooks) = (self.cfg, &self.name, &self.trainer, &self.hooks);
        let outcome = if trainer.env_steps >= cfg.env_steps_per_learner {
            Outcome::Done
        } else {
            Outcome::Stopped
        };
        let state = match outcome {
            Outcome::Done => BeatState::Done,
            Outcome::Stopped => BeatState::Stopped,
        };
        let waited = self.waited;
        let secs = self.segment_start.elapsed().as_secs_f64() - waited;
        let trained = trainer.env_steps - self.steps_at_start;
        let rate = trained as f64 / secs.max(1e-9);
        // A run that trained no step (a finished league started again)
        // keeps the rate it reported last.
        self.store.heartbeat(
            name,
            state,
            trainer.env_steps,
            (trained > 0).then_some(rate),
        )?;
        tracing::info!(
            "{name}: {state} at {} env steps, {} matches recorded; this run {:.1} s training ({waited:.1} s waiting for the other side), {rate:.0} env steps/s",
            trainer.env_steps, hooks.matches_recorded, secs
        );
        let team = self.seat.side.agents(cfg.num_captors).len() as f64;
        let own_rows = trained as f64 * team;
        if own_rows > 0.0 && hooks.nets.rows > 0 {
            tracing::info!(
                "{name}: inference per robot row: own networks (actor + critic, sampling) {:.2} us, opponent networks (actor, batched per opponent) {:.2} us over {} rows",
                1e6 * self.own_inference / own_rows,
                1e6 * hooks.nets.seconds / hooks.nets.rows as f64,
                hooks.nets.rows
            );
        }
        Ok(outcome)
    }
}

/// The learner's own resume point, and its row pointed at it.
fn save_learner(
    trainer: &Trainer,
    store: &Store,
    dir: &LeagueDir,
    seat: Seat,
    id: i64,
) -> Result<()> {
    let run_dir = dir.seat_dir(seat);
    let written = trainer.save(&run_dir)?;
    if let Some(ckpt) = written.first() {
        let sha = crate::run::folder::pool::sha256_of_meta(ckpt)?;
        let rel = dir.relative(ckpt);
        store.update_learner(id, trainer.env_steps, (&rel, &sha))?;
    }
    Ok(())
}
