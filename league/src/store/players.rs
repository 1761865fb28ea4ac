//! The `players` table: the league's learners and its frozen members, with
//! the checkpoint files each names (a recorded member never changes).

use super::connection::{now_ms, Store, StoreError};
use crate::data::{self, PlayerRow};
use crate::data::{side_name, NewPlayer, Player};
use sqlx::Row;

impl Store {
    /// Adds a player; a player of the same name already there is returned
    /// as it is (adding is idempotent, so a killed writer cannot duplicate).
    /// A recorded member never changes: adding a name that is recorded with
    /// other checkpoint files is an error, not a silent no-op.
    pub fn add_player(&self, p: &NewPlayer) -> Result<i64, StoreError> {
        if let Some((rel, _)) = p
            .checkpoint
            .as_ref()
            .filter(|(rel, _)| !data::inside_pool(rel))
        {
            return Err(StoreError::Invalid(format!(
                "{}: player {} would name the checkpoint {rel:?}, outside the league's pool folder",
                self.url, p.name
            )));
        }
        let (path, sha) = match &p.checkpoint {
            Some((a, b)) => (Some(a.as_str()), Some(b.as_str())),
            None => (None, None),
        };
        let pool = &self.pool;
        let (id, stored_path, stored_sha) = self.run(move || async move {
            sqlx::query(
                "INSERT INTO players (name, side, kind, parent, created_at_ms, env_steps, curriculum_stage, checkpoint_path, checkpoint_sha256) \
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9) ON CONFLICT (name) DO NOTHING",
            )
            .bind(&p.name)
            .bind(side_name(p.side))
            .bind(p.kind.name())
            .bind(p.parent)
            .bind(now_ms())
            .bind(p.env_steps as i64)
            .bind(p.curriculum_stage as i64)
            .bind(path)
            .bind(sha)
            .execute(pool)
            .await?;
            let row = sqlx::query(
                "SELECT id, checkpoint_path, checkpoint_sha256 FROM players WHERE name = $1",
            )
            .bind(&p.name)
            .fetch_one(pool)
            .await?;
            Ok((
                row.try_get::<i64, _>("id")?,
                row.try_get::<Option<String>, _>("checkpoint_path")?,
                row.try_get::<Option<String>, _>("checkpoint_sha256")?,
            ))
        })?;
        if p.checkpoint.is_some()
            && (stored_path.as_deref() != path || stored_sha.as_deref() != sha)
        {
            return Err(StoreError::Invalid(format!(
                "{}: player {} is already recorded with other checkpoint files ({} sha256 {}); a recorded member never changes",
                self.url,
                p.name,
                stored_path.as_deref().unwrap_or("none"),
                stored_sha.as_deref().unwrap_or("none"),
            )));
        }
        Ok(id)
    }

    /// Points a learner's row at its newest checkpoint.
    pub fn update_learner(
        &self,
        id: i64,
        env_steps: u64,
        checkpoint: (&str, &str),
    ) -> Result<(), StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query(
                "UPDATE players SET env_steps = $1, checkpoint_path = $2, checkpoint_sha256 = $3 WHERE id = $4",
            )
            .bind(env_steps as i64)
            .bind(checkpoint.0)
            .bind(checkpoint.1)
            .bind(id)
            .execute(pool)
            .await
            .map(|_| ())
        })
    }

    /// Takes a member out of play, saying why.
    pub fn quarantine(&self, id: i64, why: &str) -> Result<(), StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query("UPDATE players SET quarantined = $1 WHERE id = $2")
                .bind(why)
                .bind(id)
                .execute(pool)
                .await
                .map(|_| ())
        })
    }

    /// Takes a member back into play: its files verify again.
    pub fn reinstate(&self, id: i64) -> Result<(), StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query("UPDATE players SET quarantined = NULL WHERE id = $1")
                .bind(id)
                .execute(pool)
                .await
                .map(|_| ())
        })
    }

    /// Every `players` row as stored, by id.
    fn player_rows(&self) -> Result<Vec<PlayerRow>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as(
                "SELECT id, name, side, kind, parent, created_at_ms, env_steps, curriculum_stage, checkpoint_path, checkpoint_sha256, quarantined \
                 FROM players ORDER BY id",
            )
            .fetch_all(pool)
            .await
        })
    }

    pub fn players(&self) -> Result<Vec<Player>, StoreError> {
        let rows = self.player_rows()?;
        rows.into_iter()
            .map(|r| {
                Player::try_from(r).map_err(|e| StoreError::Invalid(format!("{}: {e}", self.url)))
            })
            .collect()
    }

    /// Every player, by id, for a report: a row naming a checkpoint outside
    /// the pool is listed without it and flagged in `quarantined`, where
    /// `players` refuses the whole read.
    pub fn players_flagged(&self) -> Result<Vec<Player>, StoreError> {
        let rows = self.player_rows()?;
        Ok(rows.into_iter().map(PlayerRow::flagged).collect())
    }
}
