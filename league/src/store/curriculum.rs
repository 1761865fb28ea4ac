//! The `curriculum` table: the speed curriculum's stage changes, in order.

use super::connection::{now_ms, Store, StoreError};
use crate::data::StageChange;

impl Store {
    /// Appends a curriculum stage change.
    pub fn push_curriculum(
        &self,
        stage: usize,
        speed_ratio: f64,
        reason: &str,
    ) -> Result<(), StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query(
                "INSERT INTO curriculum (stage, speed_ratio, reason, at_ms) VALUES ($1, $2, $3, $4)",
            )
            .bind(stage as i64)
            .bind(speed_ratio)
            .bind(reason)
            .bind(now_ms())
            .execute(pool)
            .await
            .map(|_| ())
        })
    }

    /// Curriculum stage changes, oldest first.
    pub fn curriculum_history(&self) -> Result<Vec<StageChange>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as("SELECT stage, speed_ratio, reason, at_ms FROM curriculum ORDER BY id")
                .fetch_all(pool)
                .await
        })
    }
}
