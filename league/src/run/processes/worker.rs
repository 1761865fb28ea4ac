//! `t2e-league worker`: runs a league's seats on any host. It takes free
//! seats from the store (leases, `store::leases`), runs each as a child
//! process of this binary against the shared pool folder, renews the
//! leases while they run, and supervises them with the manager's rules
//! (`supervision`): a crash restarts from the last checkpoint with
//! back-off, a seat that cannot start fails and stops the league.
//!
//! Safety rules:
//! - A lease that cannot be renewed because another worker holds the seat
//!   now (it expired) ends the child at once: a seat never trains twice.
//! - Each claim holds its seat under a name of its own (the worker's, then
//!   `/N`): a seat row deleted and defined anew, then taken again by this
//!   same worker, is a new lease, and the old one's renewal fails, so the
//!   seat does not run twice here either.
//! - A worker that cannot reach the store for as long as its leases last
//!   ends its children itself before another worker may take their seats.
//! - A worker killed with -9 takes its children with it (`PR_SET_PDEATHSIG`);
//!   its leases expire and other workers resume the seats from the pool.
//! - The pool folder must be the one every host shares: a worker that
//!   cannot see a file the store names refuses to start, naming the file.

use crate::error::{LeagueError, Result};
use crate::rules::supervision::{CrashBudget, Exit, Next};
use crate::run::folder::layout::LeagueDir;
use crate::run::folder::open::open_process;
use crate::run::processes::spawn::{reap_error, spawn, Ended, Role, Supervised};
use crate::run::processes::supervising_loop::{supervise, Pass, Policy};
use crate::store::{SeatLease, SeatRow, SeatState, Store};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};
use t2e_core::error::ConfigError;

/// How a worker runs.
#[derive(Clone, Debug)]
pub struct WorkerOptions {
    /// Seats it runs at once.
    pub seats: usize,
    /// The host name its leases and heartbeats record.
    pub host: String,
    /// Stop after this long (children checkpoint, seats are given back).
    pub run_for: Option<Duration>,
    /// How long a lease lasts without renewal (renewed every third of it).
    pub lease: Duration,
    /// Where the children's logs go (a local folder).
    pub logs: PathBuf,
}

impl WorkerOptions {
    /// The options a worker cannot run with; the error names the option.
    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.seats == 0 {
            return Err(ConfigError::new(
                "seats",
                0,
                "a worker runs at least one seat",
            ));
        }
        if self.lease < Duration::from_secs(3) {
            return Err(ConfigError::new(
                "lease",
                format!("{:?}", self.lease),
                "at least 3 s (it is renewed every third of it)",
            ));
        }
        if self.host.trim().is_empty() {
            return Err(ConfigError::about("host", "empty"));
        }
        // Status prints one seat per line, and holders are split on ':'.
        if let Some(c) = self
            .host
            .chars()
            .find(|c| c.is_control() || *c == ':' || c.is_whitespace())
        {
            return Err(ConfigError::new(
                "host",
                format!("{:?}", self.host),
                format!("holds {c:?}; a host name is one word without ':' (letters, digits, '-', '.', '_')"),
            ));
        }
        if self.host.len() > 253 {
            return Err(ConfigError::about(
                "host",
                format!(
                    "{} characters; a host name has at most 253",
                    self.host.len()
                ),
            ));
        }
        Ok(())
    }
}

/// A seat this worker holds and its process.
struct Held {
    lease: SeatLease,
    proc: Supervised,
}

/// The pool folder holds this league and every file the store names, or the
/// worker refuses to run on it.
fn check_pool(dir: &LeagueDir, store: &Store) -> Result<()> {
    let pool = dir.root.display();
    for p in store.players()? {
        if let Some((path, _)) = &p.checkpoint {
            if !crate::store::inside_pool(path) {
                return Err(LeagueError::Pool(format!(
                    "{}: player {} names {path}, outside the pool folder; refusing it",
                    store.url(),
                    p.name
                )));
            }
            if !dir.root.join(path).exists() {
                return Err(LeagueError::Pool(format!(
                    "{pool}: cannot see {path}, which the store names for player {} (written by another host?): the pool folder is not shared. Every worker's --pool must be the one folder all hosts share",
                    p.name
                )));
            }
        }
    }
    Ok(())
}

const GONE: &str = "its seat row is gone from the store (deleted?); the manager defines it again";

/// Why `renew_lease` failed, as the store shows it now; `worker` is this
/// worker's name, which its claims' holders extend.
fn why_lost(store: &Store, lease: &SeatLease, worker: &str) -> String {
    match store.seats() {
        Err(e) => format!("the store cannot tell why: {e}"),
        Ok(seats) => match seats.into_iter().find(|s| s.name == lease.seat) {
            // Never taken since it was defined: the row this worker held was
            // deleted and the manager has defined the seat anew.
            None => GONE.into(),
            Some(s) if s.holder.is_none() && s.claims == 0 => GONE.into(),
            Some(s) if s.state != SeatState::Open => {
                format!("the seat was ended ({}) by someone else", s.state.name())
            }
            Some(s) => match s.holder {
                // This worker took the seat again, under another claim,
                // while still holding the old one: the old row was gone.
                Some(h) if claim_of(&h) == Some(worker) => {
                    format!("{GONE}, and this worker has taken it again ({h})")
                }
                Some(h) => format!(
                    "another worker ({h} on {}) holds it now",
                    s.host.as_deref().unwrap_or("?")
                ),
                None => "the seat was given back by someone else and is free".into(),
            },
        },
    }
}

/// The worker a claim's holder belongs to (`WORKER/N` -> `WORKER`).
fn claim_of(holder: &str) -> Option<&str> {
    holder.rsplit_once('/').map(|(worker, _)| worker)
}

/// Runs seats until every seat of the league is done (Ok), one fails (an
/// error naming it), `run_for` passes or `stop` is set (Ok: seats given
/// back for other workers or a later run).
pub fn run_worker(dir: &LeagueDir, opts: &WorkerOptions, stop: &AtomicBool) -> Result<()> {
    opts.validate()?;
    // The store first: an unreachable server or a wrong password is the
    // error to show, before anything about the pool folder.
    drop(Store::open_existing(&dir.store)?);
    if !dir.identity_path().is_file() {
        return Err(LeagueError::Pool(format!(
            "{}: holds no league.json, so it is not this league's pool folder (the store is {}). --pool must be the folder the manager's --pool names, shared by every host",
            dir.root.display(),
            dir.store
        )));
    }
    let opened = open_process(dir)?;
    let store = opened.store;
    check_pool(dir, &store)?;
    let holder = format!(
        "{}:{}:{}",
        opts.host,
        std::process::id(),
        &crate::run::folder::layout::new_league_id()[..8]
    );
    let lease_ms = opts.lease.as_millis() as i64;
    tracing::info!(
        "worker {holder}: league {} ({}), pool {}, up to {} seats",
        opened.cfg.name,
        store.url(),
        dir.root.display(),
        opts.seats
    );
    let mut worker = Worker {
        dir,
        opts,
        store: &store,
        holder,
        lease_ms,
        budget: CrashBudget::default(),
        held: Vec::new(),
        every_seat_done: false,
        last_renewed: Instant::now(),
        last_claim: Instant::now() - Duration::from_secs(60),
        claims: 0,
    };
    supervise(&mut worker, stop, opts.run_for)
}

/// A worker: the seats it holds, each a child process under its lease.
struct Worker<'a> {
    dir: &'a LeagueDir,
    opts: &'a WorkerOptions,
    store: &'a Store,
    holder: String,
    lease_ms: i64,
    budget: CrashBudget,
    held: Vec<Held>,
    /// The league has nothing left for any worker.
    every_seat_done: bool,
    last_renewed: Instant,
    last_claim: Instant,
    claims: u64,
}

impl Policy for Worker<'_> {
    fn interrupt(&mut self) {
        for h in &self.held {
            h.proc.interrupt();
        }
    }

    fn pass(&mut self, pass: &mut Pass) -> Result<()> {
        self.renew();
        self.reap(pass)?;
        self.held.retain(|h| !h.proc.finished);
        if !pass.stopping
            && self.held.len() < self.opts.seats
            && self.last_claim.elapsed() >= Duration::from_secs(1)
        {
            self.last_claim = Instant::now();
            self.claim(pass)?;
        }
        Ok(())
    }

    fn through(&self, stopping: bool) -> bool {
        self.every_seat_done || (stopping && self.held.is_empty())
    }
}

impl Worker<'_> {
    /// Renews every third of the lease; a seat taken over, or a store out
    /// of reach for as long as the lease, ends its child here.
    fn renew(&mut self) {
        let (opts, store, holder) = (self.opts, self.store, &self.holder);
        if self.last_renewed.elapsed() < opts.lease / 3 {
            return;
        }
        let mut all_ok = true;
        for h in &mut self.held {
            match store.renew_lease(&h.lease, self.lease_ms) {
                Ok(true) => {}
                Ok(false) => {
                    tracing::warn!(
                        "worker {holder}: lost the lease of {} ({}); ending its process",
                        h.lease.seat,
                        why_lost(store, &h.lease, holder)
                    );
                    if let Some(mut c) = h.proc.child.take() {
                        c.kill().ok();
                        c.wait().ok();
                    }
                    h.proc.finished = true;
                }
                Err(e) => {
                    all_ok = false;
                    tracing::warn!("worker {holder}: cannot renew {}: {e}", h.lease.seat);
                }
            }
        }
        if all_ok {
            self.last_renewed = Instant::now();
        } else if self.last_renewed.elapsed() >= opts.lease * 9 / 10 {
            for h in &mut self.held {
                if let Some(mut c) = h.proc.child.take() {
                    tracing::warn!(
                        "worker {holder}: the store was out of reach for the lease's length; ending {} before another worker may take it",
                        h.lease.seat
                    );
                    c.kill().ok();
                    c.wait().ok();
                }
                h.proc.finished = true;
            }
        }
    }

    /// Reaps the seats' processes, by the manager's rules, and restarts
    /// those that crashed once their back-off has passed.
    fn reap(&mut self, pass: &mut Pass) -> Result<()> {
        let (dir, opts, store, holder) = (self.dir, self.opts, self.store, &self.holder);
        for h in &mut self.held {
            let p = &mut h.proc;
            if let Some(Ended {
                exit,
                next,
                crash_text,
            }) = p
                .reap(pass.asked, self.budget)
                .map_err(|e| reap_error(&p.role, e))?
            {
                let name = p.role.name();
                match next {
                    Next::Finished => {
                        if exit == Exit::Done {
                            store.finish_seat(&h.lease, SeatState::Done, None)?;
                            tracing::info!("worker {holder}: {name} done");
                        } else {
                            store.release_seat(&h.lease)?;
                        }
                        p.finished = true;
                    }
                    Next::Restart { after, cause } => {
                        store
                            .record_crash(&name, &cause, &crash_text)
                            .unwrap_or_else(|e| tracing::error!("cannot record a crash: {e}"));
                        tracing::warn!(
                            "worker {holder}: {name} crashed ({cause}); restarting it in {} s",
                            after.as_secs()
                        );
                        p.restart_at = Some(Instant::now() + after);
                    }
                    Next::StopLeague { why } => {
                        if exit != Exit::CannotStart {
                            store.record_crash(&name, &why, &crash_text).ok();
                        }
                        store.finish_seat(&h.lease, SeatState::Failed, Some(&why))?;
                        tracing::info!("worker {holder}: {why}");
                        p.finished = true;
                        pass.fail(why);
                    }
                }
            }
            p.restart_when_due(pass.stopping, |role| {
                spawn(dir, role, &opts.logs, Some(&opts.host))
            })?;
            if pass.stopping && p.child.is_none() && !p.finished {
                store.release_seat(&h.lease).ok();
                p.finished = true;
            }
        }
        Ok(())
    }

    /// Takes a free seat, if the league has one.
    fn claim(&mut self, pass: &mut Pass) -> Result<()> {
        let (store, holder) = (self.store, &self.holder);
        let seats = store.seats()?;
        if let Some(why) = SeatRow::first_failure(&seats) {
            pass.fail(why);
            return Ok(());
        }
        if self.held.is_empty() && seats.iter().all(|s| s.state == SeatState::Done) {
            tracing::info!("worker {holder}: every seat of the league is done");
            self.every_seat_done = true;
            return Ok(());
        }
        self.claims += 1;
        let claim = format!("{holder}/{}", self.claims);
        if let Some(lease) = store.claim_seat(&claim, &self.opts.host, self.lease_ms)? {
            let Some(role) = Role::from_name(&lease.seat) else {
                store.release_seat(&lease)?;
                return Err(LeagueError::Refused(format!(
                    "{}: seat {} is not one this build runs (a newer manager?)",
                    store.url(),
                    lease.seat
                )));
            };
            tracing::info!(
                "worker {holder}: took {} (taken {} times so far)",
                lease.seat,
                lease.claims
            );
            self.held.push(Held {
                lease,
                proc: Supervised::new(role),
            });
        }
        Ok(())
    }
}
