//! Where a league's store lives, read from `--store`: a SQLite file (the
//! embedded default, `league.db` in the league directory) or a PostgreSQL
//! database shared by workers on many hosts.
//!
//! A PostgreSQL URL carries credentials, so it is never printed as given:
//! `StoreUrl`'s `Display` masks the password, and every error and log line
//! goes through it.

use std::fmt;
use std::path::{Path, PathBuf};

/// Which database speaks for the store.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    Sqlite,
    Postgres,
}

/// A store's location.
#[derive(Clone, PartialEq, Eq)]
pub enum StoreUrl {
    /// A SQLite database file.
    Sqlite(PathBuf),
    /// A PostgreSQL connection URL, credentials included (never shown).
    Postgres(String),
}

/// A `--store` value that names no store this program can open: the
/// value as shown (its password masked; empty where it says nothing) and
/// why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StoreUrlError {
    pub shown: String,
    pub why: String,
}

impl std::fmt::Display for StoreUrlError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.shown.is_empty() {
            write!(f, "--store: {}", self.why)
        } else {
            write!(f, "--store {}: {}", self.shown, self.why)
        }
    }
}

impl std::error::Error for StoreUrlError {}

fn refused(shown: &str, why: impl Into<String>) -> StoreUrlError {
    StoreUrlError {
        shown: shown.to_string(),
        why: why.into(),
    }
}

impl StoreUrl {
    /// The embedded default: `league.db` in the league directory.
    pub fn in_dir(league_dir: &Path) -> StoreUrl {
        StoreUrl::Sqlite(league_dir.join("league.db"))
    }

    /// Reads `--store`: `postgres://` or `postgresql://` selects PostgreSQL;
    /// `sqlite:` or a plain path selects SQLite. A URL of another scheme is
    /// refused rather than taken for a file name.
    pub fn parse(text: &str) -> Result<StoreUrl, StoreUrlError> {
        let text = text.trim();
        if text.is_empty() {
            return Err(refused(
                "",
                "empty; give postgres://USER@HOST:PORT/DB or a SQLite file",
            ));
        }
        let lower = text.to_ascii_lowercase();
        if lower.starts_with("postgres://") || lower.starts_with("postgresql://") {
            check_postgres(text)?;
            return Ok(StoreUrl::Postgres(text.to_string()));
        }
        if let Some(rest) = text
            .strip_prefix("sqlite://")
            .or_else(|| text.strip_prefix("sqlite:"))
        {
            if rest.is_empty() || rest.contains('?') {
                return Err(refused(
                    text,
                    "give the SQLite file's path after sqlite: (options are the store's own)",
                ));
            }
            return Ok(StoreUrl::Sqlite(PathBuf::from(rest)));
        }
        if let Some((scheme, _)) = text.split_once("://") {
            return Err(refused(
                "",
                format!("unknown scheme {scheme}:// (postgres:// for PostgreSQL, sqlite: or a path for SQLite)"),
            ));
        }
        Ok(StoreUrl::Sqlite(PathBuf::from(text)))
    }

    pub fn backend(&self) -> Backend {
        match self {
            StoreUrl::Sqlite(_) => Backend::Sqlite,
            StoreUrl::Postgres(_) => Backend::Postgres,
        }
    }

    /// The URL with its password: for connecting, or for handing to a
    /// child process in its environment. Never print it.
    pub fn secret(&self) -> &str {
        match self {
            StoreUrl::Postgres(url) => url,
            StoreUrl::Sqlite(_) => "",
        }
    }
}

/// A PostgreSQL URL names one database, and nothing after it: a stray path
/// (`/db/extra`) would otherwise be read as a database called `db/extra`.
fn check_postgres(url: &str) -> Result<(), StoreUrlError> {
    let shown = mask(url);
    let after_scheme = url.split_once("://").map(|x| x.1).unwrap_or("");
    let without_query = after_scheme.split('?').next().unwrap_or("");
    let (authority, path) = match without_query.split_once('/') {
        Some((a, p)) => (a, p),
        None => (without_query, ""),
    };
    let host = authority.rsplit('@').next().unwrap_or("");
    if host.is_empty() && !url.contains("host=") {
        return Err(refused(&shown, "names no host"));
    }
    if path.contains('/') {
        return Err(refused(
            &shown,
            format!("a stray path after the database name ({path}); the URL names one database: postgres://USER@HOST:PORT/DB"),
        ));
    }
    if let Some(port) = host.rsplit_once(':').map(|x| x.1) {
        if !port.is_empty() && port.parse::<u16>().is_err() {
            return Err(refused(&shown, format!("port {port} is not a port number")));
        }
    }
    Ok(())
}

/// A URL with its password replaced by `***`: `postgres://u:***@h/db`.
/// Passwords in the query (`?password=`) are masked too.
pub fn mask(url: &str) -> String {
    let Some((scheme, rest)) = url.split_once("://") else {
        return url.to_string();
    };
    let (main, query) = match rest.split_once('?') {
        Some((m, q)) => (m, Some(q)),
        None => (rest, None),
    };
    let (authority, path) = match main.split_once('/') {
        Some((a, p)) => (a, Some(p)),
        None => (main, None),
    };
    let authority = match authority.rsplit_once('@') {
        Some((userinfo, host)) => match userinfo.split_once(':') {
            Some((user, _)) => format!("{user}:***@{host}"),
            None => format!("{userinfo}@{host}"),
        },
        None => authority.to_string(),
    };
    let mut out = format!("{scheme}://{authority}");
    if let Some(p) = path {
        out.push('/');
        out.push_str(p);
    }
    if let Some(q) = query {
        let masked: Vec<String> = q
            .split('&')
            .map(|kv| match kv.split_once('=') {
                Some((k, _)) if k.eq_ignore_ascii_case("password") => format!("{k}=***"),
                _ => kv.to_string(),
            })
            .collect();
        out.push('?');
        out.push_str(&masked.join("&"));
    }
    out
}

impl fmt::Display for StoreUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            StoreUrl::Sqlite(path) => write!(f, "{}", path.display()),
            StoreUrl::Postgres(url) => write!(f, "{}", mask(url)),
        }
    }
}

impl fmt::Debug for StoreUrl {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "StoreUrl({self})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passwords_never_show() {
        assert_eq!(
            mask("postgres://league:s3cret@db.lab:5432/t2e"),
            "postgres://league:***@db.lab:5432/t2e"
        );
        assert_eq!(
            mask("postgresql://league@db/t2e?password=s3cret&sslmode=require"),
            "postgresql://league@db/t2e?password=***&sslmode=require"
        );
        let url = StoreUrl::parse("postgres://u:p%40ss@h:1/d").unwrap();
        assert!(!format!("{url} {url:?}").contains("p%40ss"));
    }

    #[test]
    fn the_backend_comes_from_the_url() {
        assert_eq!(
            StoreUrl::parse("postgres://u@h:5432/d").unwrap().backend(),
            Backend::Postgres
        );
        assert_eq!(
            StoreUrl::parse("sqlite:/tmp/x/league.db").unwrap(),
            StoreUrl::Sqlite("/tmp/x/league.db".into())
        );
        assert_eq!(
            StoreUrl::parse("runs/l/league.db").unwrap(),
            StoreUrl::Sqlite("runs/l/league.db".into())
        );
    }

    #[test]
    fn malformed_urls_are_refused_with_the_reason() {
        let e = StoreUrl::parse("postgres://u:pw@h:5432/db/extra")
            .unwrap_err()
            .to_string();
        assert!(e.contains("stray path") && !e.contains("pw@"), "{e}");
        assert!(StoreUrl::parse("mysql://h/db")
            .unwrap_err()
            .to_string()
            .contains("unknown scheme"));
        assert!(StoreUrl::parse("postgres://u@h:port/db")
            .unwrap_err()
            .to_string()
            .contains("not a port"));
        assert!(StoreUrl::parse("postgres:///db")
            .unwrap_err()
            .to_string()
            .contains("no host"));
        assert!(StoreUrl::parse("").is_err());
    }
}
