//! The manager's side of a league whose seats run on workers (`run
//! --store URL --pool DIR`): it defines the seats in the store, starts its
//! local workers, and follows the seats until every one is done, one fails,
//! `--for` passes or Ctrl-C. Workers on other hosts (`t2e-league worker`)
//! take seats the same way as the local ones; the manager only reads.

use crate::error::{LeagueError, Result, ResultExt};
use crate::rules::config::LeagueConfig;
use crate::run::folder::layout::LeagueDir;
use crate::run::processes::spawn::Role;
use crate::run::processes::supervising_loop::{supervise, Pass, Policy};
use crate::store::{SeatRow, SeatState, Store, StoreUrl};
use std::path::Path;
use std::process::Child;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

/// Starts a worker for the league in `dir` as a child of this process.
pub fn spawn_worker(dir: &LeagueDir, logs: &Path, index: usize) -> Result<Child> {
    let child = crate::run::processes::child::ChildCommand::Worker {
        pool: dir.root.clone(),
        logs: logs.parent().unwrap_or(logs).to_path_buf(),
        seats: 1,
    };
    let mut cmd = child
        .command()
        .map_err(|e| LeagueError::process("cannot find this program to spawn workers", e))?;
    match &dir.store {
        StoreUrl::Postgres(_) => cmd.env("T2E_STORE", dir.store.secret()),
        StoreUrl::Sqlite(path) => cmd.env("T2E_STORE", path),
    };
    // Through a pipe: a worker whose log sits on a full disk would die in
    // its first line of output.
    crate::run::processes::spawn::spawn_logged(cmd, &logs.join(format!("worker-{index}.log")))
        .map(|(child, _)| child)
        .context("cannot start a worker")
}

/// Defines the seats, runs `local` workers, and waits for the league.
#[allow(clippy::too_many_arguments)]
pub fn supervise_workers(
    dir: &LeagueDir,
    cfg: &LeagueConfig,
    store: &Store,
    roles: &[Role],
    local: usize,
    logs: &Path,
    run_for: Option<Duration>,
    stop: &AtomicBool,
    guard: &mut crate::run::processes::manager_lease::ManagerGuard,
) -> Result<()> {
    let names: Vec<String> = roles.iter().map(|r| r.name()).collect();
    store.define_seats(&names)?;
    let reopened = store.reopen_failed_seats()?;
    for s in reopened {
        tracing::warn!("seat {s} had failed; open again for this run");
    }
    tracing::info!(
        "league {}: {} seats in {} for workers; {local} local workers (logs in {}); more join with `t2e-league worker --store URL --pool {}`",
        cfg.name,
        names.len(),
        store.url(),
        logs.display(),
        dir.root.display()
    );
    let mut workers: Vec<Option<Child>> = Vec::new();
    for i in 0..local {
        workers.push(Some(spawn_worker(dir, logs, i)?));
    }
    let mut seats = Seats {
        dir,
        store,
        guard,
        logs,
        names,
        workers,
        all_done: false,
        last_look: Instant::now() - Duration::from_secs(60),
        last_line: String::new(),
    };
    let result = supervise(&mut seats, stop, run_for);
    // A summary only: a store that cannot be read now must not hide why
    // the league ended.
    if let (Ok(matches), Ok(players)) = (store.match_count(), store.players()) {
        tracing::info!(
            "league {}: {matches} matches, {} players; `t2e-league status --store URL` shows the table",
            cfg.name,
            players.len()
        );
    }
    result
}

/// The manager of a league on workers: it follows the seats in the store
/// and keeps its local workers running.
struct Seats<'a> {
    dir: &'a LeagueDir,
    store: &'a Store,
    guard: &'a mut crate::run::processes::manager_lease::ManagerGuard,
    logs: &'a Path,
    names: Vec<String>,
    workers: Vec<Option<Child>>,
    all_done: bool,
    last_look: Instant,
    last_line: String,
}

impl Policy for Seats<'_> {
    fn interrupt(&mut self) {
        tracing::info!("stopping: each worker's seats finish their iteration and checkpoint");
        self.workers
            .iter()
            .flatten()
            .for_each(crate::run::processes::spawn::interrupt);
    }

    fn pass(&mut self, pass: &mut Pass) -> Result<()> {
        if self.last_look.elapsed() >= Duration::from_secs(1) {
            self.last_look = Instant::now();
            if let Err(e) = self.guard.renew(self.store) {
                pass.fail(e.chain());
            }
            self.look(pass)?;
        }
        for (i, slot) in self.workers.iter_mut().enumerate() {
            if let Some(c) = slot {
                let exited = c
                    .try_wait()
                    .map_err(|e| LeagueError::process(format!("cannot wait for worker {i}"), e))?;
                if let Some(status) = exited {
                    *slot = None;
                    if !pass.stopping && !self.all_done && !status.success() {
                        tracing::warn!(
                            "worker {i} exited ({status}); starting another (log: {})",
                            self.logs.join(format!("worker-{i}.log")).display()
                        );
                        std::thread::sleep(Duration::from_secs(1));
                        *slot = Some(spawn_worker(self.dir, self.logs, i)?);
                    }
                }
            }
        }
        Ok(())
    }

    fn through(&self, stopping: bool) -> bool {
        (self.all_done || stopping) && self.workers.iter().flatten().count() == 0
    }
}

impl Seats<'_> {
    /// Reads the seats: a failed one ends the league, a missing one is
    /// defined again, their states go to the log when they change.
    fn look(&mut self, pass: &mut Pass) -> Result<()> {
        let (store, names) = (self.store, &self.names);
        // A store out of reach for a moment is waited out (`Store::run`).
        let mut seats = store.seats()?;
        // A seat row deleted by hand would leave its learner unrun and
        // the other one waiting for it forever: define it again, open,
        // and a worker resumes it from its checkpoint.
        let missing: Vec<String> = names
            .iter()
            .filter(|n| !seats.iter().any(|s| &s.name == *n))
            .cloned()
            .collect();
        if !missing.is_empty() && !pass.stopping {
            store.define_seats(&missing)?;
            tracing::warn!(
                "seat {} was missing from {} (its row deleted?); defined it again, open for a worker",
                missing.join(", "),
                store.url()
            );
            seats = store.seats()?;
        }
        if let Some(s) = seats.iter().find(|s| !names.contains(&s.name)) {
            pass.fail(format!(
                "{}: holds seat {}, which is not one of this league's ({}); remove its row, or run the manager that defined it",
                store.url(),
                s.name,
                names.join(", ")
            ));
        }
        if let Some(why) = SeatRow::first_failure(&seats) {
            pass.fail(why);
        }
        self.all_done = seats.iter().all(|s| s.state == SeatState::Done);
        let line = seats
            .iter()
            .map(|s| {
                format!(
                    "{} {}{}",
                    s.name,
                    s.state.name(),
                    match (&s.host, s.state) {
                        (Some(h), SeatState::Open) if s.holder.is_some() => format!(" on {h}"),
                        _ => String::new(),
                    }
                )
            })
            .collect::<Vec<_>>()
            .join(", ");
        if line != self.last_line {
            tracing::info!("seats: {line}");
            self.last_line = line;
        }
        Ok(())
    }
}
