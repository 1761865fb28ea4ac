//! The league's store: players, matches, ratings, curriculum, heartbeats,
//! crashes, seats, the config, exploits and held-out panel episodes, through sqlx,
//! one module per table (or pair of tables), each adding its methods to `Store`. Two backends behind one
//! API (`url`): a SQLite file (`league.db` in the league directory, the
//! embedded default) or a PostgreSQL database that workers on many hosts
//! share. sqlx is async; its runtime lives here, inside `Store`, so the
//! rest of the league stays synchronous.
//!
//! Invariants:
//! - SQLite: WAL, a busy timeout and short transactions: several processes
//!   (the manager, the learners, `status`) read and write it at once.
//! - The schema comes from `league/migrations/{sqlite,postgres}/*.sql`
//!   (`sqlx::migrate!`): the same migrations, numbered alike, for both
//!   (tests/integration/store.rs checks the schemas agree); an older database is
//!   migrated, one written by a newer schema is refused.
//! - Queries are one text for both backends (`$N` parameters, `ON
//!   CONFLICT`, no database-specific function; times are written by the
//!   program), except where a backend has its own way to do a thing right
//!   (taking a seat: `FOR UPDATE SKIP LOCKED` on PostgreSQL).
//! - A match is recorded once: its key names the episode (learner, world,
//!   episode), and recording it again is a no-op. The rating update of a
//!   match is written in the same transaction (`Tx`) as the match. So every
//!   write can be retried when the connection fails (`Store::run`).
//! - A PostgreSQL URL's password is never printed (`StoreUrl`'s Display).

mod connection;
mod curriculum;
mod exploits;
mod health;
mod held_out;
mod leases;
mod matches;
mod meta;
mod players;
mod ratings;
pub mod url;

#[cfg(test)]
pub use crate::data::test_player;
pub use crate::data::{
    inside_pool, player_names, BeatState, Crash, Heartbeat, Kind, MatchRecord, NewPlayer,
    PairResult, Player, RatingEntry, SeatRow, SeatState, StageChange,
};
pub use connection::{host_name, now_ms, Presence, Store, StoreError};
pub use exploits::ExploitRecord;
pub use held_out::{HeldOutEpisode, HeldOutResult, Panel};
pub use leases::{ManagerLease, SeatLease};
pub use url::{Backend, StoreUrl};

#[cfg(test)]
mod tests {
    use super::connection::{transient_code, TABLES};
    use super::*;
    use t2e_core::env::Side;

    #[test]
    fn tables_are_those_the_migrations_create() {
        for dir in ["sqlite", "postgres"] {
            let folder = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("migrations")
                .join(dir);
            let mut created: Vec<String> = Vec::new();
            for entry in std::fs::read_dir(&folder).unwrap() {
                let text = std::fs::read_to_string(entry.unwrap().path()).unwrap();
                for part in text.split("CREATE TABLE ").skip(1) {
                    let name: String = part
                        .trim_start_matches("IF NOT EXISTS ")
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    created.push(name);
                }
            }
            created.sort();
            created.dedup();
            assert_eq!(created, TABLES.to_vec(), "{dir}");
        }
    }

    #[test]
    fn a_store_missing_a_table_is_refused_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let url = StoreUrl::Sqlite(dir.path().join("league.db"));
        let store = Store::open(&url).unwrap();
        let pool = &store.pool;
        store
            .run(move || async move { sqlx::query("DROP TABLE ratings").execute(pool).await })
            .unwrap();
        drop(store);
        let err = Store::open_existing(&url)
            .err()
            .expect("refused")
            .to_string();
        assert!(err.contains("no table ratings"), "{err}");
    }

    #[test]
    fn a_busy_sqlite_database_is_waited_out_and_a_wrong_query_is_not() {
        // "(code: 5) database is locked" ended an exploit after its
        // training; it is now retried like a server that went away.
        for code in ["5", "517", "6", "08006", "57P01", "53300"] {
            assert!(transient_code(code), "{code}");
        }
        for code in ["1", "19", "2067", "23505", "42P01", "22P02"] {
            assert!(!transient_code(code), "{code}");
        }
    }

    fn player(name: &str, side: Side, kind: Kind) -> NewPlayer {
        NewPlayer {
            name: name.into(),
            side,
            kind,
            parent: None,
            env_steps: 0,
            curriculum_stage: 0,
            checkpoint: None,
        }
    }

    fn game(key: &str, c: i64, t: i64, captured: bool) -> MatchRecord {
        MatchRecord {
            key: key.into(),
            captor_player: c,
            target_player: t,
            map: "m".into(),
            num_captors: 3,
            speed_ratio: 1.0,
            seed: 7,
            captured,
            steps: 120,
            final_asz_m2: Some(0.2),
            recorded_by: "test".into(),
        }
    }

    #[test]
    fn the_curriculum_window_comes_back_from_the_store() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(&StoreUrl::in_dir(dir.path())).unwrap();
        let c = store
            .add_player(&player("captors-main", Side::Captors, Kind::Learner))
            .unwrap();
        let t = store
            .add_player(&player("rule-based", Side::Target, Kind::Heuristic))
            .unwrap();
        for (i, won) in [true, false, true, true, false].into_iter().enumerate() {
            store
                .record_match(&game(&format!("k/{i}"), c, t, won))
                .unwrap();
        }
        let faster = MatchRecord {
            speed_ratio: 1.2,
            ..game("k/fast", c, t, true)
        };
        store.record_match(&faster).unwrap();
        assert_eq!(
            store.recent_outcomes(c, 1.0, 0, 3).unwrap(),
            vec![true, true, false],
            "the last 3, oldest first"
        );
        assert_eq!(store.recent_outcomes(c, 1.2, 0, 10).unwrap(), vec![true]);
        assert_eq!(
            store.recent_outcomes(t, 1.0, 0, 10).unwrap(),
            Vec::<bool>::new(),
            "only this captor's"
        );
        assert!(
            store
                .recent_outcomes(c, 1.0, now_ms() + 60_000, 10)
                .unwrap()
                .is_empty(),
            "only since the stage began"
        );
    }

    #[test]
    fn a_newer_schema_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(&StoreUrl::in_dir(dir.path())).unwrap();
        store
            .rt
            .block_on(
                sqlx::query(
                    "INSERT INTO _sqlx_migrations (version, description, installed_on, success, checksum, execution_time) \
                     VALUES (9999, 'from the future', CURRENT_TIMESTAMP, TRUE, x'00', 0)",
                )
                .execute(&store.pool),
            )
            .unwrap();
        drop(store);
        let err = Store::open(&StoreUrl::in_dir(dir.path()))
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("newer") && err.contains("9999"), "{err}");
    }
}
