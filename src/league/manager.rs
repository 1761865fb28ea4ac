//! `t2e-league run`: the league's manager. It starts a league (or resumes
//! the one its directory holds), spawns each main learner as a child
//! process of the same binary, and supervises them: a learner that crashes
//! is restarted from its last checkpoint with back-off, and the crash is
//! recorded in the store. It stops at the budget (the learners stop
//! themselves), after `--for`, or on Ctrl-C: every learner finishes its
//! iteration, checkpoints and exits.
//!
//! Processes, not threads: a crash stays in its process, each process sizes
//! its own libtorch and rayon pools, and the processes share nothing but the
//! league directory (so learners can later run on other machines against a
//! shared database). Children get SIGKILL if the manager dies (Linux
//! `PR_SET_PDEATHSIG`), and each learner holds a lock of its own, so a
//! killed manager never leaves a learner running twice.

use super::config::LeagueConfig;
use super::dir::LeagueDir;
use super::learner::{ensure_heuristic_members, reconcile, Seat};
use super::store::Store;
use crate::env::Side;
use anyhow::{bail, Context, Result};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use std::fs::File;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// An exclusive lock on `path` (flock), held while the file stays open and
/// released by the kernel when the process dies, however it dies. None if
/// another live process holds it.
pub fn try_lock(path: &Path) -> Result<Option<File>> {
    use std::io::Write;
    use std::os::unix::io::AsRawFd;
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .read(true)
        .open(path)
        .with_context(|| format!("cannot open {}", path.display()))?;
    // SAFETY: flock on a file descriptor this function owns.
    let rc = unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) };
    if rc != 0 {
        return Ok(None);
    }
    f.set_len(0)?;
    writeln!(f, "{}", std::process::id())?;
    Ok(Some(f))
}

/// The pid written in a lock file, for messages.
fn lock_holder(path: &Path) -> String {
    std::fs::read_to_string(path)
        .map(|s| s.trim().to_string())
        .unwrap_or_default()
}

/// Parses `--for`: `90` or `90s`, `10m`, `2h`.
pub fn parse_duration(text: &str) -> Result<Duration, String> {
    let t = text.trim();
    let (num, unit) = match t.char_indices().find(|(_, c)| c.is_ascii_alphabetic()) {
        Some((i, _)) => (&t[..i], &t[i..]),
        None => (t, "s"),
    };
    let n: f64 = num
        .parse()
        .map_err(|_| format!("--for {text}: expected a duration such as 90s, 10m or 2h"))?;
    let secs = match unit {
        "s" => n,
        "m" | "min" => n * 60.0,
        "h" => n * 3600.0,
        _ => return Err(format!("--for {text}: unknown unit '{unit}' (s, m or h)")),
    };
    if !(secs.is_finite() && secs > 0.0 && secs <= 30.0 * 86400.0) {
        return Err(format!(
            "--for {text}: must be more than 0 and at most 30 days"
        ));
    }
    Ok(Duration::from_secs_f64(secs))
}

/// A child process the manager supervises.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Learner(Seat),
    Evaluator,
}

impl Role {
    fn name(self) -> String {
        match self {
            Role::Learner(seat) => seat.name(),
            Role::Evaluator => "evaluator".into(),
        }
    }

    fn log_path(self, dir: &LeagueDir) -> std::path::PathBuf {
        dir.root.join("logs").join(format!("{}.log", self.name()))
    }
}

struct Supervised {
    role: Role,
    child: Option<Child>,
    /// Why it is not running: finished (done or stopped) or waiting to restart.
    finished: bool,
    restart_at: Option<Instant>,
    failures: u32,
    started: Instant,
}

fn spawn(dir: &LeagueDir, role: Role) -> Result<Child> {
    let exe = std::env::current_exe().context("cannot find this program to spawn learners")?;
    std::fs::create_dir_all(dir.root.join("logs"))?;
    let log = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(role.log_path(dir))?;
    let mut cmd = Command::new(exe);
    match role {
        Role::Learner(seat) => {
            cmd.arg("league-learner")
                .arg("--side")
                .arg(seat.side.name());
            if seat.exploiter {
                cmd.arg("--exploiter");
            }
            &mut cmd
        }
        Role::Evaluator => cmd.arg("league-evaluator"),
    };
    cmd.arg("--dir")
        .arg(&dir.root)
        .stdin(Stdio::null())
        .stdout(log.try_clone()?)
        .stderr(log);
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: prctl is async-signal-safe; the child dies with its manager.
        unsafe {
            cmd.pre_exec(|| {
                libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL);
                Ok(())
            });
        }
    }
    cmd.spawn()
        .with_context(|| format!("cannot start the {}", role.name()))
}

/// The last lines of a learner's log, for the crash record.
fn log_tail(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let lines: Vec<&str> = text.lines().rev().take(5).collect();
    lines.into_iter().rev().collect::<Vec<_>>().join("\n")
}

/// Starts or resumes the league in `dir` and runs it to its end.
pub fn run(
    dir: &LeagueDir,
    config: Option<&Path>,
    run_for: Option<Duration>,
    stop: &AtomicBool,
) -> Result<()> {
    std::fs::create_dir_all(&dir.root)
        .with_context(|| format!("cannot create {}", dir.root.display()))?;
    let lock_path = dir.root.join("league.lock");
    let Some(_lock) = try_lock(&lock_path)? else {
        bail!(
            "{}: a manager (pid {}) is already running this league; stop it first (Ctrl-C) or pick another --dir",
            dir.root.display(),
            lock_holder(&lock_path)
        );
    };
    let cfg = match (config, dir.config_path().is_file()) {
        (Some(path), true) => {
            let given = LeagueConfig::load(path)?;
            let stored = dir.config()?;
            if given != stored {
                bail!(
                    "{} already holds a league started with another config ({}); resume it without --config, or pick another --dir",
                    dir.root.display(),
                    dir.config_path().display()
                );
            }
            eprintln!("resuming the league in {}", dir.root.display());
            stored
        }
        (None, true) => {
            eprintln!("resuming the league in {}", dir.root.display());
            dir.config()?
        }
        (Some(path), false) => {
            let cfg = LeagueConfig::load(path)?;
            // Refuse maps that do not fit the protocol here, with the file's
            // name, rather than in learners that crash and restart.
            let maps = crate::map::catalog::load_prepared(&cfg.maps)
                .with_context(|| format!("{}: maps = \"{}\"", path.display(), cfg.maps))?;
            cfg.protocol
                .check_training_maps(&cfg.maps, &maps)
                .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            crate::nn::checkpoint::write_file_atomically(
                &dir.config_path(),
                toml::to_string_pretty(&cfg)?.as_bytes(),
            )?;
            eprintln!("starting the league {} in {}", cfg.name, dir.root.display());
            cfg
        }
        (None, false) => bail!(
            "{} holds no league: give --config configs/league-*.toml to start one",
            dir.root.display()
        ),
    };
    let store = Store::open(&dir.root)?;
    let stored = store.config_once(&toml::to_string_pretty(&cfg)?)?;
    if LeagueConfig::parse(&stored).ok().as_ref() != Some(&cfg) {
        bail!(
            "{}: config.toml differs from the config the league's store was started with",
            dir.root.display()
        );
    }
    ensure_heuristic_members(&store)?;
    let (removed, quarantined) = reconcile(dir, &store)?;
    for r in removed {
        eprintln!("removed {r}: a snapshot folder without a row (its writer was killed)");
    }
    for q in quarantined {
        eprintln!("quarantined {q}: its checkpoint files are missing or corrupt");
    }
    let mut seats = vec![Seat::main(Side::Captors), Seat::main(Side::Target)];
    for side in [Side::Captors, Side::Target] {
        if cfg.exploiters.enabled(side) {
            seats.push(Seat::exploiter(side));
        }
    }
    for seat in &seats {
        for sub in ["", "checkpoints"] {
            crate::nn::checkpoint::clean_stale_temporaries(&dir.seat_dir(*seat).join(sub))?;
        }
    }

    let mut roles: Vec<Role> = seats.iter().map(|s| Role::Learner(*s)).collect();
    if cfg.evaluator.enabled {
        roles.push(Role::Evaluator);
    }
    let multi = MultiProgress::new();
    let bars: Vec<ProgressBar> = seats
        .iter()
        .map(|seat| {
            let b = multi.add(ProgressBar::new(cfg.env_steps_per_learner));
            b.set_style(
                ProgressStyle::with_template(
                    "{prefix:>12} [{bar:25}] {human_pos}/{human_len} steps {msg}",
                )
                .unwrap()
                .progress_chars("=> "),
            );
            b.set_prefix(seat.name());
            b
        })
        .collect();
    let mut learners: Vec<Supervised> = roles
        .into_iter()
        .map(|role| Supervised {
            role,
            child: None,
            finished: false,
            restart_at: Some(Instant::now()),
            failures: 0,
            started: Instant::now(),
        })
        .collect();
    let deadline = run_for.map(|d| Instant::now() + d);
    let mut stopping = false;
    let mut last_status = Instant::now() - Duration::from_secs(60);
    loop {
        if !stopping
            && (stop.load(Ordering::SeqCst) || deadline.is_some_and(|d| Instant::now() >= d))
        {
            stopping = true;
            multi
                .println("stopping: each learner finishes its iteration and checkpoints")
                .ok();
            for l in &learners {
                if let Some(c) = &l.child {
                    // SAFETY: signalling our own child by pid.
                    unsafe {
                        libc::kill(c.id() as i32, libc::SIGINT);
                    }
                }
            }
        }
        for l in &mut learners {
            if let Some(child) = &mut l.child {
                if let Some(status) = child.try_wait()? {
                    l.child = None;
                    if status.success() {
                        l.finished = true;
                    } else if stopping {
                        l.finished = true;
                    } else {
                        let why = match status.code() {
                            Some(code) => format!("exit code {code}"),
                            None => {
                                use std::os::unix::process::ExitStatusExt;
                                format!("signal {}", status.signal().unwrap_or(0))
                            }
                        };
                        let tail = log_tail(&l.role.log_path(dir));
                        store.record_crash(&l.role.name(), &why, &tail)?;
                        if l.started.elapsed() > Duration::from_secs(120) {
                            l.failures = 0;
                        }
                        l.failures += 1;
                        let wait = Duration::from_secs((1u64 << l.failures.min(5)).min(30));
                        multi
                            .println(format!(
                                "{} crashed ({why}); restarting from its last checkpoint in {} s (log: {})",
                                l.role.name(),
                                wait.as_secs(),
                                l.role.log_path(dir).display()
                            ))
                            .ok();
                        l.restart_at = Some(Instant::now() + wait);
                    }
                }
            }
            if l.child.is_none() && !l.finished && !stopping {
                if let Some(at) = l.restart_at {
                    if Instant::now() >= at {
                        l.child = Some(spawn(dir, l.role)?);
                        l.started = Instant::now();
                        l.restart_at = None;
                    }
                }
            }
            if stopping && l.child.is_none() {
                l.finished = true;
            }
        }
        if last_status.elapsed() >= Duration::from_secs(2) {
            last_status = Instant::now();
            let beats = store.heartbeats()?;
            let matches = store.match_count()?;
            for (bar, l) in bars.iter().zip(&learners) {
                if let Some(b) = beats.iter().find(|b| b.0 == l.role.name()) {
                    bar.set_position(b.3);
                    bar.set_message(format!(
                        "| {:.0} steps/s | {} | {matches} matches",
                        b.4, b.2
                    ));
                }
            }
        }
        if learners.iter().all(|l| l.finished) {
            break;
        }
        std::thread::sleep(Duration::from_millis(200));
    }
    for b in &bars {
        b.finish();
    }
    let players = store.players()?.len();
    eprintln!(
        "league {}: {} matches, {players} players; `t2e-league status --dir {}` shows the table",
        cfg.name,
        store.match_count()?,
        dir.root.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_parse_and_nonsense_is_refused() {
        assert_eq!(parse_duration("90").unwrap(), Duration::from_secs(90));
        assert_eq!(parse_duration("10m").unwrap(), Duration::from_secs(600));
        assert_eq!(parse_duration("1.5h").unwrap(), Duration::from_secs(5400));
        for bad in ["", "0", "-5m", "10x", "nanm", "1e9h"] {
            assert!(parse_duration(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn a_lock_is_exclusive_while_held() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("l.lock");
        let held = try_lock(&p).unwrap().unwrap();
        // flock locks are per open file description: a second open fails.
        assert!(try_lock(&p).unwrap().is_none());
        drop(held);
        assert!(try_lock(&p).unwrap().is_some());
    }
}
