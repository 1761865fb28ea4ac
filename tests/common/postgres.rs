//! A real PostgreSQL server for the tests, started by the project's own
//! `scripts/postgres.sh` (no mock store): one cluster per test binary under
//! `target/pg-test/NAME`, a fresh database per test. `scripts/test.sh`
//! stops the clusters when the tests end.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The folder of the cluster `name` (its data, port, password, logs).
pub fn cluster_dir(name: &str) -> PathBuf {
    repo().join("target").join("pg-test").join(name)
}

/// Starts (or finds running) the cluster `name`; returns its URL.
pub fn start_cluster(name: &str) -> String {
    let out = Command::new(repo().join("scripts/postgres.sh"))
        .arg("start")
        .arg(cluster_dir(name))
        .output()
        .expect("cannot run scripts/postgres.sh");
    assert!(
        out.status.success(),
        "scripts/postgres.sh start failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .last()
        .expect("scripts/postgres.sh printed no URL")
        .trim()
        .to_string()
}

pub fn stop_cluster(name: &str) {
    let out = Command::new(repo().join("scripts/postgres.sh"))
        .arg("stop")
        .arg(cluster_dir(name))
        .output()
        .expect("cannot run scripts/postgres.sh");
    assert!(
        out.status.success(),
        "scripts/postgres.sh stop failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The shared cluster of this test binary.
pub fn server() -> &'static str {
    static URL: OnceLock<String> = OnceLock::new();
    URL.get_or_init(|| start_cluster("shared"))
}

fn psql() -> String {
    for d in std::fs::read_dir("/usr/lib/postgresql")
        .into_iter()
        .flatten()
        .flatten()
    {
        let p = d.path().join("bin/psql");
        if p.exists() {
            return p.display().to_string();
        }
    }
    "psql".into()
}

/// A URL with its database replaced.
pub fn with_database(url: &str, db: &str) -> String {
    let (base, _) = url.rsplit_once('/').unwrap();
    format!("{base}/{db}")
}

/// A new, empty database on `server_url`'s server; returns its URL.
pub fn fresh_database(server_url: &str, tag: &str) -> String {
    static N: AtomicUsize = AtomicUsize::new(0);
    let db = format!(
        "t2e_{tag}_{}_{}",
        std::process::id(),
        N.fetch_add(1, Ordering::SeqCst)
    );
    let out = Command::new(psql())
        .arg(with_database(server_url, "postgres"))
        .arg("-qc")
        .arg(format!("CREATE DATABASE {db}"))
        .output()
        .expect("cannot run psql");
    assert!(
        out.status.success(),
        "CREATE DATABASE {db}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    with_database(server_url, &db)
}

/// Runs SQL against a database (for tests that tamper with a store).
pub fn sql(url: &str, statement: &str) -> String {
    let out = Command::new(psql())
        .arg(url)
        .arg("-tAc")
        .arg(statement)
        .output()
        .expect("cannot run psql");
    assert!(
        out.status.success(),
        "{statement}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}
