//! The league's processes as the manager and the workers start them: the
//! roles a seat can hold, spawning one as a child of this binary, the locks
//! that keep a seat from running twice on a host, and their logs.

use super::dir::LeagueDir;
use super::players::{Seat, EVALUATOR};
use super::store::StoreUrl;
use crate::env::Side;
use anyhow::{Context, Result};
use std::fs::{File, TryLockError};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::Instant;

/// An exclusive lock on `path`, held while the file stays open and released
/// by the kernel when the process dies, however it dies. None if another
/// live process holds it.
pub fn try_lock(path: &Path) -> Result<Option<File>> {
    use std::io::Write;
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .read(true)
        .open(path)
        .with_context(|| format!("cannot open {}", path.display()))?;
    match f.try_lock() {
        Ok(()) => {}
        Err(TryLockError::WouldBlock) => return Ok(None),
        Err(TryLockError::Error(e)) => {
            return Err(e).with_context(|| format!("cannot lock {}", path.display()))
        }
    }
    f.set_len(0)?;
    writeln!(f, "{}", std::process::id())?;
    Ok(Some(f))
}

/// The pid written in a lock file, for messages.
pub fn lock_holder(path: &Path) -> String {
    std::fs::read_to_string(path)
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

/// What a seat runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    Learner(Seat),
    Evaluator,
}

impl Role {
    /// The seat's name (`captors-main`, `target-exploiter`, `evaluator`).
    pub fn name(self) -> String {
        match self {
            Role::Learner(seat) => seat.name(),
            Role::Evaluator => EVALUATOR.into(),
        }
    }

    /// The role a seat name stands for.
    pub fn from_name(name: &str) -> Option<Role> {
        if name == EVALUATOR {
            return Some(Role::Evaluator);
        }
        [Side::Captors, Side::Target]
            .into_iter()
            .flat_map(|side| [Seat::main(side), Seat::exploiter(side)])
            .find(|seat| seat.name() == name)
            .map(Role::Learner)
    }

    pub fn log_path(self, logs: &Path) -> PathBuf {
        logs.join(format!("{}.log", self.name()))
    }
}

/// A child process its parent (the manager, a worker) supervises.
pub struct Supervised {
    pub role: Role,
    pub child: Option<Child>,
    /// Finished: done, or stopped when the manager asked.
    pub finished: bool,
    pub restart_at: Option<Instant>,
    pub failures: u32,
    pub started: Instant,
    /// Length of its log when it started: what it printed since is its own.
    pub log_offset: u64,
    /// Its crashes: (at ms, cause), for the crash budget.
    pub crashes: Vec<(i64, String)>,
}

impl Supervised {
    /// A process to start now.
    pub fn new(role: Role) -> Supervised {
        Supervised {
            role,
            child: None,
            finished: false,
            restart_at: Some(Instant::now()),
            failures: 0,
            started: Instant::now(),
            log_offset: 0,
            crashes: Vec::new(),
        }
    }
}

/// Asks a child to stop (SIGINT): it finishes its iteration and checkpoints.
pub fn interrupt(child: &Child) {
    // SAFETY: signalling our own child by pid.
    unsafe {
        libc::kill(child.id() as i32, libc::SIGINT);
    }
}

/// The child dies with its parent (Linux `PR_SET_PDEATHSIG`): a manager or
/// worker killed with -9 leaves nothing running.
pub fn die_with_parent(cmd: &mut Command) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: prctl is async-signal-safe.
        unsafe {
            cmd.pre_exec(|| {
                libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
                Ok(())
            });
        }
    }
}

/// Starts `role` for the league in `dir` as a child process, its output
/// appended to its log in `logs`. A PostgreSQL store's URL reaches the child
/// in its environment (`T2E_STORE`), never on its command line, where any
/// user of the host could read the password.
pub fn spawn(dir: &LeagueDir, role: Role, logs: &Path, host: Option<&str>) -> Result<Child> {
    std::fs::create_dir_all(logs).with_context(|| format!("cannot create {}", logs.display()))?;
    let log = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(role.log_path(logs))?;
    let mut cmd =
        crate::util::own_command().context("cannot find this program to spawn learners")?;
    match role {
        Role::Learner(seat) => {
            cmd.arg("league-learner")
                .arg("--side")
                .arg(seat.side.name());
            if seat.exploiter {
                cmd.arg("--exploiter");
            }
        }
        Role::Evaluator => {
            cmd.arg("league-evaluator");
        }
    };
    // Any store but the default league.db in the pool folder reaches the
    // child, or a worker's learner would look for one there and refuse.
    match &dir.store {
        StoreUrl::Postgres(_) => {
            cmd.env("T2E_STORE", dir.store.secret());
        }
        StoreUrl::Sqlite(path) if dir.store != StoreUrl::in_dir(&dir.root) => {
            cmd.env("T2E_STORE", path);
        }
        StoreUrl::Sqlite(_) => {}
    }
    if let Some(h) = host {
        cmd.env("T2E_HOST", h);
    }
    cmd.arg("--dir")
        .arg(&dir.root)
        .stdin(Stdio::null())
        .stdout(log.try_clone()?)
        .stderr(log);
    die_with_parent(&mut cmd);
    cmd.spawn()
        .with_context(|| format!("cannot start the {}", role.name()))
}

/// What a log holds from byte `offset` on.
pub fn log_since(path: &Path, offset: u64) -> String {
    use std::io::{Read, Seek, SeekFrom};
    let mut text = String::new();
    if let Ok(mut f) = File::open(path) {
        if f.seek(SeekFrom::Start(offset)).is_ok() {
            let _ = f.read_to_string(&mut text);
        }
    }
    text
}

/// The last lines of a text, for the crash record.
pub fn tail(text: &str, n: usize) -> String {
    let lines: Vec<&str> = text.lines().rev().take(n).collect();
    lines.into_iter().rev().collect::<Vec<_>>().join("\n")
}

/// The league directory a league process (learner, evaluator) works in:
/// its store from `T2E_STORE` when a worker gave one, else `league.db` in it.
pub fn dir_from_env(root: &Path) -> Result<LeagueDir> {
    match std::env::var("T2E_STORE") {
        Ok(url) if !url.is_empty() => {
            let store = StoreUrl::parse(&url).map_err(anyhow::Error::msg)?;
            Ok(LeagueDir::with_store(root, store))
        }
        _ => Ok(LeagueDir::new(root)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seat_names_name_their_roles() {
        for role in [
            Role::Evaluator,
            Role::Learner(Seat::main(Side::Captors)),
            Role::Learner(Seat::exploiter(Side::Target)),
        ] {
            assert_eq!(Role::from_name(&role.name()), Some(role));
        }
        assert_eq!(Role::from_name("captors-mian"), None);
    }

    #[test]
    fn a_lock_is_exclusive_while_held() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("x.lock");
        let held = try_lock(&path).unwrap().unwrap();
        // flock locks belong to open file descriptions: a second open in
        // this process conflicts as another process's would.
        assert!(try_lock(&path).unwrap().is_none());
        drop(held);
        assert!(try_lock(&path).unwrap().is_some());
    }
}
