//! The setting every learner shares: how many bad updates in a row stop
//! training.

use t2e_core::error::ConfigError;

/// Every learner's `max_bad_updates`: updates undone in a row before
/// training stops, at least one.
pub fn check_max_bad_updates(n: u32) -> Result<(), ConfigError> {
    t2e_core::error::in_range("max_bad_updates", n, 1..=u32::MAX, "must be at least 1")
}
