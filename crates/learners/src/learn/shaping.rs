//! Training-only, potential-based reward shaping (Ng, Harada and Russell,
//! 1999): a learner may add F = gamma * phi(s') - phi(s) to the spec's
//! reward. Shaping of this form leaves the optimal policies unchanged; it
//! only tells the learner sooner which states lead somewhere. The
//! environment's reward, the returns a run reports and every evaluation
//! stay the spec's; a run that shapes says so in its config (and hash).

use crate::env::potential::Potential;
use crate::error::{in_interval, ConfigError};
use serde::{Deserialize, Serialize};

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

/// The shaping term of one step, in potential units: gamma phi(s') - phi(s)
/// with phi(s) = `before`. An episode that ended by capture reached a
/// terminal state, whose potential is 0 (so shaping sums to -phi(s_0) over
/// any episode and cannot change which policies are optimal); one cut off by
/// the step limit reached `final_phi`, which the learner also bootstraps
/// from; otherwise the world is in s' = `after`.
pub fn shaping_term(
    before: f32,
    after: f32,
    final_phi: f32,
    terminated: bool,
    truncated: bool,
    gamma: f64,
) -> f32 {
    let next = if terminated {
        0.0
    } else if truncated {
        final_phi
    } else {
        after
    };
    (gamma * next as f64 - before as f64) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms_telescope_to_the_start_potential_over_a_captured_episode() {
        // phi along an episode: 0.25, 0.5, 0.75, then capture.
        let phis = [0.25f32, 0.5, 0.75];
        let gamma = 0.9;
        let mut discounted = 0.0f64;
        for t in 0..3 {
            let terminated = t == 2;
            let after = if terminated { 0.3 } else { phis[t + 1] };
            let f = shaping_term(phis[t], after, 0.0, terminated, false, gamma);
            discounted += gamma.powi(t as i32) * f as f64;
        }
        // sum_t gamma^t (gamma phi_{t+1} - phi_t) = gamma^T phi_T - phi_0, phi_T = 0.
        assert!((discounted + 0.25).abs() < 1e-6, "{discounted}");
        // Truncation bootstraps from the state reached, not the next episode's.
        let f = shaping_term(0.5, 0.0, 1.0, false, true, 0.5);
        assert!((f - 0.0).abs() < 1e-6);
        let f = shaping_term(0.5, 1.0, 0.0, false, false, 1.0);
        assert!((f - 0.5).abs() < 1e-6);
    }

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
