//! `[evaluator]` in a league's config: which panels every snapshot plays,
//! for how many episodes, on which maps. A config type, read by the config,
//! the league folder and the evaluator process alike, so it lives with the
//! configs rather than in the process that plays the panels.

use serde::{Deserialize, Serialize};
use t2e_core::env::Side;
use t2e_core::error::{in_interval, in_range, ConfigError};
use t2e_learners::controllers::ControllerSpec;

/// The test panel's ASZ-greedy team is `greedy:2` (0.1 m cells): the one
/// `greedy:K` validation may not play, so the test stays unseen.
pub const TEST_GREEDY_COARSENING: usize = 2;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EvaluatorConfig {
    /// Run the evaluator process at all.
    pub enabled: bool,
    /// Episodes each snapshot plays against each panel member.
    pub episodes: usize,
    /// Share of one core the evaluator may use (it sleeps the rest).
    pub cpu_share: f64,
    /// Held-out opponents of the target snapshots: captor controllers
    /// (`greedy:2`, `ckpt:PATH` of a team trained elsewhere) that play the
    /// panel but never the league, so the league's target never trained
    /// against them. Their episodes are kept apart from the matches (no
    /// rating, no draw). Empty by default (an ASZ-greedy episode costs
    /// seconds); stored only when set.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub held_out_captors: Vec<String>,
    /// Held-out opponents of the captor snapshots (target controllers), as
    /// `held_out_captors`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub held_out_targets: Vec<String>,
    /// The validation panel's maps (`generated:N@S`, a folder): never a
    /// Gibson test map (under either protocol) and never a training map.
    /// Validation chooses what `export --best` exports, so it shares no
    /// map and no team with the test. Stored only when set.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub validation_maps: Option<String>,
    /// The validation teams of the target snapshots: captor controllers
    /// the league never meets and no test panel holds (`expert:SEED`, the
    /// expert captors with randomised constants; `ckpt:PATH` of a team
    /// trained elsewhere, such as a cooperative team of another seed or
    /// naive co-evolution's captors; `greedy:K` for K other than 2, a
    /// relative of the ASZ planner the test plays). Not the expert (a
    /// member) and not `greedy:2` (the test's team). Stored only when set.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub validation_captors: Vec<String>,
    /// The validation opponents of the captor snapshots (target
    /// controllers), as `validation_captors`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub validation_targets: Vec<String>,
}

impl Default for EvaluatorConfig {
    fn default() -> Self {
        EvaluatorConfig {
            enabled: true,
            episodes: 20,
            cpu_share: 0.25,
            held_out_captors: Vec::new(),
            held_out_targets: Vec::new(),
            validation_maps: None,
            validation_captors: Vec::new(),
            validation_targets: Vec::new(),
        }
    }
}

impl EvaluatorConfig {
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_interval("cpu_share", self.cpu_share, 0.0, 1.0, false)?;
        if self.enabled && self.episodes == 0 {
            return Err(ConfigError::new(
                "episodes",
                0,
                "every snapshot must play at least one panel episode (or set enabled = false)",
            ));
        }
        in_range("episodes", self.episodes, 0..=100_000, "at most 100000")?;
        for side in [Side::Captors, Side::Target] {
            self.held_out(side)?;
            let validation = self.validation(side)?;
            let held_out = self.held_out(side)?;
            if let Some((name, _)) = validation
                .iter()
                .find(|(_, v)| held_out.iter().any(|(_, h)| h == v))
            {
                return Err(ConfigError::new(
                    Self::validation_field(side),
                    format!("\"{name}\""),
                    "also a held-out opponent; validation shares no team with another panel",
                ));
            }
        }
        let teams = !(self.validation_captors.is_empty() && self.validation_targets.is_empty());
        match &self.validation_maps {
            None if teams => {
                return Err(ConfigError::about("validation_captors / validation_targets", "need validation_maps: validation plays on maps that are neither trained on nor tested on (e.g. \"generated:8@1001\")"))
            }
            Some(spec) if !teams => {
                return Err(ConfigError::new("validation_maps", format!("\"{spec}\""), "no validation team to play there (set validation_captors or validation_targets)"))
            }
            Some(spec) => {
                let source = spec.split(':').next().unwrap_or_default();
                if matches!(source, "gibson" | "small" | "medium" | "large") {
                    return Err(ConfigError::new("validation_maps", format!("\"{spec}\""), "the Gibson maps are the test maps under either protocol; validation never plays on a test map (use generated:N@S or a folder of your own)"));
                }
            }
            None => {}
        }
        Ok(())
    }

    fn validation_field(member_side: Side) -> &'static str {
        match member_side {
            Side::Target => "validation_captors",
            Side::Captors => "validation_targets",
        }
    }

    /// The validation opponents of `member_side`'s snapshots, parsed.
    pub fn validation(
        &self,
        member_side: Side,
    ) -> Result<Vec<(String, ControllerSpec)>, ConfigError> {
        let names = match member_side {
            Side::Target => &self.validation_captors,
            Side::Captors => &self.validation_targets,
        };
        let side = member_side.other();
        let specs = ControllerSpec::parse_list(
            Self::validation_field(member_side),
            names,
            side,
            |spec| {
                match spec {
            ControllerSpec::Heuristic => Some(format!(
                "the {} is a member of the league, which it trains against; validation plays teams the league never meets",
                match side {
                    Side::Captors => "expert heuristic",
                    Side::Target => "rule-based target",
                }
            )),
            ControllerSpec::Greedy { coarsening: TEST_GREEDY_COARSENING } => Some(
                "the ASZ-greedy planner on 0.1 m cells is the test panel's team; validation shares no team with the test (a relative of it, greedy:3 or greedy:4, is not the test's team; or expert:SEED, or a trained team)"
                    .into(),
            ),
            _ => None,
        }
            },
        )?;
        Ok(specs
            .into_iter()
            .map(|spec| (spec.to_string(), spec))
            .collect())
    }

    /// The held-out opponents that play `member_side`'s snapshots, parsed.
    pub fn held_out(
        &self,
        member_side: Side,
    ) -> Result<Vec<(String, ControllerSpec)>, ConfigError> {
        let (field, names) = match member_side {
            Side::Target => ("held_out_captors", &self.held_out_captors),
            Side::Captors => ("held_out_targets", &self.held_out_targets),
        };
        let side = member_side.other();
        // A checkpoint is loaded (and checked) when the evaluator starts.
        let specs = ControllerSpec::parse_list(field, names, side, |spec| {
            (*spec == ControllerSpec::Heuristic).then(|| {
                format!(
                    "the {} is a permanent league member, which the league trains against; a held-out opponent is one it never meets",
                    match side {
                        Side::Captors => "expert heuristic",
                        Side::Target => "rule-based target",
                    }
                )
            })
        })?;
        Ok(specs
            .into_iter()
            .map(|spec| (spec.to_string(), spec))
            .collect())
    }
}
