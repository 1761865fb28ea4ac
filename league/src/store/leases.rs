//! Seats as leases: how workers on many hosts share a league's seats.
//!
//! The manager defines the seats (`define_seats`). A worker takes a seat
//! whose lease is free or expired (`claim_seat`), renews the lease while it
//! runs the seat (`renew_lease`), and ends it (`finish_seat`) or gives it
//! back (`release_seat`). A worker that dies stops renewing; once the lease
//! has expired, any worker takes the seat and resumes it from its last
//! checkpoint in the pool folder.
//!
//! Taking a seat is one statement: on PostgreSQL the seat is chosen with
//! `FOR UPDATE SKIP LOCKED`, so concurrent workers never wait on each other
//! nor take the same seat; SQLite runs one writer at a time, so the same
//! `UPDATE ... WHERE` without the lock clause is atomic there. Every write
//! names the holder, so a worker whose lease was taken over cannot change
//! the seat any more (`renew_lease` tells it so).

use super::connection::{now_ms, Store, StoreError};
use super::url::Backend;
use crate::data::{SeatRow, SeatState};
use sqlx::Row;

/// A seat a worker holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SeatLease {
    pub seat: String,
    pub holder: String,
    /// How many times the seat has been taken, this one included.
    pub claims: u64,
}

impl Store {
    /// Defines the league's seats (again: a seat already defined is kept as
    /// it is, its state and lease included).
    pub fn define_seats(&self, names: &[String]) -> Result<(), StoreError> {
        let pool = &self.pool;
        for name in names {
            let name = name.as_str();
            self.run(move || async move {
                sqlx::query(
                    "INSERT INTO seats (name, state, holder, host, lease_until_ms, claims, reason, updated_at_ms) \
                     VALUES ($1, 'open', NULL, NULL, 0, 0, NULL, $2) ON CONFLICT (name) DO NOTHING",
                )
                .bind(name)
                .bind(now_ms())
                .execute(pool)
                .await
                .map(|_| ())
            })?;
        }
        Ok(())
    }

    /// Takes one open seat whose lease is free or expired, for `lease_ms`
    /// from now; None when every open seat is held.
    pub fn claim_seat(
        &self,
        holder: &str,
        host: &str,
        lease_ms: i64,
    ) -> Result<Option<SeatLease>, StoreError> {
        let lock = match self.backend() {
            Backend::Postgres => "FOR UPDATE SKIP LOCKED",
            Backend::Sqlite => "",
        };
        // Times from the database's clock: a worker whose clock runs behind
        // would otherwise write leases that others already see expired, and
        // take live ones.
        let now = self.now_sql();
        let sql = format!(
            "UPDATE seats SET holder = $1, host = $2, lease_until_ms = {now} + $3, claims = claims + 1, updated_at_ms = {now} \
             WHERE name = (SELECT name FROM seats WHERE state = 'open' AND (holder IS NULL OR lease_until_ms < {now}) \
                           ORDER BY name LIMIT 1 {lock}) \
             AND state = 'open' AND (holder IS NULL OR lease_until_ms < {now}) \
             RETURNING name, claims"
        );
        let sql = sql.as_str();
        let pool = &self.pool;
        let row = self.run(move || async move {
            sqlx::query(sql)
                .bind(holder)
                .bind(host)
                .bind(lease_ms)
                .fetch_optional(pool)
                .await
        })?;
        row.map(|r| {
            Ok(SeatLease {
                seat: r.try_get("name")?,
                holder: holder.to_string(),
                claims: r.try_get::<i64, _>("claims")? as u64,
            })
        })
        .transpose()
        .map_err(|e| self.db(e))
    }

    /// Extends a lease to `lease_ms` from now. False when the seat is no
    /// longer this holder's (its lease expired and another worker took it,
    /// or it was ended): the holder must stop running it at once.
    pub fn renew_lease(&self, lease: &SeatLease, lease_ms: i64) -> Result<bool, StoreError> {
        let pool = &self.pool;
        let (seat, holder) = (lease.seat.as_str(), lease.holder.as_str());
        let now = self.now_sql();
        let sql = format!(
            "UPDATE seats SET lease_until_ms = {now} + $1, updated_at_ms = {now} WHERE name = $2 AND holder = $3 AND state = 'open'"
        );
        let sql = sql.as_str();
        self.run(move || async move {
            sqlx::query(sql)
                .bind(lease_ms)
                .bind(seat)
                .bind(holder)
                .execute(pool)
                .await
                .map(|r| r.rows_affected() == 1)
        })
    }

    /// Gives a seat back unfinished (its worker is stopping): another worker
    /// may take it at once.
    pub fn release_seat(&self, lease: &SeatLease) -> Result<(), StoreError> {
        let pool = &self.pool;
        let (seat, holder) = (lease.seat.as_str(), lease.holder.as_str());
        self.run(move || async move {
            sqlx::query(
                "UPDATE seats SET holder = NULL, lease_until_ms = 0, updated_at_ms = $1 WHERE name = $2 AND holder = $3 AND state = 'open'",
            )
            .bind(now_ms())
            .bind(seat)
            .bind(holder)
            .execute(pool)
            .await
            .map(|_| ())
        })
    }

    /// Ends a seat: done (it reached its budget) or failed (it cannot run,
    /// with the reason). False when the seat was not this holder's.
    pub fn finish_seat(
        &self,
        lease: &SeatLease,
        state: SeatState,
        reason: Option<&str>,
    ) -> Result<bool, StoreError> {
        let pool = &self.pool;
        let (seat, holder) = (lease.seat.as_str(), lease.holder.as_str());
        self.run(move || async move {
            sqlx::query(
                "UPDATE seats SET state = $1, reason = $2, lease_until_ms = 0, updated_at_ms = $3 WHERE name = $4 AND holder = $5 AND state = 'open'",
            )
            .bind(state.name())
            .bind(reason)
            .bind(now_ms())
            .bind(seat)
            .bind(holder)
            .execute(pool)
            .await
            .map(|r| r.rows_affected() == 1)
        })
    }

    /// Opens again the seats a former run failed (its cause may be fixed);
    /// returns their names.
    pub fn reopen_failed_seats(&self) -> Result<Vec<String>, StoreError> {
        let failed: Vec<String> = self
            .seats()?
            .into_iter()
            .filter(|s| s.state == SeatState::Failed)
            .map(|s| s.name)
            .collect();
        let pool = &self.pool;
        for name in &failed {
            let name = name.as_str();
            self.run(move || async move {
                sqlx::query(
                    "UPDATE seats SET state = 'open', holder = NULL, lease_until_ms = 0, reason = NULL, updated_at_ms = $1 WHERE name = $2 AND state = 'failed'",
                )
                .bind(now_ms())
                .bind(name)
                .execute(pool)
                .await
                .map(|_| ())
            })?;
        }
        Ok(failed)
    }

    /// Every seat, by name.
    pub fn seats(&self) -> Result<Vec<SeatRow>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as(
                "SELECT name, state, holder, host, lease_until_ms, claims, reason FROM seats ORDER BY name",
            )
            .fetch_all(pool)
            .await
        })
    }
}

/// The league's manager as the store records it (`manager_lease`).
#[derive(Clone, Debug, PartialEq, Eq, sqlx::FromRow)]
pub struct ManagerLease {
    pub holder: String,
    pub host: String,
    pub pid: i64,
    /// The pool folder it runs the league on, as that host names it.
    pub pool: String,
    pub lease_until_ms: i64,
    pub updated_at_ms: i64,
}

impl Store {
    /// The database's clock in Unix milliseconds: leases are written and
    /// judged by this one clock, so hosts whose clocks disagree cannot
    /// take a live lease for an expired one.
    pub fn clock_ms(&self) -> Result<i64, StoreError> {
        let pool = &self.pool;
        let sql = format!("SELECT {} AS now", self.now_sql());
        let sql = sql.as_str();
        self.run(move || async move { sqlx::query(sql).fetch_one(pool).await?.try_get("now") })
    }

    fn now_sql(&self) -> &'static str {
        match self.backend() {
            Backend::Postgres => "CAST(EXTRACT(EPOCH FROM clock_timestamp()) * 1000 AS BIGINT)",
            Backend::Sqlite => "CAST((julianday('now') - 2440587.5) * 86400000.0 AS INTEGER)",
        }
    }

    /// Takes the manager's lease for `lease_ms`: when none is recorded, when
    /// it expired, when `holder` has it already, or when it is `stale`'s
    /// (a manager known dead: same host, its pid gone). Otherwise the live
    /// manager's lease is returned and nothing is changed.
    pub fn claim_manager(
        &self,
        me: &ManagerLease,
        lease_ms: i64,
        stale: Option<&str>,
    ) -> Result<Result<(), ManagerLease>, StoreError> {
        let now = self.now_sql();
        let sql = format!(
            "INSERT INTO manager_lease (id, holder, host, pid, pool, lease_until_ms, updated_at_ms) \
             VALUES (1, $1, $2, $3, $4, {now} + $5, {now}) \
             ON CONFLICT (id) DO UPDATE SET holder = $1, host = $2, pid = $3, pool = $4, \
             lease_until_ms = {now} + $5, updated_at_ms = {now} \
             WHERE manager_lease.lease_until_ms < {now} OR manager_lease.holder = $1 OR manager_lease.holder = $6 \
             RETURNING holder"
        );
        let sql = sql.as_str();
        let pool = &self.pool;
        let taken = self.run(move || async move {
            sqlx::query(sql)
                .bind(&me.holder)
                .bind(&me.host)
                .bind(me.pid)
                .bind(&me.pool)
                .bind(lease_ms)
                .bind(stale.unwrap_or(""))
                .fetch_optional(pool)
                .await
                .map(|r| r.is_some())
        })?;
        if taken {
            return Ok(Ok(()));
        }
        match self.manager()? {
            Some(other) => Ok(Err(other)),
            // Released between the two statements: try once more.
            None => self.claim_manager(me, lease_ms, stale),
        }
    }

    /// Extends the manager's lease; false when another manager holds it now.
    pub fn renew_manager(&self, holder: &str, lease_ms: i64) -> Result<bool, StoreError> {
        let now = self.now_sql();
        let sql = format!(
            "UPDATE manager_lease SET lease_until_ms = {now} + $1, updated_at_ms = {now} WHERE id = 1 AND holder = $2"
        );
        let sql = sql.as_str();
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query(sql)
                .bind(lease_ms)
                .bind(holder)
                .execute(pool)
                .await
                .map(|r| r.rows_affected() == 1)
        })
    }

    /// Gives the manager's lease up (its manager is ending).
    pub fn release_manager(&self, holder: &str) -> Result<(), StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query("DELETE FROM manager_lease WHERE id = 1 AND holder = $1")
                .bind(holder)
                .execute(pool)
                .await
                .map(|_| ())
        })
    }

    /// The manager's lease as recorded, live or not.
    pub fn manager(&self) -> Result<Option<ManagerLease>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as(
                "SELECT holder, host, pid, pool, lease_until_ms, updated_at_ms FROM manager_lease WHERE id = 1",
            )
            .fetch_optional(pool)
            .await
        })
    }
}
