//! The `heartbeats` and `crashes` tables: each learner's latest state and
//! throughput, and every crash with its last error line.

use super::connection::{host_name, now_ms, Store, StoreError};
use crate::data::{BeatState, Crash, Heartbeat};

impl Store {
    /// A learner's latest state and throughput; `steps_per_s` None keeps
    /// the rate last reported (a run that trained no step measured none).
    pub fn heartbeat(
        &self,
        learner: &str,
        state: BeatState,
        env_steps: u64,
        steps_per_s: Option<f64>,
    ) -> Result<(), StoreError> {
        let rate = steps_per_s.map(|r| if r.is_finite() { r } else { 0.0 });
        let host = host_name();
        let host = host.as_str();
        let pool = &self.pool;
        // No Option<f64> bind (see NO_NULL_FLOATS): a flag says whether the
        // rate is new.
        self.run(move || async move {
            sqlx::query(
                "INSERT INTO heartbeats (learner, pid, host, state, env_steps, steps_per_s, at_ms) VALUES ($1, $2, $3, $4, $5, $6, $7) \
                 ON CONFLICT (learner) DO UPDATE SET pid = excluded.pid, host = excluded.host, state = excluded.state, env_steps = excluded.env_steps, \
                 steps_per_s = CASE WHEN $8 = 1 THEN excluded.steps_per_s ELSE heartbeats.steps_per_s END, at_ms = excluded.at_ms",
            )
            .bind(learner)
            .bind(std::process::id() as i64)
            .bind(host)
            .bind(state.name())
            .bind(env_steps as i64)
            .bind(rate.unwrap_or(0.0))
            .bind(now_ms())
            .bind(rate.is_some() as i64)
            .execute(pool)
            .await
            .map(|_| ())
        })
    }

    pub fn heartbeats(&self) -> Result<Vec<Heartbeat>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as(
                "SELECT learner, pid, host, state, env_steps, steps_per_s, at_ms FROM heartbeats ORDER BY learner",
            )
            .fetch_all(pool)
            .await
        })
    }

    pub fn record_crash(
        &self,
        learner: &str,
        exit_status: &str,
        message: &str,
    ) -> Result<(), StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query(
                "INSERT INTO crashes (learner, exit_status, message, at_ms) VALUES ($1, $2, $3, $4)",
            )
            .bind(learner)
            .bind(exit_status)
            .bind(message)
            .bind(now_ms())
            .execute(pool)
            .await
            .map(|_| ())
        })
    }

    /// Crashes, oldest first.
    pub fn crashes(&self) -> Result<Vec<Crash>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as("SELECT learner, exit_status, message, at_ms FROM crashes ORDER BY id")
                .fetch_all(pool)
                .await
        })
    }
}
