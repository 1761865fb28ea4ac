//! The `league_config` table: the league's config, stored once, and its
//! identity.

use super::connection::{now_ms, Store, StoreError};
use sqlx::Row;

impl Store {
    /// Stores the league's config the first time; returns the one stored
    /// (the first), so a resumed league can tell whether it changed.
    pub fn config_once(&self, toml: &str) -> Result<String, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query(
                "INSERT INTO league_config (id, config_toml, created_at_ms) VALUES (1, $1, $2) ON CONFLICT (id) DO NOTHING",
            )
            .bind(toml)
            .bind(now_ms())
            .execute(pool)
            .await?;
            sqlx::query("SELECT config_toml FROM league_config WHERE id = 1")
                .fetch_one(pool)
                .await?
                .try_get::<String, _>(0)
        })
    }

    /// The config the league was started with, if the store holds one (an
    /// empty store does not).
    pub fn stored_config(&self) -> Result<Option<String>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query("SELECT config_toml FROM league_config WHERE id = 1")
                .fetch_optional(pool)
                .await?
                .map(|r| r.try_get::<String, _>(0))
                .transpose()
        })
    }

    /// The league's identity, if one was written (a store from before
    /// identities has no such column until it is migrated).
    pub fn league_id(&self) -> Result<Option<String>, StoreError> {
        let pool = &self.pool;
        let row = self.run(move || async move {
            sqlx::query("SELECT * FROM league_config WHERE id = 1")
                .fetch_optional(pool)
                .await
        })?;
        Ok(row.and_then(|r| r.try_get::<Option<String>, _>("league_id").ok().flatten()))
    }

    /// Writes the league's identity once (the config row must exist);
    /// returns the identity stored, which is `id` unless one was there.
    pub fn set_league_id_once(&self, id: &str) -> Result<String, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query(
                "UPDATE league_config SET league_id = $1 WHERE id = 1 AND league_id IS NULL",
            )
            .bind(id)
            .execute(pool)
            .await
            .map(|_| ())
        })?;
        self.league_id()?.ok_or_else(|| {
            StoreError::Invalid(format!(
                "{}: holds no league config to attach an identity to",
                self.url
            ))
        })
    }
}
