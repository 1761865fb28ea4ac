//! The evaluator's panels as a league's config names them: the held-out
//! and validation teams per member side, each checked against the league's
//! game, and the validation maps, checked to hold no test map. Loaded by
//! `run` before a new league is stored (preflight) and by the evaluator.

use crate::rules::config::LeagueConfig;
use crate::store::Panel;
use std::sync::Arc;
use t2e_core::env::Side;
use t2e_core::error::ConfigError;
use t2e_core::map::PreparedMap;
use t2e_learners::controllers::ControllerSpec;

/// Each member side's opponents on one panel: (name, controller).
pub type PanelTeams = Vec<(Side, Vec<(String, ControllerSpec)>)>;

/// The controllers of the held-out and validation panels, per member side.
pub struct Panels {
    pub held_out: PanelTeams,
    pub validation: PanelTeams,
    /// The validation maps (empty when there is no validation panel).
    pub validation_maps: Arc<Vec<Arc<PreparedMap>>>,
}

/// The held-out and validation opponents per member side, checkpoints
/// loaded and checked against the league's game, and the validation maps,
/// checked to hold no test map.
pub fn load_panels(cfg: &LeagueConfig) -> Result<Panels, ConfigError> {
    let env = t2e_core::env::EnvConfig {
        num_captors: cfg.num_captors,
        target_speed: cfg.curriculum.stages[0],
        episode_length: cfg.episode_length,
        ..t2e_core::env::EnvConfig::default()
    };
    let load = |panel: Panel| -> Result<PanelTeams, ConfigError> {
        [Side::Captors, Side::Target]
            .into_iter()
            .map(|member_side| {
                let specs = match panel {
                    Panel::HeldOut => cfg.evaluator.held_out(member_side),
                    Panel::Validation => cfg.evaluator.validation(member_side),
                }
                .map_err(|e| e.within("evaluator"))?;
                for (name, spec) in &specs {
                    spec.check(member_side.other(), &env).map_err(|e| {
                        ConfigError::new(
                            format!("evaluator {} opponent", panel.name()),
                            format!("\"{name}\""),
                            e.to_string(),
                        )
                    })?;
                }
                Ok((member_side, specs))
            })
            .collect()
    };
    let validation_maps = match &cfg.evaluator.validation_maps {
        None => Arc::new(Vec::new()),
        Some(spec) => {
            let maps = t2e_core::map::catalog::load_prepared(spec).map_err(|e| {
                ConfigError::new(
                    "evaluator.validation_maps",
                    format!("\"{spec}\""),
                    format!("{e:#}"),
                )
            })?;
            t2e_core::protocol::check_extra_maps(spec, &maps)
                .map_err(|e| ConfigError::about("evaluator.validation_maps", e.to_string()))?;
            maps
        }
    };
    Ok(Panels {
        held_out: load(Panel::HeldOut)?,
        validation: load(Panel::Validation)?,
        validation_maps,
    })
}
