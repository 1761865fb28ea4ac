//! Training-only, potential-based reward shaping (Ng, Harada and Russell,
//! 1999): a learner may add F = gamma * phi(s') - phi(s) to the spec's
//! reward. Shaping of this form leaves the optimal policies unchanged; it
//! only tells the learner sooner which states lead somewhere. The
//! environment's reward, the returns a run reports and every evaluation
//! stay the spec's; a run that shapes says so in its config (and hash):
//! `settings/shaping.rs`'s `ShapingConfig`.

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
}
