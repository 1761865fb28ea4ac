//! What the off-policy settings tables (MADDPG's, MAAC's) share: the replay
//! settings a learner is built with, and their checks.

use crate::nn::NetConfig;
use t2e_core::error::{in_range, ConfigError};

/// The replay settings every off-policy config has, read once when a
/// learner is built.
#[derive(Clone, Debug, PartialEq)]
pub struct ReplaySettings {
    pub actor_lr: f64,
    pub critic_lr: f64,
    pub adam_eps: f64,
    pub buffer_steps: usize,
    pub chunk_len: usize,
    pub batch_size: usize,
    pub replay_ratio: f64,
    pub learning_starts: usize,
    pub max_bad_updates: u32,
}

/// What the off-policy kind reads of an algorithm's settings table.
pub trait ReplayConfig: Clone + Sync {
    fn replay_settings(&self) -> ReplaySettings;
    fn gamma(&self) -> f64;
    /// Checks the table (some settings depend on the networks' shape).
    fn check(&self, net: &NetConfig) -> Result<(), ConfigError>;
}

/// Checks shared by the off-policy configs; the error names the field.
pub fn check_replay(
    chunk_len: usize,
    batch_size: usize,
    buffer_steps: usize,
    learning_starts: usize,
) -> Result<(), ConfigError> {
    in_range("chunk_len", chunk_len, 1..=1000, "must be in 1..=1000")?;
    in_range(
        "batch_size",
        batch_size,
        1..=100_000,
        "must be in 1..=100000 sequences",
    )?;
    in_range(
        "buffer_steps",
        buffer_steps,
        chunk_len * batch_size..=100_000_000,
        &format!("must hold at least one batch ({batch_size} sequences of {chunk_len} steps) and at most 100,000,000 steps"),
    )?;
    in_range(
        "learning_starts",
        learning_starts,
        0..=buffer_steps,
        &format!("more than the buffer holds (buffer_steps = {buffer_steps})"),
    )
}
