//! The manager's side of a league whose seats run on workers (`run
//! --store URL --pool DIR`): it defines the seats in the store, starts its
//! local workers, and follows the seats until every one is done, one fails,
//! `--for` passes or Ctrl-C. Workers on other hosts (`t2e-league worker`)
//! take seats the same way as the local ones; the manager only reads.

use crate::rules::config::LeagueConfig;
use crate::run::dir::LeagueDir;
use crate::run::process::Role;
use crate::store::{SeatRow, SeatState, Store, StoreUrl};
use anyhow::{bail, Context, Result};
use std::path::Path;
use std::process::Child;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Starts a worker for the league in `dir` as a child of this process.
pub fn spawn_worker(dir: &LeagueDir, logs: &Path, index: usize) -> Result<Child> {
    let child = crate::run::child::ChildCommand::Worker {
        pool: dir.root.clone(),
        logs: logs.parent().unwrap_or(logs).to_path_buf(),
        seats: 1,
    };
    let mut cmd = child
        .command()
        .context("cannot find this program to spawn workers")?;
    match &dir.store {
        StoreUrl::Postgres(_) => cmd.env("T2E_STORE", dir.store.secret()),
        StoreUrl::Sqlite(path) => cmd.env("T2E_STORE", path),
    };
    // Through a pipe: a worker whose log sits on a full disk would die in
    // its first line of output.
    crate::run::process::spawn_logged(cmd, &logs.join(format!("worker-{index}.log")))
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
    guard: &mut crate::run::manager_lease::ManagerGuard,
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
    let deadline = run_for.map(|d| Instant::now() + d);
    let mut stopping = false;
    let mut failure: Option<String> = None;
    let mut last_look = Instant::now() - Duration::from_secs(60);
    let mut last_line = String::new();
    loop {
        if !stopping
            && (stop.load(Ordering::SeqCst)
                || failure.is_some()
                || deadline.is_some_and(|d| Instant::now() >= d))
        {
            stopping = true;
            tracing::info!("stopping: each worker's seats finish their iteration and checkpoint");
            workers
                .iter()
                .flatten()
                .for_each(crate::run::process::interrupt);
        }
        let mut all_done = false;
        if last_look.elapsed() >= Duration::from_secs(1) {
            last_look = Instant::now();
            if let Err(e) = guard.renew(store) {
                failure.get_or_insert(format!("{e:#}"));
            }
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
            if !missing.is_empty() && !stopping {
                store.define_seats(&missing)?;
                tracing::warn!(
                    "seat {} was missing from {} (its row deleted?); defined it again, open for a worker",
                    missing.join(", "),
                    store.url()
                );
                seats = store.seats()?;
            }
            if let Some(s) = seats.iter().find(|s| !names.contains(&s.name)) {
                failure.get_or_insert(format!(
                    "{}: holds seat {}, which is not one of this league's ({}); remove its row, or run the manager that defined it",
                    store.url(),
                    s.name,
                    names.join(", ")
                ));
            }
            if let Some(why) = SeatRow::first_failure(&seats) {
                failure.get_or_insert(why);
            }
            all_done = seats.iter().all(|s| s.state == SeatState::Done);
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
            if line != last_line {
                tracing::info!("seats: {line}");
                last_line = line;
            }
        }
        for (i, slot) in workers.iter_mut().enumerate() {
            if let Some(c) = slot {
                if let Some(status) = c.try_wait()? {
                    *slot = None;
                    if !stopping && !all_done && !status.success() {
                        tracing::warn!(
                            "worker {i} exited ({status}); starting another (log: {})",
                            logs.join(format!("worker-{i}.log")).display()
                        );
                        std::thread::sleep(Duration::from_secs(1));
                        *slot = Some(spawn_worker(dir, logs, i)?);
                    }
                }
            }
        }
        let running = workers.iter().flatten().count();
        if (all_done || stopping) && running == 0 {
            break;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    tracing::info!(
        "league {}: {} matches, {} players; `t2e-league status --store URL` shows the table",
        cfg.name,
        store.match_count()?,
        store.players()?.len()
    );
    match failure {
        Some(why) => bail!("{why}"),
        None => Ok(()),
    }
}
