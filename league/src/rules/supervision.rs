//! What the manager does when one of its processes exits: every exit has
//! one defined outcome. Pure functions of the exit, the manager's state and
//! the crash history, so each rule has a hand-computed test.
//!
//! | exit                                   | manager stopping | outcome                               |
//! |----------------------------------------|------------------|---------------------------------------|
//! | 0: reached its budget (done)           | either           | finished                              |
//! | `EXIT_STOPPED`: stopped on SIGINT      | yes              | finished                              |
//! | `EXIT_STOPPED`                         | no (a SIGINT the manager did not send) | a crash: restarted, counted |
//! | `EXIT_CANNOT_START`: refused to start  | either           | the league stops with its error       |
//! | any other code, or a signal            | yes              | finished (it was being stopped)       |
//! | any other code, or a signal            | no               | a crash: restarted after a back-off, unless the crash budget is spent: then the league stops with an error naming the process and the cause |
//!
//! A process that cannot start (its checkpoint is missing or corrupt, its
//! state disagrees with the store, its config is wrong) would fail the same
//! way however often it is restarted, so it stops the league at once
//! rather than letting the other learner train on alone.

use std::time::Duration;

/// A learner or the evaluator stopped on SIGINT before its budget.
pub const EXIT_STOPPED: i32 = 3;
/// A learner or the evaluator refused to start (sysexits' EX_CONFIG).
pub const EXIT_CANNOT_START: i32 = 78;

/// How a child process ended.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Exit {
    Done,
    Stopped,
    CannotStart,
    /// Any other exit code, or a signal: "exit code N" / "signal N".
    Crashed(String),
}

/// Classifies an exit status (its code, or the signal that ended it).
pub fn classify(code: Option<i32>, signal: Option<i32>) -> Exit {
    match (code, signal) {
        (Some(0), _) => Exit::Done,
        (Some(EXIT_STOPPED), _) => Exit::Stopped,
        (Some(EXIT_CANNOT_START), _) => Exit::CannotStart,
        (Some(c), _) => Exit::Crashed(format!("exit code {c}")),
        (None, Some(s)) => Exit::Crashed(format!("signal {s}")),
        (None, None) => Exit::Crashed("unknown exit".into()),
    }
}

/// How a learner process ended (its exit code: `supervision`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// It reached its budget.
    Done,
    /// It was stopped (SIGINT) before its budget, after checkpointing.
    Stopped,
}

/// How many crashes of one cause, within how long, stop the league.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CrashBudget {
    pub max_same_cause: usize,
    pub window_ms: i64,
}

impl Default for CrashBudget {
    /// Three crashes of one cause within ten minutes: a learner killed now
    /// and then (out of memory, a kill -9) restarts; one that fails the
    /// same way over and over stops the league within a minute.
    fn default() -> Self {
        CrashBudget {
            max_same_cause: 3,
            window_ms: 10 * 60 * 1000,
        }
    }
}

impl CrashBudget {
    /// Crashes of `cause` within the window that ends at `now_ms`, counting
    /// one at `now_ms` itself if it is in `history` (history: (at ms, cause)).
    pub fn count(&self, history: &[(i64, String)], cause: &str, now_ms: i64) -> usize {
        history
            .iter()
            .filter(|(at, c)| c == cause && now_ms - at < self.window_ms && *at <= now_ms)
            .count()
    }
}

/// What the manager does next with a process that exited.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Next {
    Finished,
    /// Restart after this wait; the crash (with its cause) is recorded.
    Restart {
        after: Duration,
        cause: String,
    },
    /// Stop every process and end `run` with this error.
    StopLeague {
        why: String,
    },
}

/// Back-off before restart number `failures` (1, 2, ...): 2, 4, 8, 16, 30 s.
pub fn backoff(failures: u32) -> Duration {
    Duration::from_secs((1u64 << failures.clamp(1, 5)).min(30))
}

/// The outcome of one exit (see the module's table). `message` is the
/// process's own last error line, if it printed one; `history` holds this
/// process's earlier crashes (at ms, cause), and this one is added to it.
#[allow(clippy::too_many_arguments)]
pub fn decide(
    name: &str,
    exit: &Exit,
    message: Option<&str>,
    stopping: bool,
    history: &mut Vec<(i64, String)>,
    now_ms: i64,
    failures: u32,
    budget: CrashBudget,
) -> Next {
    let cause = match (exit, stopping) {
        (Exit::Done, _) | (Exit::Stopped, true) | (Exit::Crashed(_), true) => {
            return Next::Finished
        }
        (Exit::CannotStart, _) => {
            return Next::StopLeague {
                why: format!(
                    "{name} cannot start: {}",
                    message.unwrap_or("(no message; see its log)")
                ),
            }
        }
        (Exit::Stopped, false) => {
            "stopped by a signal the manager did not send (SIGINT to it alone)".to_string()
        }
        (Exit::Crashed(status), false) => match message {
            Some(m) => format!("{status}: {m}"),
            None => status.clone(),
        },
    };
    history.push((now_ms, cause.clone()));
    let n = budget.count(history, &cause, now_ms);
    if n >= budget.max_same_cause {
        return Next::StopLeague {
            why: format!(
                "{name} crashed {n} times within {} min with the same cause ({cause}); stopping the league",
                budget.window_ms / 60_000
            ),
        };
    }
    Next::Restart {
        after: backoff(failures),
        cause,
    }
}

/// The error line a process printed last (`error: ...`, or a panic), from
/// the text of its log written since it started.
/// The message of an error line as either log format writes it: `error:
/// ...` (text) or an object whose level is ERROR (`--log-format json`).
fn logged_error(line: &str) -> Option<String> {
    if let Some(rest) = line.strip_prefix("error:") {
        return Some(rest.trim().to_string());
    }
    if !line.starts_with('{') {
        return None;
    }
    let v: serde_json::Value = serde_json::from_str(line).ok()?;
    (v["level"] == "ERROR")
        .then(|| v["fields"]["message"].as_str().map(str::to_string))
        .flatten()
}

pub fn last_error_line(log: &str) -> Option<String> {
    let lines: Vec<&str> = log.lines().map(str::trim).collect();
    let at = lines
        .iter()
        .rposition(|l| logged_error(l).is_some() || l.contains("panicked at"))?;
    let l = lines[at];
    let mut line = logged_error(l).unwrap_or_else(|| l.to_string());
    // A panic prints where on its own line and what on the next one.
    if l.contains("panicked at") && l.ends_with(':') {
        if let Some(what) = lines.get(at + 1).filter(|w| !w.is_empty()) {
            line = format!("{line} {what}");
        }
    }
    Some(line.chars().take(400).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    const B: CrashBudget = CrashBudget {
        max_same_cause: 3,
        window_ms: 600_000,
    };

    #[test]
    fn every_exit_has_one_outcome() {
        assert_eq!(classify(Some(0), None), Exit::Done);
        assert_eq!(classify(Some(3), None), Exit::Stopped);
        assert_eq!(classify(Some(78), None), Exit::CannotStart);
        assert_eq!(classify(Some(1), None), Exit::Crashed("exit code 1".into()));
        assert_eq!(classify(None, Some(9)), Exit::Crashed("signal 9".into()));
        let mut h = Vec::new();
        let d = |exit: Exit, stopping: bool, h: &mut Vec<(i64, String)>| {
            decide(
                "captors-main",
                &exit,
                Some("boom"),
                stopping,
                h,
                1_000,
                1,
                B,
            )
        };
        assert_eq!(d(Exit::Done, false, &mut h), Next::Finished);
        assert_eq!(d(Exit::Done, true, &mut h), Next::Finished);
        assert_eq!(d(Exit::Stopped, true, &mut h), Next::Finished);
        assert_eq!(
            d(Exit::Crashed("signal 9".into()), true, &mut h),
            Next::Finished
        );
        assert!(h.is_empty(), "nothing above is a crash");
        assert_eq!(
            d(Exit::CannotStart, false, &mut h),
            Next::StopLeague {
                why: "captors-main cannot start: boom".into()
            }
        );
        match d(Exit::Stopped, false, &mut h) {
            Next::Restart { after, cause } => {
                assert_eq!(after, Duration::from_secs(2));
                assert!(cause.contains("did not send"), "{cause}");
            }
            other => panic!("{other:?}"),
        }
        assert_eq!(h.len(), 1, "an unasked stop counts against the budget");
    }

    #[test]
    fn the_same_cause_three_times_in_the_window_stops_the_league() {
        let mut h = Vec::new();
        let crash = Exit::Crashed("exit code 1".into());
        let at = |h: &mut Vec<(i64, String)>, t: i64, msg: &str| {
            decide("target-main", &crash, Some(msg), false, h, t, 1, B)
        };
        assert!(matches!(
            at(&mut h, 0, "checkpoint corrupt"),
            Next::Restart { .. }
        ));
        // Another cause between does not add up with it.
        assert!(matches!(
            at(&mut h, 1_000, "disk full"),
            Next::Restart { .. }
        ));
        assert!(matches!(
            at(&mut h, 2_000, "checkpoint corrupt"),
            Next::Restart { .. }
        ));
        match at(&mut h, 3_000, "checkpoint corrupt") {
            Next::StopLeague { why } => {
                assert!(
                    why.starts_with("target-main crashed 3 times within 10 min"),
                    "{why}"
                );
                assert!(why.contains("exit code 1: checkpoint corrupt"), "{why}");
            }
            other => panic!("{other:?}"),
        }
        // Outside the window, old crashes no longer count.
        let mut h = vec![
            (0, "exit code 1: x".to_string()),
            (1, "exit code 1: x".to_string()),
        ];
        assert!(matches!(
            decide("c", &crash, Some("x"), false, &mut h, 600_001, 1, B),
            Next::Restart { .. }
        ));
        assert_eq!(backoff(1), Duration::from_secs(2));
        assert_eq!(backoff(3), Duration::from_secs(8));
        assert_eq!(backoff(9), Duration::from_secs(30));
    }

    #[test]
    fn the_error_line_is_found_in_a_log() {
        let log = "captors-main: resuming at 640 env steps\nwarning: slow\nerror: checkpoints/x: meta.json missing\n";
        assert_eq!(
            last_error_line(log).as_deref(),
            Some("checkpoints/x: meta.json missing")
        );
        let panic = "thread 'main' panicked at src/x.rs:3:5:\nindex out of bounds\n";
        let line = last_error_line(panic).unwrap();
        assert!(line.contains("panicked at src/x.rs"), "{line}");
        assert!(
            line.ends_with("index out of bounds"),
            "the panic's message: {line}"
        );
        assert_eq!(last_error_line("all fine\n"), None);
        // `--log-format json`: the object whose level is ERROR.
        let json = concat!(
            r#"{"timestamp":"t","level":"INFO","fields":{"message":"captors-main: resuming"},"target":"t2e"}"#,
            "\n",
            r#"{"timestamp":"t","level":"ERROR","fields":{"message":"checkpoints/x: meta.json missing"},"target":"t2e_league"}"#,
            "\n",
            r#"{"timestamp":"t","level":"WARN","fields":{"message":"slow"},"target":"t2e"}"#,
            "\n",
        );
        assert_eq!(
            last_error_line(json).as_deref(),
            Some("checkpoints/x: meta.json missing")
        );
    }
}
