//! The store on both backends, against a real PostgreSQL server started by
//! `scripts/postgres.sh` (tests/integration/common/postgres.rs): the same contract, the
//! same schema, seats as leases under contention, and clear errors for bad
//! URLs that never show the password.

use crate::common;

use common::postgres::{fresh_database, server, sql, with_database};
use league::store::{
    BeatState, ExploitRecord, HeldOutEpisode, Kind, MatchRecord, NewPlayer, Panel, SeatState,
    Store, StoreUrl,
};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::{Arc, Barrier, Mutex};
use t2e_core::env::Side;

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

/// One store of each backend: a SQLite file and a fresh PostgreSQL database.
fn both(tag: &str) -> (tempfile::TempDir, Vec<StoreUrl>) {
    let dir = tempfile::tempdir().unwrap();
    let urls = vec![
        StoreUrl::in_dir(dir.path()),
        StoreUrl::parse(&fresh_database(server(), tag)).unwrap(),
    ];
    (dir, urls)
}

#[test]
fn both_backends_keep_the_same_contract() {
    let (_dir, urls) = both("contract");
    let mut seen = Vec::new();
    for url in &urls {
        let store = Store::open(url).unwrap();
        let c = store
            .add_player(&player("captors-main", Side::Captors, Kind::Learner))
            .unwrap();
        let t = store
            .add_player(&player("rule-based", Side::Target, Kind::Heuristic))
            .unwrap();
        assert_eq!(
            store
                .add_player(&player("captors-main", Side::Captors, Kind::Learner))
                .unwrap(),
            c,
            "{url}: adding twice is a no-op"
        );
        // No |ASZ| first, then one: see NO_NULL_FLOATS in the store.
        let no_asz = MatchRecord {
            final_asz_m2: None,
            ..game("a/0/0", c, t, true)
        };
        assert!(store.record_match(&no_asz).unwrap());
        assert!(!store.record_match(&game("a/0/0", c, t, true)).unwrap());
        assert!(store.record_match(&game("a/0/1", c, t, false)).unwrap());
        assert!(store.record_match(&game("a/1/0", c, t, true)).unwrap());
        let payoff = store.payoff().unwrap();
        assert_eq!((payoff[0].captor_wins, payoff[0].games), (2, 3), "{url}");
        let ratings = store.ratings().unwrap();
        assert!(ratings[&c].mu > ratings[&t].mu, "{url}: {ratings:?}");
        assert_eq!(store.rating_history(c).unwrap().len(), 3);
        // A rate of None first, then one (a learner's first beats): the
        // statement prepared for the first must take the second.
        store
            .heartbeat("captors-main", BeatState::Waiting, 0, None)
            .unwrap();
        store
            .heartbeat("captors-main", BeatState::Training, 640, Some(512.0))
            .unwrap();
        store
            .heartbeat("captors-main", BeatState::Done, 1280, None)
            .unwrap();
        let beat = store.heartbeats().unwrap().remove(0);
        assert_eq!(
            (beat.state, beat.env_steps, beat.steps_per_s),
            (BeatState::Done, 1280, 512.0)
        );
        store.push_curriculum(1, 1.2, "captors won").unwrap();
        store
            .record_crash("target-main", "signal 9", "killed")
            .unwrap();
        assert_eq!(store.config_once("a = 1").unwrap(), "a = 1");
        assert_eq!(store.config_once("a = 2").unwrap(), "a = 1");
        assert_eq!(store.set_league_id_once("L1").unwrap(), "L1");
        assert_eq!(store.set_league_id_once("L2").unwrap(), "L1");
        assert_eq!(
            store.recent_outcomes(c, 1.0, 0, 2).unwrap(),
            vec![false, true]
        );
        // An exploit (tests/integration/exploit.rs runs it for real on SQLite): all its
        // map sets at once, once; a player the store does not know refused.
        let exploit = |maps: &str, wins: u64, player: i64| ExploitRecord {
            exploit_key: "x1".into(),
            player,
            player_sha256: None,
            player_env_steps: Some(1_280),
            best_response: "captors mappo".into(),
            budget: "600000 env steps".into(),
            env_steps: 600_000,
            train_ms: 90_000,
            seed: 0,
            maps: maps.into(),
            num_captors: 3,
            speed_ratio: 1.0,
            episodes: 100,
            episode_length: 500,
            wins,
        };
        let rows = [exploit("small", 68, t), exploit("medium", 36, t)];
        assert!(store.record_exploit(&rows).unwrap(), "{url}");
        assert!(
            !store.record_exploit(&rows).unwrap(),
            "{url}: recorded once"
        );
        assert_eq!(store.exploit("x1").unwrap(), rows.to_vec(), "{url}");
        let mut stranger = exploit("small", 1, 999);
        stranger.exploit_key = "x2".into();
        assert!(store.record_exploit(&[stranger]).is_err(), "{url}");
        assert!(store.exploit("x2").unwrap().is_empty(), "{url}");
        // The evaluator's episodes against a held-out opponent: once per key.
        let held_out = |key: &str, captured: bool| HeldOutEpisode {
            key: key.into(),
            panel: Panel::HeldOut,
            member: t,
            opponent: "greedy:2".into(),
            map: "m".into(),
            speed_ratio: 1.0,
            seed: 7,
            captured,
            steps: 120,
        };
        assert!(store.record_held_out(&held_out("h/0", true)).unwrap());
        assert!(!store.record_held_out(&held_out("h/0", false)).unwrap());
        assert!(store.record_held_out(&held_out("h/1", false)).unwrap());
        assert!(store.has_held_out("h/1").unwrap() && !store.has_held_out("h/2").unwrap());
        // A validation episode against the same controller is its own row.
        let mut validation = held_out("v/0", false);
        validation.panel = Panel::Validation;
        validation.steps = 500;
        assert!(store.record_held_out(&validation).unwrap());
        let results = store.held_out_results().unwrap();
        assert_eq!(
            results
                .iter()
                .map(|r| (
                    r.member,
                    r.panel,
                    r.opponent.as_str(),
                    r.captures,
                    r.episodes,
                    r.steps
                ))
                .collect::<Vec<_>>(),
            vec![
                (t, Panel::HeldOut, "greedy:2", 1, 2, 240),
                (t, Panel::Validation, "greedy:2", 0, 1, 500)
            ],
            "{url}"
        );
        // What both backends read back must be the same, ids included.
        let players: Vec<_> = store
            .players()
            .unwrap()
            .into_iter()
            .map(|p| (p.id, p.name, p.side, p.kind))
            .collect();
        seen.push((
            players,
            store.payoff().unwrap(),
            store.curriculum_history().unwrap().len(),
            store.crashes().unwrap().len(),
            store.match_count().unwrap(),
            store.exploits().unwrap(),
            store.held_out_results().unwrap(),
        ));
    }
    assert_eq!(seen[0], seen[1], "SQLite and PostgreSQL disagree");
}

/// Column name, type family and NOT NULL of every table, per backend.
type Schema = BTreeMap<String, BTreeSet<(String, &'static str, bool)>>;

fn family(declared: &str) -> &'static str {
    let t = declared.to_ascii_lowercase();
    if t.contains("int") {
        "integer"
    } else if t.contains("double") || t.contains("real") || t.contains("float") {
        "real"
    } else if t.contains("text") || t.contains("char") {
        "text"
    } else {
        "other"
    }
}

fn schema(url: &str) -> Schema {
    use sqlx::{Connection, Row};
    sqlx::any::install_default_drivers();
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async {
        let mut conn = sqlx::AnyConnection::connect(url).await.unwrap();
        let rows = if url.starts_with("sqlite") {
            sqlx::query(
                "SELECT m.name AS t, p.name AS c, p.type AS ty, p.\"notnull\" + p.pk AS nn FROM sqlite_master m, pragma_table_info(m.name) p \
                 WHERE m.type = 'table' AND m.name NOT LIKE 'sqlite_%' AND m.name <> '_sqlx_migrations'",
            )
            .fetch_all(&mut conn)
            .await
            .unwrap()
        } else {
            sqlx::query(
                "SELECT c.table_name::text AS t, c.column_name::text AS c, c.data_type::text AS ty, \
                 CASE WHEN c.is_nullable = 'NO' THEN 1 ELSE 0 END AS nn FROM information_schema.columns c \
                 WHERE c.table_schema = current_schema() AND c.table_name <> '_sqlx_migrations'",
            )
            .fetch_all(&mut conn)
            .await
            .unwrap()
        };
        let mut out = Schema::new();
        for r in rows {
            let t: String = r.get("t");
            let ty: String = r.get("ty");
            let nn: i64 = r.try_get::<i64, _>("nn").or_else(|_| r.try_get::<i32, _>("nn").map(i64::from)).unwrap();
            out.entry(t)
                .or_default()
                .insert((r.get::<String, _>("c"), family(&ty), nn > 0));
        }
        out
    })
}

/// Processes that open a new league's store at once (the manager creating
/// it, a worker joining, `status` polling) all come out with the whole
/// schema; none fails on a migration another one applied first.
#[test]
fn many_openers_of_a_new_store_all_get_the_whole_schema() {
    for round in 0..6 {
        let (_dir, urls) = both(&format!("openers{round}"));
        for url in urls {
            let barrier = Arc::new(Barrier::new(6));
            let opened: Vec<_> = (0..6)
                .map(|_| {
                    let (url, barrier) = (url.clone(), barrier.clone());
                    std::thread::spawn(move || {
                        barrier.wait();
                        Store::open(&url).map(|s| s.players().map(|p| p.len()))
                    })
                })
                .collect();
            for h in opened {
                let r = h.join().unwrap();
                assert!(matches!(r, Ok(Ok(0))), "round {round}, {url:?}: {r:?}");
            }
        }
    }
}

#[test]
fn both_backends_have_the_same_schema() {
    let dir = tempfile::tempdir().unwrap();
    let pg_url = fresh_database(server(), "schema");
    drop(Store::open(&StoreUrl::in_dir(dir.path())).unwrap());
    drop(Store::open(&StoreUrl::parse(&pg_url).unwrap()).unwrap());
    let sqlite = schema(&format!(
        "sqlite://{}",
        dir.path().join("league.db").display()
    ));
    let pg = schema(&pg_url);
    assert!(
        sqlite.contains_key("seats") && sqlite.contains_key("matches"),
        "{sqlite:?}"
    );
    assert_eq!(sqlite, pg, "the two migration sets give different schemas");
}

#[test]
fn seats_are_leases_that_one_holder_has_at_a_time() {
    let (_dir, urls) = both("seats");
    for url in urls {
        let store = Store::open(&url).unwrap();
        let seats: Vec<String> = ["captors-main", "target-main", "evaluator"]
            .map(String::from)
            .to_vec();
        store.define_seats(&seats).unwrap();
        store.define_seats(&seats).unwrap();
        // Eight workers claim at once, each its own connection: every seat
        // goes to exactly one of them.
        let barrier = Arc::new(Barrier::new(8));
        let won = Arc::new(Mutex::new(Vec::new()));
        let handles: Vec<_> = (0..8)
            .map(|w| {
                let (url, barrier, won) = (url.clone(), barrier.clone(), won.clone());
                std::thread::spawn(move || {
                    let store = Store::open_existing(&url).unwrap();
                    barrier.wait();
                    while let Some(lease) = store
                        .claim_seat(&format!("worker-{w}"), "host", 60_000)
                        .unwrap()
                    {
                        won.lock().unwrap().push(lease);
                    }
                })
            })
            .collect();
        for h in handles {
            h.join().unwrap();
        }
        let won = won.lock().unwrap().clone();
        let names: BTreeSet<_> = won.iter().map(|l| l.seat.clone()).collect();
        assert_eq!(won.len(), 3, "{url}: {won:?}");
        assert_eq!(names.len(), 3, "{url}: a seat taken twice: {won:?}");
        assert!(store.claim_seat("late", "host", 60_000).unwrap().is_none());
        // A lease that expires goes to the next worker; its old holder can
        // no longer renew or end it.
        let first = won[0].clone();
        assert!(
            store.renew_lease(&first, -1).unwrap(),
            "renewed (to the past)"
        );
        let next = store
            .claim_seat("worker-9", "host2", 60_000)
            .unwrap()
            .unwrap();
        assert_eq!((next.seat.as_str(), next.claims), (first.seat.as_str(), 2));
        assert!(
            !store.renew_lease(&first, 60_000).unwrap(),
            "{url}: the old holder renewed"
        );
        assert!(!store.finish_seat(&first, SeatState::Done, None).unwrap());
        assert!(store.finish_seat(&next, SeatState::Done, None).unwrap());
        let row = store
            .seats()
            .unwrap()
            .into_iter()
            .find(|s| s.name == next.seat)
            .unwrap();
        assert_eq!(row.state, SeatState::Done);
        assert!(
            store
                .renew_lease(&next, -1)
                .map(|renewed| !renewed)
                .unwrap(),
            "a done seat has no lease"
        );
        assert!(
            store
                .claim_seat("worker-10", "h", 60_000)
                .unwrap()
                .is_none(),
            "a done seat is never taken again"
        );
        // Released: free at once.
        let other = won[1].clone();
        store.release_seat(&other).unwrap();
        assert_eq!(
            store
                .claim_seat("worker-11", "h", 60_000)
                .unwrap()
                .unwrap()
                .seat,
            other.seat
        );
    }
}

#[test]
fn bad_urls_say_what_is_wrong_and_never_show_the_password() {
    let good = server();
    let password = good.split(':').nth(2).unwrap().split('@').next().unwrap();
    let wrong_password = good.replace(password, "not-the-password");
    let err = Store::open(&StoreUrl::parse(&wrong_password).unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("password authentication failed"), "{err}");
    assert!(
        !err.contains("not-the-password") && !err.contains(password),
        "{err}"
    );
    let err = Store::open(&StoreUrl::parse(&with_database(good, "no_such_db")).unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("no_such_db") && err.contains("does not exist"),
        "{err}"
    );
    // A port nothing listens on.
    let port = good.rsplit(':').next().unwrap().split('/').next().unwrap();
    let closed = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let err = Store::open(&StoreUrl::parse(&good.replace(port, &closed.to_string())).unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("cannot connect") && err.contains("server running"),
        "{err}"
    );
    assert!(!err.contains(password), "{err}");
    let err = StoreUrl::parse(&format!("{good}/extra"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("stray path") && !err.contains(password),
        "{err}"
    );
}

#[test]
fn a_newer_schema_on_postgres_is_refused() {
    let url = fresh_database(server(), "newer");
    drop(Store::open(&StoreUrl::parse(&url).unwrap()).unwrap());
    sql(
        &url,
        "INSERT INTO _sqlx_migrations (version, description, success, checksum, execution_time) VALUES (9999, 'from the future', TRUE, '\\x00', 0)",
    );
    let err = Store::open(&StoreUrl::parse(&url).unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("newer") && err.contains("9999"), "{err}");
    let err = Store::open_read_only(&StoreUrl::parse(&url).unwrap())
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("newer") && err.contains("9999"), "{err}");
}

#[test]
fn one_manager_holds_a_league_at_a_time_by_the_stores_clock() {
    use league::store::ManagerLease;
    let (_tmp, urls) = both("manager");
    for url in urls {
        let s = Store::open(&url).unwrap();
        let lease = |holder: &str, host: &str| ManagerLease {
            holder: holder.into(),
            host: host.into(),
            pid: 7,
            pool: "/pool".into(),
            lease_until_ms: 0,
            updated_at_ms: 0,
        };
        let a = lease("a", "host-a");
        let b = lease("b", "host-b");
        assert!(s.manager().unwrap().is_none());
        assert_eq!(s.claim_manager(&a, 60_000, None).unwrap(), Ok(()));
        assert_eq!(
            s.claim_manager(&a, 60_000, None).unwrap(),
            Ok(()),
            "{url}: again"
        );
        let held = s.claim_manager(&b, 60_000, None).unwrap().unwrap_err();
        assert_eq!((held.holder.as_str(), held.host.as_str()), ("a", "host-a"));
        assert!(s.renew_manager("a", 60_000).unwrap());
        assert!(!s.renew_manager("b", 60_000).unwrap());
        // A holder known dead is replaced at once; a live one never.
        assert_eq!(s.claim_manager(&b, 60_000, Some("a")).unwrap(), Ok(()));
        assert!(!s.renew_manager("a", 60_000).unwrap(), "{url}: a lost it");
        // An expired lease is free, by the store's clock.
        assert!(s.renew_manager("b", -1_000).unwrap());
        assert_eq!(s.claim_manager(&a, 60_000, None).unwrap(), Ok(()));
        let now = s.clock_ms().unwrap();
        let local = league::store::now_ms();
        assert!((now - local).abs() < 5_000, "{url}: clock {now} vs {local}");
        s.release_manager("b").unwrap();
        assert!(
            s.manager().unwrap().is_some(),
            "only its holder releases it"
        );
        s.release_manager("a").unwrap();
        assert!(s.manager().unwrap().is_none());
    }
}
