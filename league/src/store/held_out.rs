//! The evaluator's episodes against held-out opponents: controllers named
//! in the config that play league members but are never members
//! themselves. They have their own table, so nothing a learner draws, and
//! no rating, ever sees them. Each episode belongs to one panel: the
//! held-out panel is watched; the validation panel chooses what `export
//! --best` exports.

use super::connection::{now_ms, Store, StoreError};
pub use crate::data::{HeldOutEpisode, HeldOutResult, Panel};

/// A panel as the store writes it (`Panel::name`).
fn parse_panel(s: &str) -> Result<Panel, sqlx::Error> {
    match s {
        "held-out" => Ok(Panel::HeldOut),
        "validation" => Ok(Panel::Validation),
        other => Err(sqlx::Error::ColumnDecode {
            index: "panel".into(),
            source: format!("unknown panel '{other}'").into(),
        }),
    }
}

impl<'r> sqlx::FromRow<'r, sqlx::any::AnyRow> for HeldOutResult {
    fn from_row(r: &'r sqlx::any::AnyRow) -> Result<Self, sqlx::Error> {
        use sqlx::Row;
        let n = |col: &str| super::connection::u64_column(r, col);
        Ok(HeldOutResult {
            member: r.try_get("member")?,
            panel: parse_panel(&r.try_get::<String, _>("panel")?)?,
            opponent: r.try_get("opponent")?,
            captures: n("captures")?,
            episodes: n("episodes")?,
            steps: n("steps")?,
        })
    }
}

impl Store {
    /// Records one episode; false (nothing changed) when its key is known.
    pub fn record_held_out(&self, e: &HeldOutEpisode) -> Result<bool, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query(
                "INSERT INTO held_out_episodes (episode_key, member, opponent, map, speed_ratio, seed, captured, steps, recorded_at_ms, panel) \
                 VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10) ON CONFLICT (episode_key) DO NOTHING",
            )
            .bind(&e.key)
            .bind(e.member)
            .bind(&e.opponent)
            .bind(&e.map)
            .bind(e.speed_ratio)
            .bind(e.seed as i64)
            .bind(i64::from(e.captured))
            .bind(i64::from(e.steps))
            .bind(now_ms())
            .bind(e.panel.name())
            .execute(pool)
            .await
            .map(|r| r.rows_affected() == 1)
        })
    }

    pub fn has_held_out(&self, key: &str) -> Result<bool, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            let n: i64 =
                sqlx::query_scalar("SELECT COUNT(*) FROM held_out_episodes WHERE episode_key = $1")
                    .bind(key)
                    .fetch_one(pool)
                    .await?;
            Ok(n > 0)
        })
    }

    /// Every held-out episode recorded (the evaluator's count includes them).
    pub fn held_out_count(&self) -> Result<u64, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            let n: i64 = sqlx::query_scalar("SELECT COUNT(*) FROM held_out_episodes")
                .fetch_one(pool)
                .await?;
            Ok(n as u64)
        })
    }

    /// Captures, episodes and steps per (member, panel, opponent).
    pub fn held_out_results(&self) -> Result<Vec<HeldOutResult>, StoreError> {
        let pool = &self.pool;
        self.run(move || async move {
            sqlx::query_as(
                "SELECT member, panel, opponent, CAST(SUM(captured) AS BIGINT) AS captures, COUNT(*) AS episodes, CAST(SUM(steps) AS BIGINT) AS steps \
                 FROM held_out_episodes GROUP BY member, panel, opponent ORDER BY member, panel, opponent",
            )
            .fetch_all(pool)
            .await
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::{Kind, NewPlayer, StoreUrl};
    use t2e_core::env::Side;

    #[test]
    fn held_out_episodes_are_recorded_once_and_stay_out_of_the_matches() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(&StoreUrl::in_dir(dir.path())).unwrap();
        let member = store
            .add_player(&NewPlayer {
                name: "target-snap-1".into(),
                side: Side::Target,
                kind: Kind::Snapshot,
                parent: None,
                env_steps: 10,
                curriculum_stage: 0,
                checkpoint: None,
            })
            .unwrap();
        let episode = |i: u32, opponent: &str, captured: bool| HeldOutEpisode {
            key: format!("evaluator/held-out/{member}/{opponent}/{i}"),
            panel: Panel::HeldOut,
            member,
            opponent: opponent.into(),
            map: "m".into(),
            speed_ratio: 1.0,
            seed: u64::from(i),
            captured,
            steps: 100,
        };
        for (i, captured) in [true, false, true].into_iter().enumerate() {
            assert!(store
                .record_held_out(&episode(i as u32, "greedy:2", captured))
                .unwrap());
        }
        assert!(store.record_held_out(&episode(9, "random", false)).unwrap());
        assert!(
            !store
                .record_held_out(&episode(0, "greedy:2", false))
                .unwrap(),
            "a key is recorded once"
        );
        assert!(store
            .has_held_out(&episode(2, "greedy:2", true).key)
            .unwrap());
        assert!(!store
            .has_held_out(&episode(3, "greedy:2", true).key)
            .unwrap());
        assert_eq!(store.held_out_count().unwrap(), 4);
        assert_eq!(
            store.held_out_results().unwrap(),
            vec![
                HeldOutResult {
                    member,
                    panel: Panel::HeldOut,
                    opponent: "greedy:2".into(),
                    captures: 2,
                    episodes: 3,
                    steps: 300,
                },
                HeldOutResult {
                    member,
                    panel: Panel::HeldOut,
                    opponent: "random".into(),
                    captures: 0,
                    episodes: 1,
                    steps: 100,
                },
            ]
        );
        assert_eq!(store.match_count().unwrap(), 0, "no match row");
        assert!(store.payoff().unwrap().is_empty());
        let mut stranger = episode(1, "random", true);
        stranger.member = member + 50;
        assert!(store.record_held_out(&stranger).is_err(), "foreign key");
    }
}
