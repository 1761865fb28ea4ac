//! The loop every supervising process of a league runs: the manager over
//! its seats' processes, the manager of a league on workers over the
//! seats in the store (seats.rs), and each worker over the seats it holds
//! (worker.rs). Each of them is a small `Policy`: what one pass does and
//! when it is through. The loop owns the rest, once for all three: when to
//! stop (Ctrl-C, `--for`, a failure), asking what runs to stop exactly
//! once, the pace of the passes, and the one failure the process ends with.

use crate::error::{LeagueError, Result};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Time between passes.
const PASS_EVERY: Duration = Duration::from_millis(200);

/// What one supervising process does in the loop.
pub trait Policy {
    /// Asks what it runs to stop (each seat finishes its iteration and
    /// checkpoints). Called once, when the loop starts stopping.
    fn interrupt(&mut self);
    /// One pass: reap and restart children, renew leases, look at the
    /// store. A failure that must end the league goes to `pass.fail`; an
    /// error returned ends this process at once.
    fn pass(&mut self, pass: &mut Pass) -> Result<()>;
    /// Nothing is left to wait for (`stopping`: the loop is stopping).
    fn through(&self, stopping: bool) -> bool;
}

/// Where the loop stands, for one pass.
pub struct Pass<'a> {
    /// The loop is stopping: nothing is started any more.
    pub stopping: bool,
    /// Its children were asked to stop (by the loop, or by a Ctrl-C that
    /// reached them and this process at once): a child that stops now
    /// finished as asked.
    pub asked: bool,
    failure: &'a mut Option<String>,
}

impl Pass<'_> {
    /// Ends the league with `why`, unless it already ends with another.
    pub fn fail(&mut self, why: impl Into<String>) {
        self.failure.get_or_insert_with(|| why.into());
    }
}

/// Runs `policy` until it is through; stops when `stop` is set, after
/// `run_for`, or at the first failure. The first failure is the error.
pub fn supervise(
    policy: &mut dyn Policy,
    stop: &AtomicBool,
    run_for: Option<Duration>,
) -> Result<()> {
    let deadline = run_for.map(|d| Instant::now() + d);
    let mut stopping = false;
    let mut failure: Option<String> = None;
    loop {
        if !stopping
            && (stop.load(Ordering::SeqCst)
                || failure.is_some()
                || deadline.is_some_and(|d| Instant::now() >= d))
        {
            stopping = true;
            policy.interrupt();
        }
        let mut pass = Pass {
            stopping,
            asked: stopping || stop.load(Ordering::SeqCst),
            failure: &mut failure,
        };
        policy.pass(&mut pass)?;
        if policy.through(stopping) {
            break;
        }
        std::thread::sleep(PASS_EVERY);
    }
    match failure {
        Some(why) => Err(LeagueError::Failed(why)),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A policy that records what the loop asked of it.
    #[derive(Default)]
    struct Script {
        passes: u32,
        interrupts: u32,
        fail_at: Option<u32>,
        through_after_stop: bool,
        asked: Vec<bool>,
    }

    impl Policy for Script {
        fn interrupt(&mut self) {
            self.interrupts += 1;
        }
        fn pass(&mut self, pass: &mut Pass) -> Result<()> {
            self.passes += 1;
            self.asked.push(pass.asked);
            if Some(self.passes) == self.fail_at {
                pass.fail("seat crashed");
                pass.fail("a second cause, not the first");
            }
            self.through_after_stop = pass.stopping;
            Ok(())
        }
        fn through(&self, stopping: bool) -> bool {
            stopping && self.through_after_stop
        }
    }

    #[test]
    fn the_first_failure_stops_the_loop_once_and_is_its_error() {
        let mut script = Script {
            fail_at: Some(2),
            ..Script::default()
        };
        let err = supervise(&mut script, &AtomicBool::new(false), None).unwrap_err();
        assert_eq!(err.to_string(), "seat crashed");
        assert_eq!(script.interrupts, 1);
        // Two passes before the stop, one that saw it.
        assert_eq!(script.asked, vec![false, false, true]);
    }

    #[test]
    fn a_stop_asked_before_the_start_interrupts_once_and_ends_without_error() {
        let mut script = Script::default();
        supervise(&mut script, &AtomicBool::new(true), None).unwrap();
        assert_eq!((script.interrupts, script.passes), (1, 1));
        assert_eq!(script.asked, vec![true]);
    }

    #[test]
    fn run_for_ends_the_loop_as_a_stop() {
        let mut script = Script::default();
        supervise(
            &mut script,
            &AtomicBool::new(false),
            Some(Duration::from_millis(300)),
        )
        .unwrap();
        assert_eq!(script.interrupts, 1);
        assert!(script.passes >= 2, "{} passes", script.passes);
        assert_eq!(script.asked.last(), Some(&true));
        assert!(!script.asked[0]);
    }
}
