//! The `matches` table: one row per episode, recorded once by its key,
//! and what is read back from it (the payoff, the curriculum's window).
//! A match and its rating update are one transaction (`Tx`): the match is
//! written here, the ratings by `store::ratings`.

use super::connection::{now_ms, Store, StoreError, Tx};
use super::ratings;
use crate::data::{MatchRecord, PairResult};
use sqlx::Row;

impl Store {
    /// Records a match and updates both players' live ratings, in one
    /// transaction. Returns false (and changes nothing) when a match with
    /// the same key is already recorded.
    pub fn record_match(&self, m: &MatchRecord) -> Result<bool, StoreError> {
        if !m.speed_ratio.is_finite() || m.final_asz_m2.is_some_and(|a| !a.is_finite()) {
            return Err(StoreError::Invalid(format!(
                "match {}: non-finite speed ratio or |ASZ|",
                m.key
            )));
        }
        let pool = &self.pool;
        self.run(move || async move {
            let mut tx = Tx::begin(pool).await?;
            let Some(match_id) = insert_match(&mut tx, m).await? else {
                tx.rollback().await?;
                return Ok(false);
            };
            ratings::apply_outcome(
                &mut tx,
                match_id,
                m.captor_player,
                m.target_player,
                m.captured,
            )
            .await?;
            tx.commit().await?;
            Ok(true)
        })
    }

    pub fn has_match(&self, key: &str) -> Result<bool, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query("SELECT COUNT(*) FROM matches WHERE match_key = $1")
                .bind(key)
                .fetch_one(pool)
                .await?
                .try_get::<i64, _>(0)
        })
        .map(|n| n > 0)
    }

    pub fn match_count(&self) -> Result<u64, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query("SELECT COUNT(*) FROM matches")
                .fetch_one(pool)
                .await?
                .try_get::<i64, _>(0)
        })
        .map(|n| n as u64)
    }

    /// Matches a recorder (a learner's name, or "evaluator") wrote.
    pub fn matches_recorded_by(&self, recorder: &str) -> Result<u64, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query("SELECT COUNT(*) FROM matches WHERE recorded_by = $1")
                .bind(recorder)
                .fetch_one(pool)
                .await?
                .try_get::<i64, _>(0)
        })
        .map(|n| n as u64)
    }

    /// The payoff table: captor wins and games per captor-target pair.
    pub fn payoff(&self) -> Result<Vec<PairResult>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as(
                "SELECT captor_player AS captor, target_player AS target, CAST(SUM(captured) AS BIGINT) AS captor_wins, COUNT(*) AS games FROM matches \
                 GROUP BY captor_player, target_player ORDER BY captor_player, target_player",
            )
            .fetch_all(pool)
            .await
        })
    }

    /// The payoff of the matches one recorder wrote ("evaluator": the
    /// panel's episodes, which the matchmaker's choices do not bias).
    pub fn payoff_recorded_by(&self, recorder: &str) -> Result<Vec<PairResult>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as(
                "SELECT captor_player AS captor, target_player AS target, CAST(SUM(captured) AS BIGINT) AS captor_wins, COUNT(*) AS games FROM matches \
                 WHERE recorded_by = $1 GROUP BY captor_player, target_player ORDER BY captor_player, target_player",
            )
            .bind(recorder)
            .fetch_all(pool)
            .await
        })
    }

    /// Outcomes (captured or not), oldest first, of the last `limit`
    /// matches `captor_player` played at `speed_ratio` since `since_ms`: the
    /// curriculum's window, rebuilt when a learner restarts.
    pub fn recent_outcomes(
        &self,
        captor_player: i64,
        speed_ratio: f64,
        since_ms: i64,
        limit: usize,
    ) -> Result<Vec<bool>, StoreError> {
        let pool = &self.pool;
        let rows = self.run(move || async move {
            sqlx::query(
                "SELECT captured FROM matches WHERE captor_player = $1 AND ABS(speed_ratio - $2) < 1e-9 \
                 AND recorded_at_ms >= $3 ORDER BY id DESC LIMIT $4",
            )
            .bind(captor_player)
            .bind(speed_ratio)
            .bind(since_ms)
            .bind(limit as i64)
            .fetch_all(pool)
            .await
        })?;
        rows.iter()
            .rev()
            .map(|r| r.try_get::<i64, _>(0).map(|c| c != 0))
            .collect::<Result<_, _>>()
            .map_err(|e| self.db(e))
    }
}

/// Writes a match row; `None` when its key is already recorded (nothing
/// written), else the new row's id.
async fn insert_match(tx: &mut Tx<'_>, m: &MatchRecord) -> Result<Option<i64>, sqlx::Error> {
    let inserted = sqlx::query(
        "INSERT INTO matches (match_key, captor_player, target_player, map, num_captors, speed_ratio, seed, captured, steps, final_asz_m2, recorded_by, recorded_at_ms) \
         VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, CASE WHEN $13 = 1 THEN $10 ELSE NULL END, $11, $12) ON CONFLICT (match_key) DO NOTHING",
    )
    .bind(&m.key)
    .bind(m.captor_player)
    .bind(m.target_player)
    .bind(&m.map)
    .bind(m.num_captors as i64)
    .bind(m.speed_ratio)
    .bind(m.seed as i64)
    .bind(m.captured as i64)
    .bind(m.steps as i64)
    .bind(m.final_asz_m2.unwrap_or(0.0))
    .bind(&m.recorded_by)
    .bind(now_ms())
    .bind(m.final_asz_m2.is_some() as i64)
    .execute(tx.conn())
    .await?
    .rows_affected()
        == 1;
    if !inserted {
        return Ok(None);
    }
    sqlx::query("SELECT id FROM matches WHERE match_key = $1")
        .bind(&m.key)
        .fetch_one(tx.conn())
        .await?
        .try_get("id")
        .map(Some)
}
