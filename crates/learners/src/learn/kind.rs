//! The registry of learners: `kind` is the one place that maps an
//! `Algorithm` to its `LearnerKind` (learner.rs), which each algorithm's
//! file implements. It sits above the algorithms; nothing below imports it. A new learner is
//! therefore its file, its `Algorithm` variant, and the arm of `kind` (and
//! of `Algorithm::name`) the compiler then asks for; a test runs every
//! algorithm through its kind. Only a learner with settings of its own also
//! adds their table to `SideConfig`, a field beside `ppo`, `maddpg` and
//! `maac`.

use super::learner::LearnerKind;
use super::{ippo, maac, maddpg, mappo};
use t2e_core::algorithm::Algorithm;

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
    use super::super::side_config::SideConfig;
    use super::*;
    use tch::Device;

    #[test]
    fn every_algorithm_has_a_kind_that_builds_its_learner_from_the_default_settings() {
        let side = SideConfig::default();
        for algorithm in Algorithm::ALL {
            let k = kind(algorithm);
            k.validate(&side).unwrap();
            assert!(k.chunk_len(&side) >= 1);
            assert!(k.gamma(&side) > 0.0 && k.gamma(&side) < 1.0);
            assert_eq!(k.off_policy(), k.replay(&side).is_some());
            let vector_len = t2e_core::env::EnvConfig::default().vector_len();
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
