//! The shaping table (`[captors.shaping]`, `[target.shaping]`): which
//! potential a learner's reward is shaped with (`learn/shaping.rs` adds
//! the term), and how strongly.

use serde::{Deserialize, Serialize};
use t2e_core::env::potential::Potential;
use t2e_core::error::{in_interval, ConfigError};

/// `[captors.shaping]` / `[target.shaping]` of a training config.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShapingConfig {
    /// The potential, or none (the default: the spec's reward alone).
    pub potential: Option<Potential>,
    /// phi = weight x the potential (in [0, 1]) for the captors, and
    /// -weight x it for the target, whose interest is the opposite. For
    /// scale: a capture is worth 200, a step of contact 5.
    pub weight: f64,
}

impl Default for ShapingConfig {
    fn default() -> Self {
        ShapingConfig {
            potential: None,
            weight: 50.0,
        }
    }
}

impl ShapingConfig {
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_interval("weight", self.weight, 0.0, 1000.0, true)
    }

    pub fn is_off(&self) -> bool {
        self.potential.is_none() || self.weight == 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_out_of_range_are_refused() {
        for w in [-1.0, f64::NAN, f64::INFINITY, 1e4] {
            let c = ShapingConfig {
                potential: Some(Potential::Trap),
                weight: w,
            };
            assert!(
                c.validate().unwrap_err().to_string().contains("weight"),
                "{w}"
            );
        }
        assert!(ShapingConfig::default().is_off());
    }
}
