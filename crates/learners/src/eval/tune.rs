//! The ceiling of hand-made targets: CMA-ES over the rule-based target's
//! family (`heuristics::TargetParams`), minimising the worst capture rate
//! over a training panel of captor teams. Every candidate plays the same
//! starts (the panel's evaluation seed), so two candidates differ by their
//! play, not by their luck; the winner is then played on teams and maps it
//! never met, which is where a claim is judged.
//!
//! The search runs in a space where the origin is the rule itself
//! (`params_at`): CMA-ES starts at the rule and must find its way out.

use super::{run as run_setting, EvalSetting};
use crate::controllers::ControllerSpec;
use cmaes::{CMAESOptions, DVector};
use std::sync::Arc;
use t2e_core::heuristics::TargetParams;
use t2e_core::map::PreparedMap;

/// Every setting of a search, with the defaults `tune-target` uses.
#[derive(Clone, Debug)]
pub struct TuneSettings {
    /// The captor teams whose worst capture rate is minimised.
    pub panel: Vec<ControllerSpec>,
    /// K, the number of captors.
    pub num_captors: usize,
    /// v_e / v_p.
    pub speed_ratio: f64,
    /// Episodes per team per candidate (the same starts for every candidate).
    pub episodes: usize,
    /// Steps before an episode counts as escaped.
    pub episode_length: u32,
    /// Seeds the panel's starts.
    pub eval_seed: u64,
    /// Seeds CMA-ES's samples.
    pub search_seed: u64,
    /// Generations of CMA-ES.
    pub generations: usize,
    /// Candidates per generation (CMA-ES's lambda; 8 is its default for 5
    /// constants, 4 + 3 ln 5).
    pub population: usize,
    /// CMA-ES's initial step size, in the search space of `params_at`.
    pub sigma: f64,
}

impl Default for TuneSettings {
    fn default() -> Self {
        TuneSettings {
            panel: Vec::new(),
            num_captors: 3,
            speed_ratio: 1.2,
            episodes: 50,
            episode_length: 500,
            eval_seed: 0,
            search_seed: 0,
            generations: 12,
            population: 8,
            sigma: 0.5,
        }
    }
}

/// Why a search cannot run.
#[derive(Debug, thiserror::Error)]
pub enum TuneError {
    #[error("{0}")]
    Setting(String),
    // The cause is printed, not handed on as `source()`, so that the CLI's
    // `{:#}` at the edge prints it once (the project's convention).
    #[error("playing {team} against {target}: {cause}")]
    Play {
        team: String,
        target: String,
        cause: Box<dyn std::error::Error + Send + Sync>,
    },
}

/// One candidate, as played.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Candidate {
    pub generation: usize,
    /// The controller's name (`tuned:...`).
    pub target: String,
    /// Its constants, in the order of `TargetParams::RANGES`.
    pub params: [f64; 5],
    /// Capture rate (%) by each panel team, in panel order.
    pub capture: Vec<f64>,
    /// The largest of them: what the search minimises.
    pub worst: f64,
}

/// What a search found: every candidate, and the best one.
#[derive(Clone, Debug, serde::Serialize)]
pub struct TuneOutcome {
    pub candidates: Vec<Candidate>,
    /// The rule-based target on the same panel and starts.
    pub rule: Candidate,
    pub best: Candidate,
    pub best_params: [f64; 5],
}

/// The constants at point `y` of the search space. The origin is the rule
/// (`TargetParams::RULE`) to the bit; each axis moves one constant, kept
/// in its range.
pub fn params_at(y: &[f64]) -> TargetParams {
    // Kept to 4 decimals: a candidate's name is then short enough to read
    // and to type, and the origin still rounds to the rule's constants.
    let clamp = |i: usize, x: f64| {
        let (_, low, high) = TargetParams::RANGES[i];
        ((x * 1e4).round() / 1e4).clamp(low, high)
    };
    TargetParams {
        falloff: clamp(0, 2.0 * y[0].abs()),
        wall_weight: clamp(1, TargetParams::RULE.wall_weight * y[1].exp()),
        wall_range: clamp(2, 1.0 - 0.5 * y[2].abs()),
        lead_s: clamp(3, y[3]),
        open_pull: clamp(4, y[4].abs()),
    }
}

/// Plays `params` against every panel team.
pub fn play_candidate(
    settings: &TuneSettings,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
    params: TargetParams,
    generation: usize,
) -> Result<Candidate, TuneError> {
    let target = ControllerSpec::Tuned(params);
    let mut capture = Vec::new();
    for team in &settings.panel {
        let setting = EvalSetting {
            captors: team.clone(),
            target: target.clone(),
            num_captors: settings.num_captors,
            speed_ratio: settings.speed_ratio,
            episodes: settings.episodes,
            episode_length: settings.episode_length,
            seed: settings.eval_seed,
            soa_every: 0,
            capture_rule: t2e_core::env::CaptureRule::Fast,
        };
        let (summary, _) =
            run_setting(&setting, maps, "panel", false).map_err(|e| TuneError::Play {
                team: team.to_string(),
                target: target.to_string(),
                cause: e.into(),
            })?;
        capture.push(summary.sr);
    }
    let worst = capture.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    Ok(Candidate {
        generation,
        target: target.to_string(),
        params: params.to_array(),
        capture,
        worst,
    })
}

/// Runs the search; `on_candidate` sees each candidate as it is played.
pub fn tune(
    settings: &TuneSettings,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
    mut on_candidate: impl FnMut(&Candidate),
) -> Result<TuneOutcome, TuneError> {
    if settings.panel.is_empty() {
        return Err(TuneError::Setting(
            "--panel: at least one captor team".into(),
        ));
    }
    if settings.generations == 0 || settings.population < 2 {
        return Err(TuneError::Setting(format!(
            "--generations {} / --population {}: at least one generation of at least 2 candidates",
            settings.generations, settings.population
        )));
    }
    if !(settings.sigma.is_finite() && settings.sigma > 0.0) {
        return Err(TuneError::Setting(format!(
            "--sigma {}: a positive step size",
            settings.sigma
        )));
    }
    let rule = play_candidate(settings, maps, TargetParams::RULE, 0)?;
    on_candidate(&rule);
    let mut candidates: Vec<Candidate> = Vec::new();
    let mut failure: Option<TuneError> = None;
    let mut generation = 1;
    {
        let objective = |y: &DVector<f64>| -> f64 {
            if failure.is_some() {
                return f64::NAN;
            }
            let n_per_gen = settings.population;
            let g = 1 + candidates.len() / n_per_gen;
            match play_candidate(settings, maps, params_at(y.as_slice()), g) {
                Ok(c) => {
                    on_candidate(&c);
                    let w = c.worst;
                    candidates.push(c);
                    w
                }
                Err(e) => {
                    failure = Some(e);
                    f64::NAN
                }
            }
        };
        let mut search = CMAESOptions::new(vec![0.0; 5], settings.sigma)
            .population_size(settings.population)
            .max_generations(settings.generations)
            .seed(settings.search_seed)
            .build(objective)
            .map_err(|e| TuneError::Setting(format!("CMA-ES refused its options: {e:?}")))?;
        while generation <= settings.generations {
            if search.next().is_some() {
                break;
            }
            generation += 1;
        }
    }
    if let Some(e) = failure {
        return Err(e);
    }
    // The rule first: a candidate must be strictly better to be chosen.
    let best = std::iter::once(&rule)
        .chain(&candidates)
        .min_by(|a, b| a.worst.total_cmp(&b.worst))
        .cloned()
        .expect("the rule is a candidate");
    let best_params = best.params;
    Ok(TuneOutcome {
        candidates,
        rule,
        best,
        best_params,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_search_spaces_origin_is_the_rule_and_every_point_is_in_range() {
        assert_eq!(params_at(&[0.0; 5]), TargetParams::RULE);
        for y in [[9.0, -9.0, 9.0, -9.0, 9.0], [-9.0, 9.0, -9.0, 9.0, -9.0]] {
            let p = params_at(&y);
            assert!(TargetParams::from_array(p.to_array()).is_ok(), "{p:?}");
        }
        assert_eq!(params_at(&[1.0, 0.0, 0.0, 0.0, 0.0]).falloff, 2.0);
    }
}
