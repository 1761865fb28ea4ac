//! `t2e-league run`: the league's manager. It starts a league (or resumes
//! the one its directory holds, after `open::plan_start`'s checks), spawns
//! each learner and the evaluator as child processes of the same binary,
//! and supervises them: every exit has one outcome (`supervision`): a crash
//! is recorded and restarted from the last checkpoint with back-off until
//! the crash budget is spent, a process that cannot start stops the league
//! with its error. It stops at the budget (the learners stop themselves),
//! after `--for`, or on Ctrl-C: every learner finishes its iteration,
//! checkpoints and exits. Every line it prints reaches a redirected log.
//!
//! Processes, not threads: a crash stays in its process, each process sizes
//! its own libtorch and rayon pools, and the processes share nothing but the
//! league directory (so learners can later run on other machines against a
//! shared database). Children get SIGKILL if the manager dies (Linux
//! `PR_SET_PDEATHSIG`), and each learner holds a lock of its own, so a
//! killed manager never leaves a learner running twice.

use crate::error::{IoResultExt, LeagueError, Result, ResultExt};
use crate::rules::config::LeagueConfig;
use crate::rules::players::Seat;
use crate::rules::supervision::{CrashBudget, Exit, Next};
use crate::run::folder::layout::{new_league_id, LeagueDir, LeagueIdentity};
use crate::run::folder::open::{plan_start, StartPlan};
use crate::run::folder::pool::{ensure_members, reconcile};
use crate::run::processes::manager_lease::ManagerGuard;
use crate::run::processes::spawn::{
    lock_holder, reap_error, spawn, try_lock, Ended, Role, Supervised,
};
use crate::run::processes::supervising_loop::{supervise, Pass, Policy};
use crate::run::view::{SeatProgress, View};
use crate::store::Store;
use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};
use t2e_core::env::Side;
use t2e_core::fs::write_file_atomically;

/// Starts or resumes the league in `dir` and runs it to its end. Every
/// check (`open::plan_start`) passes before anything is written.
/// How the manager runs the league's seats.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Launch {
    /// As child processes of its own (the embedded default, one host).
    Direct,
    /// As seats in the store, taken by workers (`worker`) on any host; the
    /// manager starts `local` of them itself, logging to `logs`.
    Workers { local: usize, logs: PathBuf },
}

pub fn run(
    dir: &LeagueDir,
    config: Option<&Path>,
    run_for: Option<Duration>,
    stop: &AtomicBool,
    view: &dyn View,
) -> Result<()> {
    run_with(dir, config, run_for, stop, &Launch::Direct, view)
}

/// `run`, with the seats run as `launch` says.
// Long on purpose: lock, plan, lease, write the league, start its seats: each step may only run once the one before holds, and the order reads top to bottom.
pub fn run_with(
    dir: &LeagueDir,
    config: Option<&Path>,
    run_for: Option<Duration>,
    stop: &AtomicBool,
    launch: &Launch,
    view: &dyn View,
) -> Result<()> {
    let (plan, _lock, early) = {
        // The lock comes first (two managers must not both decide), but a
        // directory that does not exist yet is created only once the plan
        // says a league starts there.
        // A store kept apart from the pool has its own guard (the manager
        // lease, taken before any write), and a pool that turns out not to
        // be the league's must not get even a league.lock: plan first there.
        let external = dir.store != crate::store::StoreUrl::in_dir(&dir.root);
        // A league.lock already there is the league's own: take it before
        // the lease too, or a manager that is only frozen (its flock still
        // held) would lose the lease to one that then fails on the lock,
        // and on waking find itself replaced: no manager at all.
        let held = if dir.root.is_dir() && (!external || dir.root.join("league.lock").is_file()) {
            Some(lock(dir)?)
        } else {
            None
        };
        let plan = plan_start(dir, config)?;
        // The store's manager lease before anything is written: a manager
        // that is not the league's own (another host, another --pool)
        // changes nothing.
        let early = match &plan {
            StartPlan::Resume { .. } => {
                let store = Store::open_existing(&dir.store)?;
                let guard = ManagerGuard::take(&store, dir)?;
                Some((store, guard))
            }
            StartPlan::New(_) => None,
        };
        let held = match held {
            None if external && dir.root.is_dir() => Some(lock(dir)?),
            held => held,
        };
        (plan, held, early)
    };
    let mut early = early;
    let (cfg, league_id) = match plan {
        StartPlan::New(cfg) => {
            // Refuse maps that do not fit the protocol here, with the file's
            // name, rather than in learners that cannot start.
            let origin = config
                .map(|p| p.display().to_string())
                .unwrap_or_else(|| dir.config_path().display().to_string());
            let maps = t2e_core::map::catalog::load_prepared(&cfg.maps)
                .with_context(|| format!("{origin}: maps = \"{}\"", cfg.maps))?;
            cfg.protocol
                .check_training_maps(&cfg.maps, &maps)
                .context(origin.as_str())?;
            crate::run::folder::pool::check_trained_members(&cfg).context(origin.as_str())?;
            crate::run::evaluation::preflight::check_new_league(&cfg, &maps)
                .context(origin.as_str())?;
            std::fs::create_dir_all(&dir.root)
                .io_context(|| format!("cannot create {}", dir.root.display()))?;
            (cfg, None)
        }
        StartPlan::Resume {
            cfg,
            restore_config,
            identity,
            write_identity,
            set_store_identity,
        } => {
            if restore_config {
                write_file_atomically(&dir.config_path(), config_text(&cfg)?.as_bytes())?;
                tracing::warn!(
                    "{}: was missing; restored from the league's store",
                    dir.config_path().display()
                );
            }
            if set_store_identity {
                // A resumed league's store is open already (`early`).
                if let Some((store, _)) = &early {
                    store.set_league_id_once(&identity.league_id)?;
                }
            }
            if write_identity {
                dir.write_identity(&identity)?;
            }
            tracing::info!("resuming the league {} in {}", cfg.name, dir.root.display());
            (cfg, Some(identity.league_id))
        }
    };
    let _lock = match _lock {
        Some(l) => l,
        None => lock(dir)?,
    };
    let (store, mut guard) = match early.take() {
        Some(held) => held,
        None => {
            let store = Store::open(&dir.store)?;
            let guard = ManagerGuard::take(&store, dir)?;
            (store, guard)
        }
    };
    let result = run_league(
        dir, &cfg, &store, league_id, &mut guard, run_for, stop, launch, view,
    );
    guard.release(&store);
    result
}

/// The league once its store is open and this manager holds its lease.
#[allow(clippy::too_many_arguments)]
fn run_league(
    dir: &LeagueDir,
    cfg: &LeagueConfig,
    store: &Store,
    league_id: Option<String>,
    guard: &mut ManagerGuard,
    run_for: Option<Duration>,
    stop: &AtomicBool,
    launch: &Launch,
    view: &dyn View,
) -> Result<()> {
    let cfg = cfg.clone();
    let league_id = match league_id {
        Some(id) => id,
        None => {
            // A new league: the store first (config, identity), then
            // league.json and config.toml; a start killed in between resumes.
            let stored = store.config_once(&config_text(&cfg)?)?;
            if LeagueConfig::parse(&stored).ok().as_ref() != Some(&cfg) {
                return Err(LeagueError::Folder(format!(
                    "{}: its store was started with another config",
                    dir.root.display()
                )));
            }
            let id = store.set_league_id_once(&new_league_id())?;
            dir.write_identity(&LeagueIdentity {
                league_id: id.clone(),
                name: cfg.name.clone(),
            })?;
            write_file_atomically(&dir.config_path(), config_text(&cfg)?.as_bytes())?;
            tracing::info!("starting the league {} in {}", cfg.name, dir.root.display());
            id
        }
    };
    ensure_members(dir, store, &cfg)?;
    log_reconciled(&reconcile(dir, store, &league_id)?);
    let seats = league_seats(&cfg);
    for seat in &seats {
        t2e_learners::learn::persist::RunDir::new(dir.seat_dir(*seat)).clean_stale_temporaries()?;
    }

    let mut roles: Vec<Role> = seats.iter().map(|s| Role::Learner(*s)).collect();
    if cfg.evaluator.enabled {
        roles.push(Role::Evaluator);
    }
    if let Launch::Workers { local, logs } = launch {
        return crate::run::processes::seats::supervise_workers(
            dir, &cfg, store, &roles, *local, logs, run_for, stop, guard,
        );
    }
    let seat_names: Vec<String> = seats.iter().map(|s| s.name()).collect();
    view.seats(&seat_names, cfg.env_steps_per_learner);
    let mut manager = Manager {
        dir,
        store,
        guard,
        view,
        logs: dir.root.join("logs"),
        procs: roles.into_iter().map(Supervised::new).collect(),
        seat_names,
        budget: CrashBudget::default(),
        last_view: Instant::now() - Duration::from_secs(60),
    };
    let result = supervise(&mut manager, stop, run_for);
    view.finish();
    // A summary only: a store that cannot be read now must not hide why
    // the league ended.
    if let (Ok(matches), Ok(players)) = (store.match_count(), store.players()) {
        tracing::info!(
            "league {}: {matches} matches, {} players; `t2e-league status --dir {}` shows the table",
            cfg.name,
            players.len(),
            dir.root.display()
        );
    }
    result
}

/// Says what `reconcile` found in the pool at start, one line each.
fn log_reconciled(found: &crate::run::folder::pool::Reconciled) {
    for r in &found.removed_temporaries {
        tracing::info!("removed {r}: a temporary its writer left when it was killed");
    }
    for a in &found.adopted {
        tracing::info!("adopted {a}: a complete snapshot whose row its writer did not live to add");
    }
    for (u, why) in &found.unrecorded {
        tracing::warn!(
            "left {u} in place, out of the pool: no row names it and it cannot be adopted ({why})"
        );
    }
    for q in &found.quarantined {
        tracing::warn!("quarantined {q}: its checkpoint files are missing or corrupt");
    }
    for r in &found.reinstated {
        tracing::info!("reinstated {r}: its files are back and verify against its recorded hash");
    }
}

/// The league's learner seats: both main learners, then the exploiters
/// its config enables.
fn league_seats(cfg: &LeagueConfig) -> Vec<Seat> {
    let mut seats = vec![Seat::main(Side::Captors), Seat::main(Side::Target)];
    for side in [Side::Captors, Side::Target] {
        if cfg.exploiters.enabled(side) {
            seats.push(Seat::exploiter(side));
        }
    }
    seats
}

/// The manager of a league on one host: its seats are its own children.
struct Manager<'a> {
    dir: &'a LeagueDir,
    store: &'a Store,
    guard: &'a mut ManagerGuard,
    view: &'a dyn View,
    logs: PathBuf,
    procs: Vec<Supervised>,
    seat_names: Vec<String>,
    budget: CrashBudget,
    last_view: Instant,
}

impl Policy for Manager<'_> {
    fn interrupt(&mut self) {
        self.view
            .say("stopping: each learner finishes its iteration and checkpoints");
        self.procs.iter().for_each(Supervised::interrupt);
    }

    fn pass(&mut self, pass: &mut Pass) -> Result<()> {
        for p in &mut self.procs {
            if let Some(Ended {
                exit,
                next,
                crash_text,
            }) = p
                .reap(pass.asked, self.budget)
                .map_err(|e| reap_error(&p.role, e))?
            {
                let log = p.role.log_path(&self.logs);
                match next {
                    Next::Finished => p.finished = true,
                    Next::Restart { after, cause } => {
                        record_crash(self.view, self.store, &p.role.name(), &cause, &crash_text);
                        self.view.say(&format!(
                            "{} crashed ({cause}); restarting from its last checkpoint in {} s (log: {})",
                            p.role.name(),
                            after.as_secs(),
                            log.display()
                        ));
                        p.restart_at = Some(Instant::now() + after);
                    }
                    Next::StopLeague { why } => {
                        if exit != Exit::CannotStart {
                            record_crash(self.view, self.store, &p.role.name(), &why, &crash_text);
                        }
                        self.view.say(&format!("{why} (log: {})", log.display()));
                        p.finished = true;
                        pass.fail(why);
                    }
                }
            }
            p.restart_when_due(pass.stopping, |role| {
                spawn(self.dir, role, &self.logs, None)
            })?;
            if pass.stopping && p.child.is_none() {
                p.finished = true;
            }
        }
        if let Err(e) = self.guard.renew(self.store) {
            pass.fail(e.chain());
        }
        if self.last_view.elapsed() >= Duration::from_secs(2) {
            self.last_view = Instant::now();
            self.show_seats();
        }
        Ok(())
    }

    fn through(&self, _stopping: bool) -> bool {
        self.procs.iter().all(|p| p.finished)
    }
}

impl Manager<'_> {
    /// The seats' progress from their heartbeats. A view only: a store
    /// that cannot be read for a moment (busy, disk full) must not end the
    /// league.
    fn show_seats(&self) {
        let (Ok(beats), Ok(matches)) = (self.store.heartbeats(), self.store.match_count()) else {
            return;
        };
        for name in &self.seat_names {
            if let Some(b) = beats.iter().find(|b| &b.learner == name) {
                self.view.seat(
                    name,
                    &SeatProgress {
                        env_steps: b.env_steps,
                        steps_per_s: b.steps_per_s,
                        state: b.state.to_string(),
                        matches,
                    },
                );
            }
        }
    }
}

/// Records a crash in the store; a store that cannot take it (disk full)
/// is reported, and the league goes on.
fn record_crash(view: &dyn View, store: &Store, name: &str, cause: &str, tail: &str) {
    if let Err(e) = store.record_crash(name, cause, tail) {
        view.say(&format!(
            "could not record the crash of {name} in the store: {e}"
        ));
    }
}

/// Takes the league's manager lock, or says who holds it.
fn lock(dir: &LeagueDir) -> Result<File> {
    let lock_path = dir.root.join("league.lock");
    match try_lock(&lock_path)? {
        Some(l) => Ok(l),
        None => Err(LeagueError::Busy(format!(
            "{}: a manager (pid {}) is already running this league; stop it first (Ctrl-C) or pick another --dir",
            dir.root.display(),
            lock_holder(&lock_path)
        ))),
    }
}

/// The league's config as the store and config.toml hold it.
fn config_text(cfg: &LeagueConfig) -> Result<String> {
    toml::to_string_pretty(cfg).map_err(|cause| LeagueError::Toml {
        context: "cannot write the league's config".into(),
        cause,
    })
}
