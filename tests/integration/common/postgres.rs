//! A real PostgreSQL server for the tests, started by the project's own
//! `scripts/postgres.sh` (no mock store): clusters under
//! `$T2E_PG_TEST_DIR/NAME` (default /tmp/t2e-pg-test; a folder the server's
//! unprivileged user can reach), a fresh database per test.
//! `scripts/test.sh` gives each run its own folder and stops its clusters
//! when the tests end.
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
    let root = std::env::var_os("T2E_PG_TEST_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/tmp/t2e-pg-test"));
    std::fs::create_dir_all(&root).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&root, std::fs::Permissions::from_mode(0o755)).ok();
    root.join(name)
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
