//! The `ratings` table: every player's live rating after each of its
//! matches, appended in the match's own transaction.

use super::connection::{now_ms, Store, StoreError, Tx};
use crate::data::RatingEntry;
use crate::rules::ratings::{self, Rating};
use sqlx::Row;
use std::collections::HashMap;

impl Store {
    /// Each player's latest live rating (players without matches are absent).
    pub fn ratings(&self) -> Result<HashMap<i64, Rating>, StoreError> {
        let pool = &self.pool;
        let rows = self.run(move || async move {
            sqlx::query(
                "SELECT r.player, r.mu, r.sigma FROM ratings r \
                 WHERE r.id = (SELECT MAX(q.id) FROM ratings q WHERE q.player = r.player)",
            )
            .fetch_all(pool)
            .await
        })?;
        rows.iter()
            .map(|r| {
                Ok((
                    r.try_get::<i64, _>("player")?,
                    Rating {
                        mu: r.try_get("mu")?,
                        sigma: r.try_get("sigma")?,
                    },
                ))
            })
            .collect::<Result<_, sqlx::Error>>()
            .map_err(|e| self.db(e))
    }

    /// A player's live ratings, oldest first.
    pub fn rating_history(&self, player: i64) -> Result<Vec<RatingEntry>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as(
                "SELECT match_id, mu, sigma, at_ms FROM ratings WHERE player = $1 ORDER BY id",
            )
            .bind(player)
            .fetch_all(pool)
            .await
        })
    }
}

/// Moves both players' live ratings by one match's outcome, inside the
/// match's transaction, so a match is never recorded without its update
/// (nor updated twice).
pub(super) async fn apply_outcome(
    tx: &mut Tx<'_>,
    match_id: i64,
    captor_player: i64,
    target_player: i64,
    captured: bool,
) -> Result<(), sqlx::Error> {
    let mut current = [Rating::default(); 2];
    for (slot, player) in current.iter_mut().zip([captor_player, target_player]) {
        if let Some(row) =
            sqlx::query("SELECT mu, sigma FROM ratings WHERE player = $1 ORDER BY id DESC LIMIT 1")
                .bind(player)
                .fetch_optional(tx.conn())
                .await?
        {
            *slot = Rating {
                mu: row.try_get("mu")?,
                sigma: row.try_get("sigma")?,
            };
        }
    }
    let (c, t) = ratings::update(current[0], current[1], captured);
    for (player, r) in [(captor_player, c), (target_player, t)] {
        sqlx::query(
            "INSERT INTO ratings (player, match_id, mu, sigma, at_ms) VALUES ($1, $2, $3, $4, $5)",
        )
        .bind(player)
        .bind(match_id)
        .bind(r.mu)
        .bind(r.sigma)
        .bind(now_ms())
        .execute(tx.conn())
        .await?;
    }
    Ok(())
}
