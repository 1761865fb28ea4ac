//! The league's permanent members: each side's default heuristic (the
//! expert captors, the rule-based target) and the extra ones a config adds
//! (`[members] captors = ["greedy:4", "ckpt:runs/coop-s1"]`): heuristics,
//! and trained teams imported once as frozen copies (`pool::ensure_members`).
//! A member is in every learner's pool, drawn by PFSP and rated like a
//! snapshot, and never trains. Which teams are members and which are held
//! out is a decision every table states: a member cannot also be a held-out
//! opponent.

use crate::rules::players::heuristic_name;
use serde::{Deserialize, Serialize};
use t2e_core::env::Side;
use t2e_core::error::ConfigError;
use t2e_learners::controllers::ControllerSpec;

/// Extra permanent members, per side, as controller names: heuristics
/// (`greedy:K`, `random`, `still`) and trained teams (`ckpt:PATH`, a
/// checkpoint or a run folder's latest). Empty by default; stored only when
/// set.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MembersConfig {
    /// Captor teams the target learners train against, beside the expert
    /// captors (an ASZ-greedy planner: `greedy:4` decides in about 1 ms for
    /// 3 captors, `greedy:2` in 4 ms; or a trained team, `ckpt:PATH`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub captors: Vec<String>,
    /// Targets the captor learners train against, beside the rule-based
    /// target.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub target: Vec<String>,
}

impl MembersConfig {
    pub fn is_empty(&self) -> bool {
        self.captors.is_empty() && self.target.is_empty()
    }

    /// Every permanent member of `side`: (player name, controller), the
    /// default heuristic first. Errors name the field.
    pub fn of(&self, side: Side) -> Result<Vec<(String, ControllerSpec)>, ConfigError> {
        let (field, names) = match side {
            Side::Captors => ("captors", &self.captors),
            Side::Target => ("target", &self.target),
        };
        let extras = ControllerSpec::parse_list(field, names, side, |spec| {
            if *spec == ControllerSpec::Heuristic {
                Some(format!(
                    "{} is already a member of every league",
                    heuristic_name(side)
                ))
            } else if matches!(spec, ControllerSpec::Checkpoint(c) if c.sampled) {
                Some("a trained member plays as the league's snapshots do (`greedy_opponents`): name it `ckpt:PATH`".into())
            } else {
                None
            }
        })?;
        let mut out = vec![(heuristic_name(side), ControllerSpec::Heuristic)];
        for spec in extras {
            let name = member_name(&spec, side);
            if out.iter().any(|(n, _)| *n == name) {
                return Err(ConfigError::new(
                    field,
                    format!("\"{spec}\""),
                    format!("its player name {name} is another member's (two checkpoints of one name: give one another folder)"),
                ));
            }
            out.push((name, spec));
        }
        Ok(out)
    }

    /// The player names of `side`'s extra members (all but the default
    /// heuristic): the ones `matchmaking.members_share` draws.
    pub fn extra_names(&self, side: Side) -> Vec<String> {
        self.of(side)
            .map(|all| all.into_iter().skip(1).map(|(n, _)| n).collect())
            .unwrap_or_default()
    }

    /// The controller of the heuristic member called `player`, if it is one.
    pub fn spec_of(&self, side: Side, player: &str) -> Option<ControllerSpec> {
        self.of(side)
            .ok()?
            .into_iter()
            .find(|(n, _)| n == player)
            .map(|(_, spec)| spec)
    }

    /// Checks both sides, and that no member is also held out (`held_out`:
    /// the evaluator's held-out controllers of each side).
    pub fn validate(
        &self,
        held_out: &[(Side, Vec<(String, ControllerSpec)>)],
    ) -> Result<(), ConfigError> {
        for side in [Side::Captors, Side::Target] {
            for (_, spec) in self.of(side)?.iter().skip(1) {
                let clash = held_out
                    .iter()
                    .filter(|(s, _)| *s == side)
                    .flat_map(|(_, specs)| specs)
                    .any(|(_, h)| h == spec);
                if clash {
                    return Err(ConfigError::new(
                        match side {
                            Side::Captors => "captors",
                            Side::Target => "target",
                        },
                        format!("\"{spec}\""),
                        "also a held-out opponent of the evaluator: a held-out opponent is one the league never trains against",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// An extra member's player name: its controller and side
/// (`greedy:4-captors`); for a trained team, its folder
/// (`ckpt:runs/coop-s1` is `coop-s1-captors`, a checkpoint inside a run's
/// `checkpoints/` is `RUN@CHECKPOINT-captors`). A name is also the member's
/// folder under `players/`, so anything but letters, digits, `.`, `_`, `-`
/// and `@` becomes `_`.
fn member_name(spec: &ControllerSpec, side: Side) -> String {
    let stem = match spec {
        ControllerSpec::Checkpoint(c) => {
            let parts: Vec<String> = c
                .path
                .components()
                .filter_map(|p| match p {
                    std::path::Component::Normal(s) => Some(s.to_string_lossy().into_owned()),
                    _ => None,
                })
                .collect();
            let stem = match parts.as_slice() {
                [.., run, dir, ckpt] if dir == "checkpoints" => format!("{run}@{ckpt}"),
                [.., last] => last.clone(),
                [] => "checkpoint".into(),
            };
            stem.chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || "._-@".contains(c) {
                        c
                    } else {
                        '_'
                    }
                })
                .collect()
        }
        _ => spec.to_string(),
    };
    format!("{stem}-{}", side.name())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn members(captors: &[&str], target: &[&str]) -> MembersConfig {
        MembersConfig {
            captors: captors.iter().map(|s| s.to_string()).collect(),
            target: target.iter().map(|s| s.to_string()).collect(),
        }
    }

    #[test]
    fn the_default_member_comes_first_and_extras_are_named_by_controller_and_side() {
        let m = members(&["greedy:4", "random"], &["still"]);
        let captors: Vec<String> = m
            .of(Side::Captors)
            .unwrap()
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        assert_eq!(
            captors,
            ["expert-captors", "greedy:4-captors", "random-captors"]
        );
        let target: Vec<String> = m
            .of(Side::Target)
            .unwrap()
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        assert_eq!(target, ["rule-based-target", "still-target"]);
        assert_eq!(
            m.spec_of(Side::Captors, "greedy:4-captors"),
            Some(ControllerSpec::Greedy { coarsening: 4 })
        );
        assert_eq!(
            m.spec_of(Side::Captors, "expert-captors"),
            Some(ControllerSpec::Heuristic)
        );
        assert_eq!(m.spec_of(Side::Captors, "captors-main"), None);
        assert_eq!(MembersConfig::default().of(Side::Target).unwrap().len(), 1);
        assert_eq!(m.extra_names(Side::Target), ["still-target"]);
    }

    #[test]
    fn a_trained_member_is_named_by_its_folder() {
        let m = members(
            &[
                "ckpt:runs/coop-s1",
                "ckpt:../runs/coop-s2/checkpoints/captors-000004800000/",
                "ckpt:/tmp/odd name!",
            ],
            &[],
        );
        assert_eq!(
            m.extra_names(Side::Captors),
            [
                "coop-s1-captors",
                "coop-s2@captors-000004800000-captors",
                "odd_name_-captors"
            ]
        );
        assert!(m
            .spec_of(Side::Captors, "coop-s1-captors")
            .unwrap()
            .is_checkpoint());
    }

    #[test]
    fn a_bad_member_is_refused_naming_the_field() {
        for (m, field) in [
            (members(&["greedy:0"], &[]), "captors = \"greedy:0\""),
            (
                members(&["greedy:4", "greedy:4"], &[]),
                "captors: \"greedy:4\" is named twice",
            ),
            (members(&[], &["greedy:9"]), "target = \"greedy:9\""),
            (members(&["expert"], &[]), "already a member"),
            (members(&["sample:runs/x"], &[]), "name it `ckpt:PATH`"),
            (
                members(&["ckpt:a/coop", "ckpt:b/coop"], &[]),
                "its player name coop-captors is another member's",
            ),
            (members(&["nonsense"], &[]), "unknown controller"),
        ] {
            let err = m.validate(&[]).unwrap_err().to_string();
            assert!(err.contains(field), "{err}");
        }
    }

    #[test]
    fn a_member_cannot_also_be_held_out() {
        let m = members(&["greedy:2"], &[]);
        let held_out = vec![(
            Side::Captors,
            vec![(
                "greedy:2".to_string(),
                ControllerSpec::Greedy { coarsening: 2 },
            )],
        )];
        let err = m.validate(&held_out).unwrap_err().to_string();
        assert!(
            err.contains("captors = \"greedy:2\": also a held-out opponent"),
            "{err}"
        );
        // A different planner's resolution is a different controller.
        let other = members(&["greedy:4"], &[]);
        other.validate(&held_out).unwrap();
    }
}
