//! The controller catalogue: every controller a user can name on the command
//! line or in a config (`heuristic`, `greedy`, `expert:SEED`, `lookahead:H`, `robust:H:MODELS`,
//! `random`, `still`, `ckpt:PATH`, `sample:PATH`), parsed and built behind the one `env::Controller` trait. It
//! sits above `heuristics` and `nn` because it names controllers of both.

use crate::nn::{CheckpointController, PolicySnapshot};
use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;
use std::sync::{Arc, OnceLock};
use t2e_core::env::{Controller, EnvConfig, Side};
use t2e_core::error::ConfigError;
use t2e_core::heuristics::{
    AszGreedy, Heuristic, Lookahead, RandomActions, RandomisedExpert, RobustLookahead, Still,
    TargetParams, TunedTarget,
};

/// Why a controller cannot be named, loaded or built for a side.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ControllerError {
    #[error("'{0}': the ASZ-greedy coarsening must be a whole number of map cells from 1 to {max} (greedy:2 marches on 0.10 m cells)", max = AszGreedy::MAX_COARSENING)]
    Coarsening(String),
    #[error(
        "'{0}': expert:SEED needs a whole number SEED (expert captors with randomised constants)"
    )]
    ExpertSeed(String),
    #[error("'{0}:' needs a path: {0}:runs/NAME (newest checkpoint) or {0}:runs/NAME/checkpoints/SIDE-STEPS")]
    MissingPath(&'static str),
    #[error("'{0}': lookahead:H[:CAPTORS] needs a horizon H of 1 to {max} steps, and CAPTORS a captor team (lookahead:10 plays against the expert captors, lookahead:10:greedy:2 against greedy:2)", max = Lookahead::MAX_HORIZON)]
    Lookahead(String),
    #[error("'{0}': robust:H:MODELS needs a horizon H of 1 to {max} steps and 1 to {models} captor teams joined by '+' (robust:10:heuristic+expert:1+greedy:3); a model is no lookahead or robust target", max = Lookahead::MAX_HORIZON, models = RobustLookahead::MAX_MODELS)]
    Robust(String),
    #[error("'{0}' plays the target only (it looks ahead against a model of the captors)")]
    LookaheadAsCaptors(String),
    #[error("'{0}' plays the target only (a hand-made target of the rule-based target's family)")]
    TunedAsCaptors(String),
    #[error("'{0}': tuned:FALLOFF,WALL,RANGE,LEAD,OPEN takes five numbers, the rule-based target's constants (tuned:0,0.6,1,0,0 is the rule): {1}")]
    Tuned(String, String),
    #[error("unknown controller '{0}' (expected heuristic, greedy, greedy:K, expert:SEED, lookahead:H[:CAPTORS], robust:H:MODELS, tuned:F,W,R,L,O, random, still, ckpt:PATH or sample:PATH)")]
    Unknown(String),
    #[error("expert:{0} is a captor team (the expert captors with randomised constants); it cannot play the target")]
    ExpertAsTarget(u64),
    /// The checkpoint's loader refused it; its message names the file.
    #[error("{0}")]
    Checkpoint(String),
    #[error("'{0}' reads a checkpoint: a prior's planner is part of the network that leans on it, so it must be a scripted target (robust:H:MODELS of scripted teams, lookahead:H, tuned:..., heuristic), whose every input travels with the checkpoint's meta.json")]
    NotScripted(String),
}

/// A controller as named on the command line.
#[derive(Clone, Debug, PartialEq)]
pub enum ControllerSpec {
    Heuristic,
    /// `greedy` or `greedy:K`: the ASZ-greedy captor marching on cells of
    /// K x K map cells (1, the spec's, when not given).
    Greedy {
        coarsening: usize,
    },
    /// `expert:SEED`: expert captors with their constants drawn per
    /// episode (`heuristics::RandomisedExpert`); captors only.
    RandomisedExpert {
        seed: u64,
    },
    /// `lookahead:H` or `lookahead:H:CAPTORS`: the lookahead target
    /// (`heuristics::Lookahead`), simulating H steps of each action against
    /// CAPTORS (the expert captors when not given); target only.
    Lookahead {
        horizon: usize,
        captors: Box<ControllerSpec>,
    },
    /// `tuned:FALLOFF,WALL,RANGE,LEAD,OPEN`: a hand-made target of the
    /// rule-based target's family (`heuristics::TunedTarget`); target only.
    Tuned(TargetParams),
    /// `robust:H:M1+M2+...`: the robust lookahead target
    /// (`heuristics::RobustLookahead`), simulating H steps of each action
    /// against every captor team M1, M2, ...; target only.
    Robust {
        horizon: usize,
        models: Vec<ControllerSpec>,
    },
    Random,
    Still,
    /// `ckpt:PATH`: a trained policy (see `nn::checkpoint`), played
    /// greedily; `sample:PATH`: the same, sampling its actions.
    Checkpoint(CheckpointSpec),
}

/// A checkpoint named by the user, read from disk the first time a
/// controller is built and shared by all controllers built after.
#[derive(Clone, Debug)]
pub struct CheckpointSpec {
    pub path: PathBuf,
    /// Sample each action from the policy (seeded by the episode) instead
    /// of taking the most likely one, the paper's evaluation.
    pub sampled: bool,
    loaded: Arc<OnceLock<Result<Arc<PolicySnapshot>, ControllerError>>>,
}

impl PartialEq for CheckpointSpec {
    fn eq(&self, other: &Self) -> bool {
        self.path == other.path && self.sampled == other.sampled
    }
}

impl CheckpointSpec {
    pub fn new(path: impl Into<PathBuf>) -> CheckpointSpec {
        CheckpointSpec {
            path: path.into(),
            sampled: false,
            loaded: Arc::new(OnceLock::new()),
        }
    }

    /// The same checkpoint, its actions sampled.
    pub fn sampled(path: impl Into<PathBuf>) -> CheckpointSpec {
        CheckpointSpec {
            sampled: true,
            ..CheckpointSpec::new(path)
        }
    }

    /// The policy for `side`; the first call reads it from disk.
    pub fn snapshot(&self, side: Side) -> Result<Arc<PolicySnapshot>, ControllerError> {
        self.loaded
            .get_or_init(|| {
                PolicySnapshot::load(&self.path, side)
                    .map(Arc::new)
                    .map_err(|e| ControllerError::Checkpoint(format!("{e:#}")))
            })
            .clone()
    }
}

impl FromStr for ControllerSpec {
    type Err = ControllerError;
    fn from_str(s: &str) -> Result<Self, ControllerError> {
        match s.trim() {
            "heuristic" | "rule" | "expert" => Ok(ControllerSpec::Heuristic),
            "greedy" | "asz-greedy" => Ok(ControllerSpec::Greedy { coarsening: 1 }),
            other if other.starts_with("greedy:") => {
                let k = &other["greedy:".len()..];
                match k.parse::<usize>() {
                    Ok(k) if (1..=AszGreedy::MAX_COARSENING).contains(&k) => {
                        Ok(ControllerSpec::Greedy { coarsening: k })
                    }
                    _ => Err(ControllerError::Coarsening(other.to_string())),
                }
            }
            other if other.starts_with("expert:") => {
                match other["expert:".len()..].parse::<u64>() {
                    Ok(seed) => Ok(ControllerSpec::RandomisedExpert { seed }),
                    Err(_) => Err(ControllerError::ExpertSeed(other.to_string())),
                }
            }
            other if other.starts_with("lookahead:") => parse_lookahead(other),
            other if other.starts_with("robust:") => parse_robust(other),
            other if other.starts_with("tuned:") => parse_tuned(other),
            "random" => Ok(ControllerSpec::Random),
            "still" => Ok(ControllerSpec::Still),
            other if other.starts_with("ckpt:") => {
                let path = &other["ckpt:".len()..];
                if path.is_empty() {
                    return Err(ControllerError::MissingPath("ckpt"));
                }
                Ok(ControllerSpec::Checkpoint(CheckpointSpec::new(path)))
            }
            other if other.starts_with("sample:") => {
                let path = &other["sample:".len()..];
                if path.is_empty() {
                    return Err(ControllerError::MissingPath("sample"));
                }
                Ok(ControllerSpec::Checkpoint(CheckpointSpec::sampled(path)))
            }
            other => Err(ControllerError::Unknown(other.to_string())),
        }
    }
}

/// `lookahead:H[:MODEL]`; apart from `from_str` because its model is itself
/// a spec, parsed recursively.
fn parse_lookahead(other: &str) -> Result<ControllerSpec, ControllerError> {
    let rest = &other["lookahead:".len()..];
    let (horizon, captors) = match rest.split_once(':') {
        Some((h, model)) => (h, model.parse::<ControllerSpec>()?),
        None => (rest, ControllerSpec::Heuristic),
    };
    match horizon.parse::<usize>() {
        Ok(h)
            if (1..=Lookahead::MAX_HORIZON).contains(&h)
                && !matches!(captors, ControllerSpec::Lookahead { .. }) =>
        {
            Ok(ControllerSpec::Lookahead {
                horizon: h,
                captors: Box::new(captors),
            })
        }
        _ => Err(ControllerError::Lookahead(other.to_string())),
    }
}

/// `robust:H:M1+M2+...`; apart from `from_str` because of its rules on which
/// models a robust planner may imagine.
fn parse_robust(other: &str) -> Result<ControllerSpec, ControllerError> {
    let refuse = || ControllerError::Robust(other.to_string());
    let (horizon, models) = other["robust:".len()..]
        .split_once(':')
        .ok_or_else(refuse)?;
    let horizon = horizon
        .parse::<usize>()
        .ok()
        .filter(|h| (1..=Lookahead::MAX_HORIZON).contains(h))
        .ok_or_else(refuse)?;
    let models = models
        .split('+')
        .map(|m| m.parse::<ControllerSpec>())
        .collect::<Result<Vec<_>, _>>()?;
    let planner = |m: &ControllerSpec| {
        matches!(
            m,
            ControllerSpec::Lookahead { .. } | ControllerSpec::Robust { .. }
        )
    };
    if models.is_empty() || models.len() > RobustLookahead::MAX_MODELS || models.iter().any(planner)
    {
        return Err(refuse());
    }
    Ok(ControllerSpec::Robust { horizon, models })
}

/// `tuned:a,b,c,d,e`; apart from `from_str` because its five numbers are
/// checked by `TargetParams`.
fn parse_tuned(other: &str) -> Result<ControllerSpec, ControllerError> {
    let refuse = |why: String| ControllerError::Tuned(other.to_string(), why);
    let values = other["tuned:".len()..]
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| refuse(e.to_string()))?;
    let values: [f64; 5] = values
        .try_into()
        .map_err(|v: Vec<f64>| refuse(format!("{} values", v.len())))?;
    TargetParams::from_array(values)
        .map(ControllerSpec::Tuned)
        .map_err(refuse)
}

impl fmt::Display for ControllerSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ControllerSpec::Heuristic => f.write_str("heuristic"),
            ControllerSpec::Greedy { coarsening: 1 } => f.write_str("greedy"),
            ControllerSpec::Greedy { coarsening } => write!(f, "greedy:{coarsening}"),
            ControllerSpec::RandomisedExpert { seed } => write!(f, "expert:{seed}"),
            ControllerSpec::Lookahead { horizon, captors } => match **captors {
                ControllerSpec::Heuristic => write!(f, "lookahead:{horizon}"),
                ref model => write!(f, "lookahead:{horizon}:{model}"),
            },
            ControllerSpec::Robust { horizon, models } => {
                let names: Vec<String> = models.iter().map(|m| m.to_string()).collect();
                write!(f, "robust:{horizon}:{}", names.join("+"))
            }
            ControllerSpec::Tuned(p) => {
                let v = p.to_array().map(|x| x.to_string());
                write!(f, "tuned:{}", v.join(","))
            }
            ControllerSpec::Random => f.write_str("random"),
            ControllerSpec::Still => f.write_str("still"),
            ControllerSpec::Checkpoint(c) if c.sampled => write!(f, "sample:{}", c.path.display()),
            ControllerSpec::Checkpoint(c) => write!(f, "ckpt:{}", c.path.display()),
        }
    }
}

impl ControllerSpec {
    /// A fresh controller for `side`; the error says why the pair does not fit.
    pub fn build(&self, side: Side) -> Result<Box<dyn Controller>, ControllerError> {
        Ok(match self {
            ControllerSpec::Heuristic => Box::new(Heuristic),
            ControllerSpec::Greedy { coarsening } => Box::new(AszGreedy::new(*coarsening)),
            ControllerSpec::RandomisedExpert { seed } => match side {
                Side::Captors => Box::new(RandomisedExpert::new(*seed)),
                Side::Target => return Err(ControllerError::ExpertAsTarget(*seed)),
            },
            ControllerSpec::Lookahead { horizon, captors } => match side {
                Side::Target => Box::new(Lookahead::new(*horizon, captors.build(Side::Captors)?)),
                Side::Captors => return Err(ControllerError::LookaheadAsCaptors(self.to_string())),
            },
            ControllerSpec::Robust { horizon, models } => match side {
                Side::Target => Box::new(RobustLookahead::new(
                    *horizon,
                    models
                        .iter()
                        .map(|m| m.build(Side::Captors))
                        .collect::<Result<_, _>>()?,
                )),
                Side::Captors => return Err(ControllerError::LookaheadAsCaptors(self.to_string())),
            },
            ControllerSpec::Tuned(params) => match side {
                Side::Target => Box::new(TunedTarget { params: *params }),
                Side::Captors => return Err(ControllerError::TunedAsCaptors(self.to_string())),
            },
            ControllerSpec::Random => Box::new(RandomActions::new()),
            ControllerSpec::Still => Box::new(Still),
            ControllerSpec::Checkpoint(c) => {
                let snapshot = c.snapshot(side)?;
                let ckpt = match &snapshot.meta.net.prior_teacher {
                    Some(text) => {
                        let planner = prior_teacher(text)
                            .and_then(|spec| spec.build(Side::Target))
                            .map_err(|e| {
                                ControllerError::Checkpoint(format!(
                                    "{}: net.prior_teacher = \"{text}\": {e}",
                                    snapshot.dir.join("meta.json").display()
                                ))
                            })?;
                        CheckpointController::leaning_on(snapshot, planner)
                    }
                    None => CheckpointController::new(snapshot),
                }
                .map_err(|e| ControllerError::Checkpoint(format!("{e:#}")))?;
                Box::new(if c.sampled { ckpt.sampling() } else { ckpt })
            }
        })
    }

    /// Checks that this controller can play `side` in environments set up as
    /// `cfg` (a checkpoint's K and side), building one to be sure.
    pub fn check(&self, side: Side, cfg: &EnvConfig) -> Result<(), ControllerError> {
        self.build(side)?;
        match self {
            ControllerSpec::Checkpoint(c) => {
                let snap = c.snapshot(side)?;
                snap.meta.check_fits(side, cfg).map_err(|e| {
                    ControllerError::Checkpoint(format!("{}: {e}", snap.dir.display()))
                })?;
            }
            // The model plays the same world's captors.
            ControllerSpec::Lookahead { captors, .. } => captors.check(Side::Captors, cfg)?,
            ControllerSpec::Robust { models, .. } => {
                for model in models {
                    model.check(Side::Captors, cfg)?;
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// Whether it reads a checkpoint (itself, or a lookahead's model).
    pub fn is_checkpoint(&self) -> bool {
        match self {
            ControllerSpec::Checkpoint(_) => true,
            ControllerSpec::Lookahead { captors, .. } => captors.is_checkpoint(),
            ControllerSpec::Robust { models, .. } => models.iter().any(|m| m.is_checkpoint()),
            _ => false,
        }
    }

    /// A config's list of controllers for `side` (`field = ["greedy:2",
    /// ...]`): each must parse, pass `refuse` (None: accepted), build for the
    /// side (a checkpoint is checked when it is loaded) and appear once.
    /// Errors name the field and the entry.
    pub fn parse_list(
        field: &str,
        names: &[String],
        side: Side,
        refuse: impl Fn(&ControllerSpec) -> Option<String>,
    ) -> Result<Vec<ControllerSpec>, ConfigError> {
        let mut out: Vec<ControllerSpec> = Vec::new();
        for name in names {
            let refused = |why: String| ConfigError::new(field, format!("\"{name}\""), why);
            let spec: ControllerSpec = name.parse().map_err(|e| refused(format!("{e}")))?;
            if let Some(why) = refuse(&spec) {
                return Err(refused(why));
            }
            if !spec.is_checkpoint() {
                spec.build(side).map_err(|e| refused(e.to_string()))?;
            }
            if out.contains(&spec) {
                return Err(ConfigError::about(
                    field,
                    format!("\"{name}\" is named twice"),
                ));
            }
            out.push(spec);
        }
        Ok(out)
    }
}

/// Parses `NetConfig::prior_teacher`: a scripted target (none of its
/// models a checkpoint), built once to be sure it plays the target.
pub fn prior_teacher(text: &str) -> Result<ControllerSpec, ControllerError> {
    let spec: ControllerSpec = text.parse()?;
    if spec.is_checkpoint() {
        return Err(ControllerError::NotScripted(text.to_string()));
    }
    spec.build(Side::Target)?;
    Ok(spec)
}
