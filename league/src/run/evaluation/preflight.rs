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

use crate::rules::config::LeagueConfig;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use t2e_core::env::Side;
use t2e_core::error::ConfigError;
use t2e_core::map::PreparedMap;
use t2e_learners::controllers::ControllerSpec;

/// Every check `run` owes a new league before its first env step, with
/// `training` the league's training maps, loaded.
pub fn check_new_league(
    cfg: &LeagueConfig,
    training: &[Arc<PreparedMap>],
) -> Result<(), ConfigError> {
    if !cfg.evaluator.enabled && cfg.evaluator.validation_maps.is_some() {
        tracing::warn!(
            "[evaluator] enabled = false: its validation panel (validation_maps = \"{}\") will never be played, so `export --best` will have nothing to choose by",
            cfg.evaluator.validation_maps.as_deref().unwrap_or("")
        );
    }
    if cfg.evaluator.enabled {
        let panels = crate::run::evaluation::panels::load_panels(cfg)?;
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
            files: t2e_learners::nn::checkpoint::read_meta(path)
                .ok()
                .map(|m| m.files)
                .filter(|f| !f.is_empty()),
        }
    }

    fn same(&self, other: &CheckpointIdentity) -> bool {
        self.canonical == other.canonical || (self.files.is_some() && self.files == other.files)
    }
}

/// No team is in two of the three roles a league gives the other side's
/// teams (a member it trains against, a held-out test team, a validation
/// team), checkpoints compared by what they are rather than by their
/// spelling: `x/../team`, or a byte copy of it, is `team`.
fn check_validation_teams_apart(cfg: &LeagueConfig) -> Result<(), ConfigError> {
    for member_side in [Side::Target, Side::Captors] {
        let (validation_field, held_out_field) = match member_side {
            Side::Target => ("evaluator.validation_captors", "evaluator.held_out_captors"),
            Side::Captors => ("evaluator.validation_targets", "evaluator.held_out_targets"),
        };
        let members_field = match member_side.other() {
            Side::Captors => "members.captors",
            Side::Target => "members.target",
        };
        let lists = [
            (
                members_field,
                "a member of the league, which it trains against",
                cfg.members
                    .of(member_side.other())
                    .map_err(|e| e.within("members"))?,
            ),
            (
                held_out_field,
                "a held-out test team",
                cfg.evaluator
                    .held_out(member_side)
                    .map_err(|e| e.within("evaluator"))?,
            ),
            (
                validation_field,
                "a validation team",
                cfg.evaluator
                    .validation(member_side)
                    .map_err(|e| e.within("evaluator"))?,
            ),
        ];
        let checkpoints: Vec<(usize, &str, CheckpointIdentity)> = lists
            .iter()
            .enumerate()
            .flat_map(|(i, (_, _, specs))| {
                specs.iter().filter_map(move |(name, spec)| match spec {
                    ControllerSpec::Checkpoint(c) => {
                        Some((i, name.as_str(), CheckpointIdentity::of(&c.path)))
                    }
                    _ => None,
                })
            })
            .collect();
        for (a, (list_a, name_a, id_a)) in checkpoints.iter().enumerate() {
            for (list_b, name_b, id_b) in &checkpoints[a + 1..] {
                if list_a != list_b && id_a.same(id_b) {
                    let (field_b, role_a) = (lists[*list_b].0, lists[*list_a].1);
                    return Err(ConfigError::new(
                        field_b,
                        format!("\"{name_b}\""),
                        format!(
                            "the same checkpoint (by its folder and weights) as \"{name_a}\", {role_a} ({}); a team plays one role: validation and test teams are ones the league never meets",
                            lists[*list_a].0
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}
