//! The store's connection: the `Store` handle (its pool, its runtime, the
//! retry of every write), its errors, and opening a league's database
//! (presence, migrations). Each table's module adds its methods to `Store`.

use super::url::{Backend, StoreUrl};
use sqlx::any::AnyPoolOptions;
use sqlx::AnyPool;
use sqlx::{Executor, Row};
use std::future::Future;
use std::path::Path;
use std::time::{Duration, Instant};

/// Why no query binds an `Option<f64>`: sqlx 0.8's Any driver sends a NULL
/// f64 to PostgreSQL as a float4 (its Real and Double are swapped in
/// `AnyArguments::convert_to`), so a statement first prepared with a NULL
/// there (and cached per connection) refuses every later float with
/// "incorrect binary data format". Optional floats are bound as a value and
/// a 0/1 flag instead; tests/integration/store.rs binds NULL first to keep it honest.
#[allow(dead_code)]
const NO_NULL_FLOATS: () = ();

static SQLITE_MIGRATIONS: sqlx::migrate::Migrator = sqlx::migrate!("migrations/sqlite");
static POSTGRES_MIGRATIONS: sqlx::migrate::Migrator = sqlx::migrate!("migrations/postgres");

/// One transaction: the writes that must land together (a match and both
/// players' rating updates; an exploit and its result) take it, each from
/// its own table's module, and it commits or rolls back whole.
pub(crate) struct Tx<'c>(sqlx::Transaction<'c, sqlx::Any>);

impl<'c> Tx<'c> {
    pub(crate) async fn begin(pool: &'c AnyPool) -> Result<Tx<'c>, sqlx::Error> {
        pool.begin().await.map(Tx)
    }

    /// The connection the transaction's statements run on.
    pub(crate) fn conn(&mut self) -> &mut sqlx::AnyConnection {
        &mut self.0
    }

    pub(crate) async fn commit(self) -> Result<(), sqlx::Error> {
        self.0.commit().await
    }

    pub(crate) async fn rollback(self) -> Result<(), sqlx::Error> {
        self.0.rollback().await
    }
}

#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("{store}: written by a newer t2e-league (schema migration {version} is unknown to this build); use a newer build to open it")]
    NewerSchema { store: String, version: i64 },
    #[error("{store}: {source}")]
    Database {
        store: String,
        #[source]
        source: sqlx::Error,
    },
    #[error("{store}: cannot connect: {why}")]
    Connect { store: String, why: String },
    #[error("{store}: migrating the schema failed: {source}")]
    Migrate {
        store: String,
        #[source]
        source: sqlx::migrate::MigrateError,
    },
    #[error("{0}")]
    Invalid(String),
}

/// An integer column that holds a count or a seed: stored as BIGINT (both
/// backends' integer), read back as u64, a negative value refused as
/// corrupt rather than wrapped.
pub(crate) fn u64_column(r: &sqlx::any::AnyRow, col: &str) -> Result<u64, sqlx::Error> {
    use sqlx::Row;
    let v: i64 = r.try_get(col)?;
    u64::try_from(v).map_err(|e| sqlx::Error::ColumnDecode {
        index: col.into(),
        source: Box::new(e),
    })
}

pub fn now_ms() -> i64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

/// Every table the migrations create (`tables_are_those_the_migrations_create`).
pub(super) const TABLES: [&str; 11] = [
    "crashes",
    "curriculum",
    "exploits",
    "heartbeats",
    "held_out_episodes",
    "league_config",
    "manager_lease",
    "matches",
    "players",
    "ratings",
    "seats",
];

/// How a process opens the store.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Access {
    Create,
    Existing,
    ReadOnly { immutable: bool },
}

/// A SQLite `league.db` that is missing or empty is not a store.
fn check_present(path: &Path) -> Result<(), StoreError> {
    match std::fs::metadata(path) {
        Ok(m) if m.len() > 0 => Ok(()),
        // SQLite creates the file empty and then writes its tables: a store
        // made in the last minute is most likely a league starting now.
        Ok(m) if m
            .modified()
            .ok()
            .and_then(|t| t.elapsed().ok())
            .is_some_and(|age| age < std::time::Duration::from_secs(60)) =>
        {
            Err(StoreError::Invalid(format!(
                "{}: empty (0 bytes) and created under a minute ago: a league is probably starting there; try again in a moment",
                path.display()
            )))
        }
        Ok(_) => Err(StoreError::Invalid(format!(
            "{}: empty (0 bytes): the league's store was truncated",
            path.display()
        ))),
        Err(_) => Err(StoreError::Invalid(format!(
            "{}: missing: the directory holds no league store",
            path.display()
        ))),
    }
}

/// What a store location holds, read without creating anything.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Presence {
    /// No store there (no file; a database without the league's tables).
    Missing,
    /// A SQLite file of 0 bytes.
    Empty,
    /// Something to open and check.
    Present,
}

/// This machine's name, for heartbeats and leases: `T2E_HOST` when a
/// worker was started with `--host`, else the kernel's hostname.
/// Read once per process: every heartbeat records it.
pub fn host_name() -> String {
    static HOST: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    HOST.get_or_init(|| {
        if let Ok(h) = std::env::var("T2E_HOST") {
            if !h.trim().is_empty() {
                return h.trim().to_string();
            }
        }
        std::fs::read_to_string("/proc/sys/kernel/hostname")
            .map(|s| s.trim().to_string())
            .ok()
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| "localhost".into())
    })
    .clone()
}

/// A database error that a later try can get past: the server is gone for
/// a moment (restarting, unreachable), not a query that is wrong.
fn transient(e: &sqlx::Error) -> bool {
    match e {
        sqlx::Error::Io(_) | sqlx::Error::PoolTimedOut | sqlx::Error::Tls(_) => true,
        sqlx::Error::Database(d) => d.code().is_some_and(|c| transient_code(&c)),
        _ => false,
    }
}

/// A database error code that a later try of the same operation can get
/// past.
pub(super) fn transient_code(code: &str) -> bool {
    // PostgreSQL (five-character SQLSTATEs): connection exceptions (08),
    // the server shutting down or starting (57P01-57P03), too many
    // connections (53300).
    code.starts_with("08")
        || matches!(code, "57P01" | "57P02" | "57P03" | "53300")
        // SQLite (numbers): SQLITE_BUSY and SQLITE_LOCKED with their
        // extended codes. The busy timeout waits out most of them, but a
        // transaction that read before another process wrote must start
        // again (SQLITE_BUSY_SNAPSHOT, 517): SQLite answers it at once.
        || matches!(code, "5" | "6" | "261" | "262" | "517" | "773")
}

/// How long a process keeps retrying a store that went away before it
/// gives up: a PostgreSQL restart or failover takes seconds to a minute.
fn retry_budget() -> Duration {
    std::env::var("T2E_STORE_RETRY_S")
        .ok()
        .and_then(|s| s.parse::<u64>().ok())
        .map(Duration::from_secs)
        .unwrap_or(Duration::from_secs(300))
}

pub struct Store {
    pub(super) rt: tokio::runtime::Runtime,
    pub(super) pool: AnyPool,
    pub(super) url: StoreUrl,
}

impl Store {
    /// Opens (creating if needed) a league's store and brings its schema up
    /// to date. Only a league being started creates its store; every other
    /// process opens it with `open_existing`.
    pub fn open(url: &StoreUrl) -> Result<Store, StoreError> {
        if let StoreUrl::Sqlite(path) = url {
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir).map_err(|e| {
                    StoreError::Invalid(format!("cannot create {}: {e}", dir.display()))
                })?;
            }
        }
        Store::connect(url, Access::Create)
    }

    /// Opens a store that exists, refusing a missing or empty SQLite file
    /// (SQLite would take either for a new database).
    pub fn open_existing(url: &StoreUrl) -> Result<Store, StoreError> {
        if let StoreUrl::Sqlite(path) = url {
            check_present(path)?;
        }
        Store::connect(url, Access::Existing)
    }

    /// What `url` holds, creating nothing: a SQLite file's size, or whether
    /// a PostgreSQL database has the league's tables.
    pub fn presence(url: &StoreUrl) -> Result<Presence, StoreError> {
        match url {
            StoreUrl::Sqlite(path) => Ok(match std::fs::metadata(path) {
                Err(_) => Presence::Missing,
                Ok(m) if m.len() == 0 => Presence::Empty,
                Ok(_) => Presence::Present,
            }),
            StoreUrl::Postgres(_) => {
                let store = Store::connect(url, Access::ReadOnly { immutable: false })?;
                let pool = &store.pool;
                let n: i64 = store.run(move || async move {
                    sqlx::query(
                        "SELECT COUNT(*) AS n FROM information_schema.tables WHERE table_schema = current_schema() AND table_name = '_sqlx_migrations'",
                    )
                    .fetch_one(pool)
                    .await?
                    .try_get("n")
                })?;
                Ok(if n > 0 {
                    Presence::Present
                } else {
                    Presence::Missing
                })
            }
        }
    }

    fn migrator(&self) -> &'static sqlx::migrate::Migrator {
        match self.url.backend() {
            Backend::Sqlite => &SQLITE_MIGRATIONS,
            Backend::Postgres => &POSTGRES_MIGRATIONS,
        }
    }

    /// Opens a league's store for reading only (`status`, `export`): nothing
    /// is created or changed, so it works on a read-only copy. The schema
    /// is not migrated; an older one is refused with the command that
    /// migrates it.
    pub fn open_read_only(url: &StoreUrl) -> Result<Store, StoreError> {
        let store = Store::inspect(url)?;
        let pool = &store.pool;
        let read_applied = || -> Result<Vec<i64>, StoreError> {
            store.run(move || async move {
                let rows = sqlx::query("SELECT version FROM _sqlx_migrations WHERE success = TRUE")
                    .fetch_all(pool)
                    .await?;
                rows.iter().map(|r| r.try_get::<i64, _>(0)).collect()
            })
        };
        let all_applied = |applied: &[i64]| {
            store
                .migrator()
                .iter()
                .all(|m| applied.contains(&m.version))
        };
        let mut applied = read_applied()?;
        // A store a league is creating this moment holds its first
        // migrations and not yet the rest: wait for the migrator before
        // calling the schema older (a `status` poll as the league starts).
        let deadline = Instant::now() + Duration::from_secs(10);
        while !all_applied(&applied) && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(250));
            applied = read_applied()?;
        }
        for m in store.migrator().iter() {
            if !applied.contains(&m.version) {
                return Err(StoreError::Invalid(format!(
                    "{url}: written by an older t2e-league (schema migration {} missing); `t2e-league run` on this league migrates it",
                    m.version,
                )));
            }
        }
        if let Some(v) = applied
            .iter()
            .find(|v| !store.migrator().iter().any(|m| m.version == **v))
        {
            return Err(StoreError::NewerSchema {
                store: url.to_string(),
                version: *v,
            });
        }
        Ok(store)
    }

    /// Opens a store read-only whatever its schema version, to check what
    /// it holds before anything is written (a file that is not a league's
    /// store is refused untouched).
    pub fn inspect(url: &StoreUrl) -> Result<Store, StoreError> {
        let probe = |store: &Store| {
            let pool = &store.pool;
            store.run(move || async move {
                sqlx::query("SELECT COUNT(*) FROM league_config")
                    .fetch_one(pool)
                    .await
                    .map(|_| ())
            })
        };
        let path = match url {
            StoreUrl::Postgres(_) => {
                let store = Store::connect(url, Access::ReadOnly { immutable: false })?;
                probe(&store).map_err(|e| {
                    StoreError::Invalid(format!(
                        "{url}: holds no league store, or not one this build reads ({e})"
                    ))
                })?;
                return Ok(store);
            }
            StoreUrl::Sqlite(path) => path,
        };
        check_present(path)?;
        let normal = Store::connect(url, Access::ReadOnly { immutable: false })
            .and_then(|s| probe(&s).map(|()| s));
        let store = match normal {
            Ok(s) => s,
            Err(first) => {
                // A WAL database whose -shm file is absent and cannot be
                // created (a read-only directory) opens only as immutable,
                // which ignores the write-ahead log: refuse rather than read
                // a stale store when the log holds changes.
                let mut wal = path.as_os_str().to_owned();
                wal.push("-wal");
                let wal = std::path::PathBuf::from(wal);
                if std::fs::metadata(&wal).is_ok_and(|m| m.len() > 0) {
                    return Err(StoreError::Invalid(format!(
                        "{}: cannot be read here ({first}); its write-ahead log {} holds changes not yet in it, which only a process that can write the directory can read",
                        path.display(),
                        wal.display()
                    )));
                }
                let s = Store::connect(url, Access::ReadOnly { immutable: true })?;
                probe(&s).map_err(|e| {
                    StoreError::Invalid(format!(
                        "{}: not a league store, or not readable as one ({e}); restore it from a backup",
                        path.display()
                    ))
                })?;
                s
            }
        };
        Ok(store)
    }

    // Long on purpose: open, check the schema's version, migrate and register, one sequence per backend whose order is the store's contract.
    fn connect(url: &StoreUrl, access: Access) -> Result<Store, StoreError> {
        sqlx::any::install_default_drivers();
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_time()
            .enable_io()
            .build()
            .map_err(|e| StoreError::Invalid(format!("cannot start the store's runtime: {e}")))?;
        let shown = url.to_string();
        let connect_error = |source: sqlx::Error| StoreError::Connect {
            store: shown.clone(),
            why: explain_connect(&source),
        };
        let pool = match url {
            StoreUrl::Sqlite(path) => {
                let mut options = sqlx::sqlite::SqliteConnectOptions::new()
                    .filename(path)
                    .foreign_keys(true);
                options = match access {
                    Access::Create | Access::Existing => {
                        options.create_if_missing(access == Access::Create)
                    }
                    Access::ReadOnly { immutable } => options.read_only(true).immutable(immutable),
                };
                let any: sqlx::any::AnyConnectOptions =
                    sqlx::ConnectOptions::to_url_lossy(&options)
                        .as_str()
                        .parse()
                        .map_err(connect_error)?;
                let writable = matches!(access, Access::Create | Access::Existing);
                rt.block_on(
                    AnyPoolOptions::new()
                        .max_connections(1)
                        .after_connect(move |conn, _| {
                            Box::pin(async move {
                                conn.execute("PRAGMA busy_timeout = 30000").await?;
                                conn.execute("PRAGMA foreign_keys = ON").await?;
                                if writable {
                                    conn.execute("PRAGMA journal_mode = WAL").await?;
                                }
                                Ok(())
                            })
                        })
                        .connect_with(any),
                )
                .map_err(|source| StoreError::Database {
                    store: shown.clone(),
                    source,
                })?
            }
            StoreUrl::Postgres(_) => {
                let any: sqlx::any::AnyConnectOptions =
                    url.secret().parse().map_err(connect_error)?;
                let read_only = matches!(access, Access::ReadOnly { .. });
                // One plain connection first: the pool retries a refused
                // connection until its timeout and then reports only that,
                // where this gives the cause (refused, password, database).
                let probe = rt
                    .block_on(<sqlx::AnyConnection as sqlx::Connection>::connect_with(
                        &any,
                    ))
                    .map_err(connect_error)?;
                rt.block_on(sqlx::Connection::close(probe)).ok();
                rt.block_on(
                    AnyPoolOptions::new()
                        .max_connections(2)
                        .acquire_timeout(Duration::from_secs(10))
                        .after_connect(move |conn, _| {
                            Box::pin(async move {
                                if read_only {
                                    conn.execute("SET default_transaction_read_only = on")
                                        .await?;
                                }
                                Ok(())
                            })
                        })
                        .connect_with(any),
                )
                .map_err(connect_error)?
            }
        };
        let store = Store {
            rt,
            pool,
            url: url.clone(),
        };
        if matches!(access, Access::Create | Access::Existing) {
            match store.migrate() {
                Ok(()) => {}
                Err(sqlx::migrate::MigrateError::VersionMissing(version)) => {
                    return Err(StoreError::NewerSchema {
                        store: shown,
                        version,
                    })
                }
                Err(source) => {
                    return Err(StoreError::Migrate {
                        store: shown,
                        source,
                    })
                }
            }
            store.check_tables()?;
        }
        Ok(store)
    }

    /// Every table the migrations create is there. A migration recorded as
    /// applied is never run again, so a table dropped since (by hand, or a
    /// file restored in part) would otherwise surface as some later query's
    /// error, or as a league that resumes and finds nothing to do.
    fn check_tables(&self) -> Result<(), StoreError> {
        let pool = &self.pool;
        let query = match self.backend() {
            Backend::Sqlite => "SELECT name FROM sqlite_master WHERE type = 'table'",
            Backend::Postgres => {
                "SELECT CAST(table_name AS TEXT) AS name FROM information_schema.tables WHERE table_schema = current_schema()"
            }
        };
        let names: Vec<String> = self
            .run(move || async move {
                sqlx::query(query)
                    .fetch_all(pool)
                    .await?
                    .iter()
                    .map(|row| row.try_get::<String, _>("name"))
                    .collect::<Result<Vec<String>, sqlx::Error>>()
            })
            .map_err(|e| {
                StoreError::Invalid(format!("{}: cannot list its tables: {e}", self.url))
            })?;
        let missing: Vec<&str> = TABLES
            .iter()
            .copied()
            .filter(|t| !names.iter().any(|n| n == t))
            .collect();
        if !missing.is_empty() {
            return Err(StoreError::Invalid(format!(
                "{}: the league's store has no table {}: it was damaged (a table dropped, or the file restored in part); restore the store from a copy",
                self.url,
                missing.join(", ")
            )));
        }
        Ok(())
    }

    /// Brings the schema up to date. PostgreSQL serialises migrators with
    /// an advisory lock; SQLite has none, so two processes opening a new
    /// league at once (a worker joining, `status` polling) may both try
    /// the same migration, and the second fails on what the first just
    /// added. Each migration is one transaction, so the loser rolled back
    /// whole: running again finds it applied and goes on.
    fn migrate(&self) -> Result<(), sqlx::migrate::MigrateError> {
        let mut attempt = 0;
        loop {
            match self.rt.block_on(self.migrator().run(&self.pool)) {
                Err(e)
                    if attempt < 5
                        && self.backend() == Backend::Sqlite
                        && !matches!(e, sqlx::migrate::MigrateError::VersionMissing(_)) =>
                {
                    attempt += 1;
                    std::thread::sleep(Duration::from_millis(100 * attempt));
                }
                done => return done,
            }
        }
    }

    /// Where the store is (a PostgreSQL URL with its password masked).
    pub fn url(&self) -> &StoreUrl {
        &self.url
    }

    pub fn backend(&self) -> Backend {
        self.url.backend()
    }

    /// Runs one database operation to its end: a connection that fails
    /// (the server restarting, a network blip) is retried with back-off
    /// for up to `T2E_STORE_RETRY_S` seconds (default 300), so a worker
    /// waits out an outage instead of crashing; any other error is
    /// returned at once. Every operation here may run twice safely (see
    /// the module's invariants).
    pub(super) fn run<T, F, Fut>(&self, mut op: F) -> Result<T, StoreError>
    where
        F: FnMut() -> Fut,
        Fut: Future<Output = Result<T, sqlx::Error>>,
    {
        let started = Instant::now();
        let mut wait = Duration::from_millis(250);
        let mut said = false;
        loop {
            match self.rt.block_on(op()) {
                Ok(v) => {
                    if said {
                        tracing::info!("{}: reachable again", self.url);
                    }
                    return Ok(v);
                }
                Err(e) if transient(&e) && started.elapsed() < retry_budget() => {
                    if !said {
                        tracing::warn!(
                            "{}: {e}; retrying with back-off for up to {} s",
                            self.url,
                            retry_budget().as_secs()
                        );
                        said = true;
                    }
                    std::thread::sleep(wait);
                    wait = (wait * 2).min(Duration::from_secs(5));
                }
                Err(source) => {
                    return Err(StoreError::Database {
                        store: self.url.to_string(),
                        source,
                    })
                }
            }
        }
    }

    pub(super) fn db(&self, source: sqlx::Error) -> StoreError {
        StoreError::Database {
            store: self.url.to_string(),
            source,
        }
    }
}

/// Why a connection failed, in words a user can act on (the URL is shown
/// by the caller, masked).
fn explain_connect(e: &sqlx::Error) -> String {
    match e {
        sqlx::Error::Database(d) => match d.code().as_deref() {
            Some("28P01") | Some("28000") => format!("{} (check the user and password in the URL or PGPASSWORD)", d.message()),
            Some("3D000") => format!("{} (create it, or name an existing database in the URL)", d.message()),
            _ => d.message().to_string(),
        },
        sqlx::Error::Io(io) => format!(
            "{io} (is the server running and listening there? `scripts/postgres.sh start DIR` starts one)"
        ),
        sqlx::Error::PoolTimedOut => "no answer within 10 s (a host that drops packets, or a server too busy to accept)".into(),
        sqlx::Error::Configuration(c) => format!("the URL is not one PostgreSQL reads: {c}"),
        other => other.to_string(),
    }
}

impl Drop for Store {
    /// Closes the connections; on SQLite the last one to close folds the
    /// write-ahead log into league.db and removes it: a league left alone
    /// is a single file that a reader without write access can open.
    fn drop(&mut self) {
        self.rt.block_on(self.pool.close());
    }
}
