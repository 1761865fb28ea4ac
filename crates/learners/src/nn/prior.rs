//! `heuristic_prior` of `NetConfig`: a learned target whose policy is the
//! rule-based target's plus what it learns.
//!
//! The learned targets here (the paper's co-evolved one, naive
//! co-evolution's and the league's) were all caught more often than the
//! rule-based target by captors they never trained against: each learns to
//! beat the captors it meets, and forgets how to flee in general. With a
//! prior of weight w, the policy's logits get w added on the action the
//! rule-based target (spec §7) would take in the same state. At w = 2 and
//! the near-uniform start of the actor's last layer, the untrained policy
//! takes the rule-based action about 2/3 of the time (e^2 / (e^2 + 4));
//! learning moves the logits away from it only where that pays. The
//! environment, the observation and the rule-based target are the spec's:
//! this is part of the network, and every checkpoint that uses it carries
//! it in its net config, so it plays the same wherever it is loaded.
//!
//! `ppo.heuristic_kl` is the training-side companion (the PPO update adds
//! it times -log pi(rule-based action)): the prior sets where the policy
//! starts, the KL keeps pulling it back while it learns. Both read the same
//! hints (`Rollout::hints`, `Learner::wants_hints`); `check_kl` is its
//! side and learner check.

use t2e_core::env::{Action, Side, TrapEnv};
use t2e_core::error::ConfigError;
use tch::{Kind, Tensor};

/// The largest prior weight accepted: beyond it the policy is the rule-based
/// target, whatever it learns (a logit gap of 20 is a probability of 2e-9).
pub const MAX_WEIGHT: f64 = 20.0;

/// The action index the rule-based target would take in `env`.
pub fn target_hint(env: &TrapEnv) -> i64 {
    t2e_core::heuristics::target_action(env).index() as i64
}

/// `logits` [..., 5] plus `weight` on each row's hinted action (`hints`
/// [...], the leading dimensions of `logits`); `logits` unchanged at 0.
pub fn add_prior(logits: Tensor, hints: &Tensor, weight: f64) -> Tensor {
    if weight == 0.0 {
        return logits;
    }
    let one_hot = hints
        .to_device(logits.device())
        .one_hot(Action::COUNT as i64)
        .to_kind(Kind::Float);
    logits + one_hot * weight
}

/// Checks a side's prior: only the target has a rule-based action to lean
/// on, and only the PPO learners (MAPPO, IPPO) read it.
pub fn check(weight: f64, side: Side, ppo: bool) -> Result<(), ConfigError> {
    if !(weight.is_finite() && (0.0..=MAX_WEIGHT).contains(&weight)) {
        return Err(ConfigError::new(
            "heuristic_prior",
            weight,
            format!("must be in [0, {MAX_WEIGHT}] (0: off)"),
        ));
    }
    target_and_ppo_only(
        "heuristic_prior",
        weight,
        side,
        ppo,
        "the rule-based target's action",
        "[target.net]",
    )
}

/// Checks a side's `ppo.heuristic_kl` (the penalty for leaving the
/// rule-based target's action): the target's alone, as the prior. Its
/// range is `PpoConfig::validate`'s.
pub fn check_kl(weight: f64, side: Side, ppo: bool) -> Result<(), ConfigError> {
    target_and_ppo_only(
        "heuristic_kl",
        weight,
        side,
        ppo,
        "a KL towards the rule-based target",
        "[target.ppo]",
    )
}

/// The rule both options share: on (> 0) only for a target trained by
/// MAPPO or IPPO.
fn target_and_ppo_only(
    field: &str,
    weight: f64,
    side: Side,
    ppo: bool,
    what: &str,
    section: &str,
) -> Result<(), ConfigError> {
    if weight > 0.0 && side == Side::Captors {
        return Err(ConfigError::new(
            field,
            weight,
            format!("only the target has one ({what}); set it under {section}"),
        ));
    }
    if weight > 0.0 && !ppo {
        return Err(ConfigError::new(
            field,
            weight,
            "only MAPPO and IPPO read it; drop it or play mappo / ippo",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_prior_adds_the_weight_on_the_hinted_action_only() {
        let logits = Tensor::from_slice(&[0.5f32, -1.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
            .view([2, 5]);
        let hints = Tensor::from_slice(&[3i64, 0]);
        let out = add_prior(logits, &hints, 2.0);
        let mut got = [0f32; 10];
        out.copy_data(&mut got, 10);
        assert_eq!(got, [0.5, -1.0, 0.0, 4.0, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0]);
        // At weight 2 over uniform logits the hinted action has e^2 / (e^2 + 4).
        let p = add_prior(
            Tensor::zeros([1, 5], (Kind::Float, tch::Device::Cpu)),
            &hints.narrow(0, 0, 1),
            2.0,
        )
        .softmax(-1, Kind::Float)
        .double_value(&[0, 3]);
        let e2 = 2f64.exp();
        assert!((p - e2 / (e2 + 4.0)).abs() < 1e-6, "{p}");
    }

    #[test]
    fn a_prior_for_the_captors_or_an_off_policy_learner_or_out_of_range_is_refused() {
        assert!(check(0.0, Side::Captors, false).is_ok());
        assert!(check(2.0, Side::Target, true).is_ok());
        assert!(check(2.0, Side::Captors, true)
            .unwrap_err()
            .to_string()
            .contains("only the target"));
        assert!(check(2.0, Side::Target, false)
            .unwrap_err()
            .to_string()
            .contains("MAPPO and IPPO"));
        for w in [-1.0, 21.0, f64::NAN, f64::INFINITY] {
            assert!(
                check(w, Side::Target, true)
                    .unwrap_err()
                    .to_string()
                    .starts_with("heuristic_prior"),
                "{w}"
            );
        }
    }

    #[test]
    fn a_kl_for_the_captors_or_an_off_policy_learner_is_refused() {
        assert!(check_kl(0.0, Side::Captors, false).is_ok());
        assert!(check_kl(0.5, Side::Target, true).is_ok());
        assert!(check_kl(0.5, Side::Captors, true)
            .unwrap_err()
            .to_string()
            .contains("only the target"));
        assert!(check_kl(0.5, Side::Target, false)
            .unwrap_err()
            .to_string()
            .contains("MAPPO and IPPO"));
    }
}
