//! `bench --store URL`: the league store's write path under contention.
//! N writers (threads, each with its own connection, as N league processes
//! have) record matches with their rating updates, the league's hottest
//! write, for a fixed time; the table gives matches recorded per second and
//! each write's latency (median, p99) for every N asked.

use anyhow::{bail, Result};
use league::store::{Kind, MatchRecord, NewPlayer, Store, StoreUrl};
use std::time::{Duration, Instant};
use t2e_core::env::Side;

pub fn run(url: &str, writers: &[usize], seconds: f64) -> Result<()> {
    let base = StoreUrl::parse(url).map_err(anyhow::Error::msg)?;
    if writers.is_empty() || writers.iter().any(|&w| w == 0 || w > 64) {
        bail!("--writers {writers:?}: each in 1..=64");
    }
    println!(
        "| store | writers | matches recorded | matches/s | write latency median (ms) | p99 (ms) |"
    );
    println!("|---|---|---|---|---|---|");
    for &n in writers {
        let tmp = tempfile_dir()?;
        let url = match &base {
            // A fresh SQLite file per row, beside the one named.
            StoreUrl::Sqlite(_) => StoreUrl::in_dir(&tmp.join(format!("w{n}"))),
            StoreUrl::Postgres(_) => base.clone(),
        };
        let store = Store::open(&url)?;
        let tag = format!("{}-{}", std::process::id(), n);
        let mk = |name: &str, side, kind| NewPlayer {
            name: format!("bench-{tag}-{name}"),
            side,
            kind,
            parent: None,
            env_steps: 0,
            curriculum_stage: 0,
            checkpoint: None,
        };
        let c = store.add_player(&mk("captors", Side::Captors, Kind::Learner))?;
        let t = store.add_player(&mk("target", Side::Target, Kind::Heuristic))?;
        let until = Instant::now() + Duration::from_secs_f64(seconds);
        let results: Vec<Result<Vec<f64>>> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..n)
                .map(|w| {
                    let (url, tag) = (url.clone(), tag.clone());
                    scope.spawn(move || write_matches(&url, &tag, w, (c, t), until))
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        let mut all = Vec::new();
        for r in results {
            all.extend(r?);
        }
        if all.is_empty() {
            bail!("--seconds {seconds}: no write finished in that time; give the writers longer");
        }
        all.sort_by(|a, b| a.total_cmp(b));
        let q = |p: f64| all[((all.len() - 1) as f64 * p).round() as usize];
        println!(
            "| {} | {n} | {} | {:.0} | {:.2} | {:.2} |",
            match base {
                StoreUrl::Sqlite(_) => "SQLite (WAL)",
                StoreUrl::Postgres(_) => "PostgreSQL",
            },
            all.len(),
            all.len() as f64 / seconds,
            q(0.5),
            q(0.99)
        );
        drop(store);
        std::fs::remove_dir_all(&tmp).ok();
    }
    Ok(())
}

/// One writer's loop, on its own connection as a league process has;
/// returns each write's latency in ms. Apart from `run` because it is what
/// each thread runs.
fn write_matches(
    url: &StoreUrl,
    tag: &str,
    w: usize,
    (c, t): (i64, i64),
    until: Instant,
) -> Result<Vec<f64>> {
    let store = Store::open_existing(url)?;
    let mut lat = Vec::new();
    let mut i = 0u64;
    while Instant::now() < until {
        let m = MatchRecord {
            key: format!("bench/{tag}/{w}/{i}"),
            captor_player: c,
            target_player: t,
            map: "bench".into(),
            num_captors: 3,
            speed_ratio: 1.0,
            seed: i,
            captured: i.is_multiple_of(2),
            steps: 100,
            final_asz_m2: Some(1.0),
            recorded_by: format!("bench-{w}"),
        };
        let at = Instant::now();
        store.record_match(&m)?;
        lat.push(at.elapsed().as_secs_f64() * 1e3);
        i += 1;
    }
    Ok(lat)
}

fn tempfile_dir() -> Result<std::path::PathBuf> {
    let dir = std::env::temp_dir().join(format!(
        "t2e-bench-store-{}-{}",
        std::process::id(),
        league::store::now_ms()
    ));
    std::fs::create_dir_all(&dir)?;
    Ok(dir)
}
