//! What the league's long commands show while they run, as calls on a
//! `View` the caller implements: the CLI draws progress bars
//! (src/cli/progress.rs), a library user or a test can take `Quiet`. The
//! league decides what happened; how it looks on a terminal is not its
//! concern.

use std::io::Write;

/// One seat's progress, as its heartbeat last said.
#[derive(Clone, Debug, PartialEq)]
pub struct SeatProgress {
    pub env_steps: u64,
    pub steps_per_s: f64,
    /// Its state as the store names it (`training`, `waiting`, ...).
    pub state: String,
    /// Matches the league has recorded, all seats together.
    pub matches: u64,
}

/// What a best response's budget counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BudgetUnit {
    EnvSteps,
    Seconds,
}

/// The watcher of a league's manager or an exploit. Every method has a
/// default that shows nothing but the lines, so a view implements only
/// what it draws.
pub trait View: Sync {
    /// A line for the person watching: a crash, a restart, a stop.
    fn say(&self, line: &str) {
        // Not eprintln!: a redirected stderr on a full disk would panic the
        // manager, the one process left to say what happened.
        let _ = writeln!(std::io::stderr(), "{line}");
    }
    /// The seats the manager runs, each training for `env_steps`.
    fn seats(&self, _names: &[String], _env_steps: u64) {}
    /// One seat's progress (the seat as named in `seats`).
    fn seat(&self, _name: &str, _progress: &SeatProgress) {}
    /// A best response starts: `total` of `unit`, `done` of them already.
    fn best_response(&self, _total: u64, _unit: BudgetUnit) {}
    /// The best response has trained `done` of its budget.
    fn best_response_at(&self, _done: u64) {}
    /// The command's work is over (bars close).
    fn finish(&self) {}
}

/// Shows the lines alone.
#[derive(Clone, Copy, Debug, Default)]
pub struct Quiet;

impl View for Quiet {}
