//! The league's processes as the manager and the workers start them: the
//! roles a seat can hold, spawning one as a child of this binary, the locks
//! that keep a seat from running twice on a host, and their logs.

use crate::error::{LeagueError, Result, ResultExt};
pub use crate::rules::players::Role;
use crate::rules::supervision::{classify, decide, last_error_line, CrashBudget, Exit, Next};
use crate::run::folder::layout::LeagueDir;
use crate::run::processes::child::ChildCommand;
use crate::store::{now_ms, StoreUrl};
use std::collections::VecDeque;
use std::fs::{File, TryLockError};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

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
        .map_err(|e| LeagueError::process(format!("cannot open {}", path.display()), e))?;
    match f.try_lock() {
        Ok(()) => {}
        Err(TryLockError::WouldBlock) => return Ok(None),
        Err(TryLockError::Error(e)) => {
            return Err(LeagueError::process(
                format!("cannot lock {}", path.display()),
                e,
            ))
        }
    }
    f.set_len(0)
        .and_then(|()| writeln!(f, "{}", std::process::id()))
        .map_err(|e| LeagueError::process(format!("cannot write {}", path.display()), e))?;
    Ok(Some(f))
}

/// The pid written in a lock file, for messages.
pub fn lock_holder(path: &Path) -> String {
    std::fs::read_to_string(path)
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
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
    /// What it printed since it started, kept by its parent.
    pub output: Option<Output>,
    /// Its crashes: (at ms, cause), for the crash budget.
    pub crashes: Vec<(i64, String)>,
}

/// How a supervised child ended, and what its supervisor does next.
pub struct Ended {
    pub exit: Exit,
    pub next: Next,
    /// The end of what it printed, for the crash record.
    pub crash_text: String,
}

impl Supervised {
    /// Reaps the child if it has exited and decides what comes next, by
    /// the same rules for the manager and every worker (`supervision`).
    /// None while it runs, or when there is no child. `asked`: its
    /// supervisor had asked it to stop.
    pub fn reap(&mut self, asked: bool, budget: CrashBudget) -> std::io::Result<Option<Ended>> {
        use std::os::unix::process::ExitStatusExt;
        let Some(child) = &mut self.child else {
            return Ok(None);
        };
        let Some(status) = child.try_wait()? else {
            return Ok(None);
        };
        self.child = None;
        let exit = classify(status.code(), status.signal());
        let (log, crash_text) = match &self.output {
            Some(o) => {
                o.wait_closed(Duration::from_secs(2));
                (o.text(), o.crash_text(5))
            }
            None => Default::default(),
        };
        // A process that ran for two minutes before failing starts its
        // back-off over.
        if self.started.elapsed() > Duration::from_secs(120) {
            self.failures = 0;
        }
        self.failures += 1;
        let next = decide(
            &self.role.name(),
            &exit,
            last_error_line(&log).as_deref(),
            asked,
            &mut self.crashes,
            now_ms(),
            self.failures,
            budget,
        );
        Ok(Some(Ended {
            exit,
            next,
            crash_text,
        }))
    }

    /// Starts it again with `start` once its back-off has passed; nothing
    /// starts while its supervisor is stopping.
    pub fn restart_when_due(
        &mut self,
        stopping: bool,
        start: impl FnOnce(Role) -> Result<(Child, Output)>,
    ) -> Result<()> {
        if self.child.is_some() || self.finished || stopping {
            return Ok(());
        }
        if self.restart_at.is_some_and(|at| Instant::now() >= at) {
            let (child, output) = start(self.role)?;
            self.child = Some(child);
            self.output = Some(output);
            self.started = Instant::now();
            self.restart_at = None;
        }
        Ok(())
    }

    /// Asks its child, if it runs, to stop.
    pub fn interrupt(&self) {
        if let Some(c) = &self.child {
            interrupt(c);
        }
    }

    /// A process to start now.
    pub fn new(role: Role) -> Supervised {
        Supervised {
            role,
            child: None,
            finished: false,
            restart_at: Some(Instant::now()),
            failures: 0,
            started: Instant::now(),
            output: None,
            crashes: Vec::new(),
        }
    }
}

/// A child that could not be waited for, as its supervisor's error.
pub fn reap_error(role: &Role, e: std::io::Error) -> LeagueError {
    LeagueError::process(format!("cannot wait for the {}", role.name()), e)
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

/// A child's output as its parent keeps it. The child writes into a pipe
/// and the parent appends each line to the log: a child whose stderr is a
/// file on a full disk panics in its first `eprintln!` and loses its
/// message with it (exit 101, an empty log, an empty crash record), while
/// a pipe never fills that way, and the parent still holds the last lines
/// when the log cannot take them.
#[derive(Clone)]
pub struct Output(Arc<Mutex<OutputState>>);

#[derive(Default)]
struct OutputState {
    lines: VecDeque<String>,
    /// The first failure to write the log, naming it.
    log_error: Option<String>,
    /// The child's end of the pipe is closed: every line is in.
    closed: bool,
}

/// Lines of a child's output kept in memory (the crash record takes the
/// last few).
const KEPT_LINES: usize = 200;

impl Output {
    /// Waits (up to `limit`) until every line the child wrote is read.
    pub fn wait_closed(&self, limit: Duration) {
        let until = Instant::now() + limit;
        while Instant::now() < until && !self.0.lock().map(|s| s.closed).unwrap_or(true) {
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// The lines kept, after a first line saying the log could not be
    /// written (and why), if it could not: the child's own last error line
    /// stays the one `last_error_line` finds, the log's failure the cause
    /// only when the child said nothing.
    pub fn text(&self) -> String {
        let Ok(s) = self.0.lock() else {
            return String::new();
        };
        let mut text = s
            .log_error
            .as_ref()
            .map(|e| format!("error: {e}\n"))
            .unwrap_or_default();
        text.extend(s.lines.iter().map(|l| format!("{l}\n")));
        text
    }

    /// The last `n` lines for a crash record, and the log's failure.
    pub fn crash_text(&self, n: usize) -> String {
        let Ok(s) = self.0.lock() else {
            return String::new();
        };
        let skip = s.lines.len().saturating_sub(n);
        let mut lines: Vec<String> = s.lines.iter().skip(skip).cloned().collect();
        if let Some(e) = &s.log_error {
            lines.push(format!("({e})"));
        }
        lines.join("\n")
    }
}

/// Starts `role` for the league in `dir` as a child process, its output
/// appended to its log in `logs` (through `Output`). A PostgreSQL store's URL reaches the child
/// in its environment (`T2E_STORE`), never on its command line, where any
/// user of the host could read the password.
pub fn spawn(
    dir: &LeagueDir,
    role: Role,
    logs: &Path,
    host: Option<&str>,
) -> Result<(Child, Output)> {
    let mut cmd = ChildCommand::seat(role, dir)
        .command()
        .map_err(|e| LeagueError::process("cannot find this program to spawn learners", e))?;
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
    spawn_logged(cmd, &role.log_path(logs))
        .with_context(|| format!("cannot start the {}", role.name()))
}

/// Starts `cmd` (dying with this process) with its output going to the log
/// at `log_path` through `Output`.
pub fn spawn_logged(mut cmd: Command, log_path: &Path) -> Result<(Child, Output)> {
    let log_path = log_path.to_path_buf();
    let log = log_path
        .parent()
        .map_or(Ok(()), std::fs::create_dir_all)
        .and_then(|_| {
            std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&log_path)
        });
    let (reader, writer) = std::io::pipe()
        .map_err(|e| LeagueError::process("cannot make a pipe for a child's output", e))?;
    let stdout = writer
        .try_clone()
        .map_err(|e| LeagueError::process("cannot make a pipe for a child's output", e))?;
    cmd.stdin(Stdio::null()).stdout(stdout).stderr(writer);
    die_with_parent(&mut cmd);
    let child = cmd.spawn().map_err(|e| {
        LeagueError::process(
            format!("cannot run {}", cmd.get_program().to_string_lossy()),
            e,
        )
    })?;
    // The parent's copies of the write end went with `cmd`: the reader sees
    // the end of the output when the child exits.
    drop(cmd);
    let output = Output(Arc::new(Mutex::new(OutputState::default())));
    let state = output.clone();
    std::thread::spawn(move || copy_output(reader, log, log_path, state));
    Ok((child, output))
}

/// Appends each line of a child's output to its log and keeps the last ones.
fn copy_output(
    reader: std::io::PipeReader,
    log: std::io::Result<File>,
    log_path: PathBuf,
    state: Output,
) {
    use std::io::{BufRead, Write};
    let (mut log, first_error) = match log {
        Ok(f) => (Some(f), None),
        Err(e) => (
            None,
            Some(format!("cannot open its log {}: {e}", log_path.display())),
        ),
    };
    if let Ok(mut s) = state.0.lock() {
        s.log_error = first_error;
    }
    let mut reader = std::io::BufReader::new(reader);
    let mut buf = Vec::new();
    loop {
        buf.clear();
        match reader.read_until(b'\n', &mut buf) {
            Ok(0) | Err(_) => break,
            Ok(_) => {}
        }
        let line = String::from_utf8_lossy(&buf).trim_end().to_string();
        let written = match &mut log {
            Some(f) => f.write_all(&buf).map_err(|e| e.to_string()),
            None => Ok(()),
        };
        let Ok(mut s) = state.0.lock() else { break };
        if let Err(e) = written {
            s.log_error
                .get_or_insert_with(|| format!("cannot write its log {}: {e}", log_path.display()));
        }
        if s.lines.len() == KEPT_LINES {
            s.lines.pop_front();
        }
        s.lines.push_back(line);
    }
    if let Ok(mut s) = state.0.lock() {
        s.closed = true;
    }
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
            let store = StoreUrl::parse(&url)?;
            Ok(LeagueDir::with_store(root, store))
        }
        _ => Ok(LeagueDir::new(root)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rules::players::Seat;
    use t2e_core::env::Side;

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
