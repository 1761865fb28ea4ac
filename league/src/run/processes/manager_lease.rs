//! The manager's lease in the store: one manager runs a league at a time,
//! wherever it runs. Its own file because the manager and `seats.rs` (the
//! manager's side of a league on workers) both hold it.

use crate::error::{LeagueError, Result};
use crate::run::folder::layout::{new_league_id, LeagueDir};
use crate::store::Store;
use std::time::{Duration, Instant};

/// How long the manager's lease in the store lasts without renewal, and how
/// often it is renewed.
const MANAGER_LEASE: Duration = Duration::from_secs(30);
const MANAGER_RENEW: Duration = Duration::from_secs(5);

/// This manager's lease in the store (`store::ManagerLease`): the flock on
/// league.lock keeps a second manager out only where it sees the same
/// folder on the same kernel, and a manager on another host, or given
/// another --pool, reaches the same PostgreSQL store all the same.
pub struct ManagerGuard {
    holder: String,
    pool: String,
    renewed: Instant,
}

impl ManagerGuard {
    /// Takes the lease, or says which live manager holds it. A lease left by
    /// a manager of this host whose process is gone (kill -9) is taken at
    /// once rather than after it expires.
    pub fn take(store: &Store, dir: &LeagueDir) -> Result<ManagerGuard> {
        let host = crate::store::host_name();
        let pid = std::process::id();
        let me = crate::store::ManagerLease {
            holder: format!("{host}:{pid}:{}", &new_league_id()[..8]),
            host: host.clone(),
            pid: i64::from(pid),
            pool: std::fs::canonicalize(&dir.root)
                .unwrap_or_else(|_| dir.root.clone())
                .display()
                .to_string(),
            lease_until_ms: 0,
            updated_at_ms: 0,
        };
        let lease_ms = MANAGER_LEASE.as_millis() as i64;
        let stale = store
            .manager()?
            .filter(|m| m.host == host && !is_manager_process(m.pid))
            .map(|m| m.holder);
        match store.claim_manager(&me, lease_ms, stale.as_deref())? {
            Ok(()) => Ok(ManagerGuard {
                holder: me.holder,
                pool: me.pool,
                renewed: Instant::now(),
            }),
            Err(other) => {
                let now = store.clock_ms().unwrap_or(other.updated_at_ms);
                Err(LeagueError::Busy(format!(
                    "{}: another manager runs this league (pid {} on {}, pool {}; it renewed its lease {:.0} s ago). Nothing was changed. \
                     Stop that manager first (Ctrl-C); a manager that was killed loses the lease {} s after its last renewal",
                    store.url(),
                    other.pid,
                    other.host,
                    other.pool,
                    (now - other.updated_at_ms).max(0) as f64 / 1000.0,
                    MANAGER_LEASE.as_secs()
                )))
            }
        }
    }

    /// Renews the lease when it is due. An error when another manager holds
    /// it now (this one stalled past its lease and was replaced): two
    /// managers must not both run the league. A store out of reach is
    /// waited out by the next renewal.
    pub fn renew(&mut self, store: &Store) -> Result<()> {
        if self.renewed.elapsed() < MANAGER_RENEW {
            return Ok(());
        }
        match store.renew_manager(&self.holder, MANAGER_LEASE.as_millis() as i64) {
            Ok(true) => {
                self.renewed = Instant::now();
                Ok(())
            }
            Ok(false) => match store.manager() {
                // The row was deleted by hand: nobody else holds the league.
                Ok(None) => {
                    self.renewed = Instant::now();
                    let me = crate::store::ManagerLease {
                        holder: self.holder.clone(),
                        host: crate::store::host_name(),
                        pid: i64::from(std::process::id()),
                        pool: self.pool.clone(),
                        lease_until_ms: 0,
                        updated_at_ms: 0,
                    };
                    match store.claim_manager(&me, MANAGER_LEASE.as_millis() as i64, None) {
                        Ok(Err(other)) => Err(LeagueError::Busy(format!(
                            "{}: another manager took this league over (pid {} on {}); stopping this one",
                            store.url(),
                            other.pid,
                            other.host
                        ))),
                        _ => Ok(()),
                    }
                }
                Ok(Some(other)) => Err(LeagueError::Busy(format!(
                    "{}: another manager took this league over (pid {} on {}, pool {}); stopping this one",
                    store.url(),
                    other.pid,
                    other.host,
                    other.pool
                ))),
                Err(_) => Ok(()),
            },
            Err(_) => Ok(()),
        }
    }

    pub fn release(&self, store: &Store) {
        store.release_manager(&self.holder).ok();
    }
}

/// Whether `pid` on this host is a running `t2e-league run`.
fn is_manager_process(pid: i64) -> bool {
    if pid <= 0 {
        return false;
    }
    std::fs::read(format!("/proc/{pid}/cmdline"))
        .map(|cmd| cmd.split(|b| *b == 0).any(|arg| arg == b"run"))
        .unwrap_or(false)
}
