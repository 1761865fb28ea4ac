//! What a training run asks of an algorithm beyond the `Learner` it builds:
//! the table of a side's config its settings live in, their chunk length,
//! discount and checks, the replay it would hold, the cost of its update,
//! and the learner itself. Each algorithm's file implements `LearnerKind`;
//! `kind` is the one place that maps an `Algorithm` to it. A new learner is
//! therefore its file, its `Algorithm` variant, and the arm of `kind` (and
//! of `Algorithm::name`) the compiler then asks for; a test runs every
//! algorithm through its kind. Only a learner with settings of its own also
//! adds their table to `SideConfig`, a field beside `ppo`, `maddpg` and
//! `maac`.

use super::config::SideConfig;
use super::learner::Learner;
use super::{ippo, maac, maddpg, mappo, Algorithm};
use crate::error::ConfigError;
use tch::Device;

pub trait LearnerKind: Sync {
    /// The table of a side's config its settings are read from (MAPPO and
    /// IPPO share `ppo`).
    fn settings_table(&self) -> &'static str;
    /// Whether it learns from a replay of past experience (and so cannot
    /// take a KL pull towards a prior, nor values states while acting).
    fn off_policy(&self) -> bool {
        false
    }
    /// Steps per recurrent chunk it trains on.
    fn chunk_len(&self, side: &SideConfig) -> usize;
    /// The discount it learns with.
    fn gamma(&self, side: &SideConfig) -> f64;
    /// Checks its settings; the error names the field within its table.
    fn validate(&self, side: &SideConfig) -> Result<(), ConfigError>;
    /// (world-steps, chunk length) of its replay, if it keeps one.
    fn replay(&self, _side: &SideConfig) -> Option<(usize, usize)> {
        None
    }
    /// FLOPs of its update per rollout row, from the FLOPs of one forward
    /// pass of actor and critic; NaN where they follow replay settings.
    fn update_flops(&self, _side: &SideConfig, _actor: f64, _critic: f64) -> f64 {
        f64::NAN
    }
    /// A fresh learner for a team of `team` robots.
    fn build(
        &self,
        side: &SideConfig,
        vector_len: usize,
        team: usize,
        device: Device,
    ) -> Box<dyn Learner>;
}

/// The kind of `algorithm`.
pub fn kind(algorithm: Algorithm) -> &'static dyn LearnerKind {
    match algorithm {
        Algorithm::Mappo => &mappo::KIND,
        Algorithm::Ippo => &ippo::KIND,
        Algorithm::Maddpg => &maddpg::KIND,
        Algorithm::Maac => &maac::KIND,
    }
}

/// The learners, by name, for messages ("mappo, ippo, maddpg or maac").
pub fn learner_names(last: &str) -> String {
    let names: Vec<&str> = Algorithm::ALL.iter().map(|a| a.name()).collect();
    match names.split_last() {
        Some((tail, head)) if !head.is_empty() => format!("{} {last} {tail}", head.join(", ")),
        _ => names.join(""),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_algorithm_has_a_kind_that_builds_its_learner_from_the_default_settings() {
        let side = SideConfig::default();
        for algorithm in Algorithm::ALL {
            let k = kind(algorithm);
            k.validate(&side).unwrap();
            assert!(k.chunk_len(&side) >= 1);
            assert!(k.gamma(&side) > 0.0 && k.gamma(&side) < 1.0);
            assert_eq!(k.off_policy(), k.replay(&side).is_some());
            let vector_len = crate::env::EnvConfig::default().vector_len();
            let learner = k.build(&side, vector_len, 3, Device::Cpu);
            assert_eq!(learner.algorithm(), algorithm, "{algorithm}");
            assert_eq!(learner.team(), 3);
            assert_eq!(learner.chunk_len(), k.chunk_len(&side));
        }
        assert_eq!(
            Algorithm::ALL
                .iter()
                .filter(|a| kind(**a).off_policy())
                .count(),
            2
        );
        assert_eq!(learner_names("or"), "mappo, ippo, maddpg or maac");
    }
}
