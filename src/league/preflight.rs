//! The checks of a new league's config that need its maps or checkpoints
//! loaded, run by `run` before the league's store or folder is written: a
//! setting refused here costs nothing, while one refused by a process
//! after training began throws the league away (its config is fixed once
//! stored).
//!
//! Maps are compared by content (`Grid::content_hash`), not by how the
//! config spells them: `"maps"` by path while training on `"shipped"`,
//! `"shipped:small"`, or a folder generated with the training seeds are
//! all the training maps. Checkpoints are compared by canonical path and
//! by the hashes of their weights, so `x/../team` is `team`.

use super::config::LeagueConfig;
use crate::controllers::ControllerSpec;
use crate::env::Side;
use crate::error::ConfigError;
use crate::map::PreparedMap;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Every check `run` owes a new league before its first env step, with
/// `training` the league's training maps, loaded.
pub fn check_new_league(
    cfg: &LeagueConfig,
    training: &[Arc<PreparedMap>],
) -> Result<(), ConfigError> {
    if cfg.evaluator.enabled {
        let panels = super::evaluator::load_panels(cfg)?;
        check_maps_apart(
            "evaluator.validation_maps",
            cfg.evaluator.validation_maps.as_deref().unwrap_or(""),
            &panels.validation_maps,
            &cfg.maps,
            training,
        )?;
    }
    check_validation_teams_apart(cfg)
}

/// No map of `validation` is, by content, a map of `training`.
pub fn check_maps_apart(
    field: &str,
    spec: &str,
    validation: &[Arc<PreparedMap>],
    training_spec: &str,
    training: &[Arc<PreparedMap>],
) -> Result<(), ConfigError> {
    let trained: BTreeMap<String, &str> = training
        .iter()
        .map(|m| (m.grid.content_hash(), m.grid.name.as_str()))
        .collect();
    let shared: Vec<String> = validation
        .iter()
        .filter_map(|m| {
            trained.get(&m.grid.content_hash()).map(|t| {
                if *t == m.grid.name {
                    t.to_string()
                } else {
                    format!("{} (= {t})", m.grid.name)
                }
            })
        })
        .collect();
    if shared.is_empty() {
        return Ok(());
    }
    let shown: Vec<&str> = shared.iter().take(5).map(String::as_str).collect();
    Err(ConfigError::new(
        field,
        format!("\"{spec}\""),
        format!(
            "{} of its {} maps are training maps (maps = \"{training_spec}\"), compared by content: {}{}; validation plays maps the league never trained on (e.g. generated:8@1001)",
            shared.len(),
            validation.len(),
            shown.join(", "),
            if shared.len() > shown.len() { ", ..." } else { "" }
        ),
    ))
}

/// What a checkpoint is, whatever its spelling: its canonical folder and
/// the hashes of its files (meta.json's list), when readable.
#[derive(Debug, Clone, PartialEq)]
struct CheckpointIdentity {
    canonical: PathBuf,
    files: Option<BTreeMap<String, String>>,
}

impl CheckpointIdentity {
    fn of(path: &Path) -> CheckpointIdentity {
        CheckpointIdentity {
            canonical: path.canonicalize().unwrap_or_else(|_| path.to_path_buf()),
            files: crate::nn::checkpoint::read_meta(path)
                .ok()
                .map(|m| m.files)
                .filter(|f| !f.is_empty()),
        }
    }

    fn same(&self, other: &CheckpointIdentity) -> bool {
        self.canonical == other.canonical || (self.files.is_some() && self.files == other.files)
    }
}

/// No validation team is a league member, checkpoints compared by what
/// they are rather than by their spelling.
fn check_validation_teams_apart(cfg: &LeagueConfig) -> Result<(), ConfigError> {
    for member_side in [Side::Target, Side::Captors] {
        let validation = cfg
            .evaluator
            .validation(member_side)
            .map_err(|e| e.within("evaluator"))?;
        let members = cfg
            .members
            .of(member_side.other())
            .map_err(|e| e.within("members"))?;
        let member_ids: Vec<(String, CheckpointIdentity)> = members
            .iter()
            .filter_map(|(name, spec)| match spec {
                ControllerSpec::Checkpoint(c) => {
                    Some((name.clone(), CheckpointIdentity::of(&c.path)))
                }
                _ => None,
            })
            .collect();
        for (name, spec) in &validation {
            let ControllerSpec::Checkpoint(c) = spec else {
                continue;
            };
            let id = CheckpointIdentity::of(&c.path);
            if let Some((member, _)) = member_ids.iter().find(|(_, m)| m.same(&id)) {
                return Err(ConfigError::new(
                    match member_side {
                        Side::Target => "evaluator.validation_captors",
                        Side::Captors => "evaluator.validation_targets",
                    },
                    format!("\"{name}\""),
                    format!("the same checkpoint as the member {member} ([members], by its folder and weights), which the league trains against; validation plays teams the league never meets"),
                ));
            }
        }
    }
    Ok(())
}
