//! Training-only extra maps beside the protocol's own (`[extra_maps]` of a
//! training config). Under the paper protocol the learner trains on the 26
//! Gibson maps it is tested on; extra maps add layouts it is never tested
//! on, for diversity (the held-out runs kept improving on 60 generated maps
//! where paper-protocol runs flattened on 26). The test set, the
//! environment and the evaluation do not change, and the extra maps are
//! held to the held-out rule: no Gibson test map, not even a near-copy. A
//! run that uses them says so in its config (and hash); every figure it
//! makes must say "paper protocol + extra maps".

use serde::{Deserialize, Serialize};
use std::sync::Arc;
use t2e_core::error::ConfigError;
use t2e_core::map::PreparedMap;

/// `[extra_maps]` of a training config.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExtraMapsConfig {
    /// A map set as `maps` names one (`generated:N`, `shipped`, a folder);
    /// empty for none (the default).
    pub maps: String,
    /// The share of training episodes played on the extra maps, in (0, 1);
    /// the rest play the protocol's own maps.
    pub share: f64,
}

impl Default for ExtraMapsConfig {
    fn default() -> Self {
        ExtraMapsConfig {
            maps: String::new(),
            share: 0.5,
        }
    }
}

impl ExtraMapsConfig {
    pub fn is_off(&self) -> bool {
        self.maps.trim().is_empty()
    }

    /// The error names the field (relative to `extra_maps.`).
    pub fn validate(&self) -> Result<(), ConfigError> {
        if !(self.share.is_finite() && self.share > 0.0 && self.share < 1.0) {
            return Err(ConfigError::new(
                "share",
                self.share,
                "must be in (0, 1), the share of episodes on the extra maps",
            ));
        }
        if self.is_off() && *self != ExtraMapsConfig::default() {
            return Err(ConfigError::new(
                "share",
                self.share,
                "but maps is empty: name the extra maps (e.g. maps = \"generated:100\") or drop [extra_maps]",
            ));
        }
        Ok(())
    }
}

/// The most copies of one map set in the list `mix` builds.
const MAX_COPIES: usize = 1000;

/// How many times each own map and each extra map is listed so that a map
/// drawn uniformly from the list is an extra one with probability closest
/// to `share`: (own copies, extra copies), each in 1..=1000, the pair with
/// the fewest listings among the closest. Pure, so the mix is the same on
/// every machine.
pub fn copies(own: usize, extra: usize, share: f64) -> (usize, usize) {
    let mut best = (1, 1);
    let mut best_error = f64::INFINITY;
    for total in 2..=2 * MAX_COPIES {
        for r in total.saturating_sub(MAX_COPIES).max(1)..=(total - 1).min(MAX_COPIES) {
            let q = total - r;
            let got = (q * extra) as f64 / (q * extra + r * own) as f64;
            let error = (got - share).abs();
            if error < best_error - 1e-12 {
                best_error = error;
                best = (r, q);
            }
        }
    }
    best
}

/// The list an environment samples its episodes' maps from: `own` and
/// `extra`, each repeated as `copies` says.
pub fn mix(
    own: &[Arc<PreparedMap>],
    extra: &[Arc<PreparedMap>],
    share: f64,
) -> Arc<Vec<Arc<PreparedMap>>> {
    let (r, q) = copies(own.len(), extra.len(), share);
    let mut maps = Vec::with_capacity(r * own.len() + q * extra.len());
    for _ in 0..r {
        maps.extend(own.iter().cloned());
    }
    for _ in 0..q {
        maps.extend(extra.iter().cloned());
    }
    Arc::new(maps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copies_hit_the_share_exactly_when_small_integers_can() {
        // 26 Gibson maps and 60 generated ones at one half: 60 q = 26 r,
        // smallest at r = 30, q = 13 (780 listings each).
        assert_eq!(copies(26, 60, 0.5), (30, 13));
        // Equal sets at one half: once each.
        assert_eq!(copies(10, 10, 0.5), (1, 1));
        // 10 and 30 at three quarters: 30 / (30 + 10) already.
        assert_eq!(copies(10, 30, 0.75), (1, 1));
        // 10 and 30 at one quarter: 30 q / (30 q + 10 r) = 1/4 at r = 9, q = 1.
        assert_eq!(copies(10, 30, 0.25), (9, 1));
        // 26 and 60 at a tenth: 54 q = 2.6 r, smallest at q = 13, r = 270.
        assert_eq!(copies(26, 60, 0.1), (270, 13));
    }

    #[test]
    fn copies_come_close_when_they_cannot_be_exact() {
        for (own, extra, share) in [
            (26, 300, 0.5),
            (26, 1500, 0.5),
            (26, 3000, 0.2),
            (7, 3, 0.9),
        ] {
            let (r, q) = copies(own, extra, share);
            let got = (q * extra) as f64 / (q * extra + r * own) as f64;
            assert!((got - share).abs() < 0.001, "{own} {extra} {share}: {got}");
        }
    }

    #[test]
    fn a_share_outside_the_open_interval_or_without_maps_is_refused() {
        for share in [0.0, 1.0, -0.5, f64::NAN, f64::INFINITY] {
            let cfg = ExtraMapsConfig {
                maps: "generated:20".into(),
                share,
            };
            assert!(
                cfg.validate()
                    .unwrap_err()
                    .to_string()
                    .starts_with("share = "),
                "{share}"
            );
        }
        let cfg = ExtraMapsConfig {
            maps: String::new(),
            share: 0.3,
        };
        assert!(cfg
            .validate()
            .unwrap_err()
            .to_string()
            .contains("maps is empty"));
        assert!(ExtraMapsConfig::default().validate().is_ok());
    }
}
