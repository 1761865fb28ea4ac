//! The league's permanent heuristic members: each side's default one (the
//! expert captors, the rule-based target) and the extra ones a config adds
//! (`[members] captors = ["greedy:4"]`). A member is in every learner's
//! pool, drawn by PFSP and rated like a snapshot, and never trains. Which
//! heuristics are members and which are held out is a decision every table
//! states: a member cannot also be a held-out opponent.

use super::players::heuristic_name;
use crate::controllers::ControllerSpec;
use crate::env::Side;
use serde::{Deserialize, Serialize};

/// Extra permanent heuristic members, per side, as controller names
/// (`greedy:K`, `random`, `still`). Empty by default; stored only when set.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MembersConfig {
    /// Heuristic captor teams the target learners train against, beside
    /// the expert captors (an ASZ-greedy planner: `greedy:4` decides in
    /// about 1 ms for 3 captors, `greedy:2` in 4 ms).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub captors: Vec<String>,
    /// Heuristic targets the captor learners train against, beside the
    /// rule-based target.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub target: Vec<String>,
}

impl MembersConfig {
    pub fn is_empty(&self) -> bool {
        self.captors.is_empty() && self.target.is_empty()
    }

    /// Every permanent heuristic member of `side`: (player name, controller),
    /// the default one first. Errors name the field.
    pub fn of(&self, side: Side) -> Result<Vec<(String, ControllerSpec)>, String> {
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
            } else if spec.is_checkpoint() {
                Some("a member here is a heuristic (greedy:K, random, still); a trained team joins the pool as a snapshot".into())
            } else {
                None
            }
        })?;
        let mut out = vec![(heuristic_name(side), ControllerSpec::Heuristic)];
        out.extend(
            extras
                .into_iter()
                .map(|spec| (member_name(&spec, side), spec)),
        );
        Ok(out)
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
    ) -> Result<(), String> {
        for side in [Side::Captors, Side::Target] {
            for (_, spec) in self.of(side)?.iter().skip(1) {
                let clash = held_out
                    .iter()
                    .filter(|(s, _)| *s == side)
                    .flat_map(|(_, specs)| specs)
                    .any(|(_, h)| h == spec);
                if clash {
                    return Err(format!(
                        "{} = \"{spec}\" is also a held-out opponent of the evaluator: a held-out opponent is one the league never trains against",
                        match side {
                            Side::Captors => "captors",
                            Side::Target => "target",
                        }
                    ));
                }
            }
        }
        Ok(())
    }
}

/// An extra member's player name: its controller and side
/// (`greedy:4-captors`).
fn member_name(spec: &ControllerSpec, side: Side) -> String {
    format!("{spec}-{}", side.name())
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
            (
                members(&["ckpt:runs/x"], &[]),
                "a trained team joins the pool",
            ),
            (members(&["nonsense"], &[]), "unknown controller"),
        ] {
            let err = m.validate(&[]).unwrap_err();
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
        let err = m.validate(&held_out).unwrap_err();
        assert!(
            err.contains("captors = \"greedy:2\" is also a held-out opponent"),
            "{err}"
        );
        // A different planner's resolution is a different controller.
        let other = members(&["greedy:4"], &[]);
        other.validate(&held_out).unwrap();
    }
}
