//! Every learner's settings, as a config file writes them: who plays a
//! side (`play`) and the tables of its learner (`ppo`, `maddpg`, `maac`,
//! `net`, `shaping`). A leaf of the learn floor: the algorithms read these
//! structs, and nothing here knows an algorithm's code.

mod bad_updates;
pub mod maac;
pub mod maddpg;
pub mod ppo;
pub mod replay;
pub mod shaping;

use crate::controllers::ControllerSpec;
use crate::nn::NetConfig;
pub use bad_updates::check_max_bad_updates;
pub use maac::MaacConfig;
pub use maddpg::MaddpgConfig;
pub use ppo::PpoConfig;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
pub use shaping::ShapingConfig;
use std::fmt;
use std::marker::PhantomData;
use std::str::FromStr;
use t2e_core::algorithm::Algorithm;
use t2e_core::error::ConfigError;

/// Who plays one side, and how it learns if it does: the one learner-settings
/// struct of a training run's sides (`SideConfig`) and of a league's
/// learners (`league::rules::config::LearnerConfig`). The two differ only in the
/// defaults a config that leaves a field out gets (`D`); the TOML is the
/// same, and `D` is not part of it (nor of the config hash).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    default,
    bound(serialize = "", deserialize = "D: SideDefaults")
)]
pub struct SideConfig<D: SideDefaults = TrainDefaults> {
    /// "mappo", "ippo", "maddpg" or "maac" to learn; otherwise a controller
    /// that does not learn: heuristic, greedy, random, still or ckpt:PATH.
    /// A league's configs have always called it `algorithm`, which reads
    /// as the same field.
    #[serde(alias = "algorithm")]
    pub play: Play,
    /// MAPPO's and IPPO's settings.
    pub ppo: PpoConfig,
    /// MADDPG's settings (left out of the stored config, and so of the
    /// config hash, while they are the defaults).
    #[serde(skip_serializing_if = "is_default")]
    pub maddpg: MaddpgConfig,
    /// MAAC's settings (as MADDPG's).
    #[serde(skip_serializing_if = "is_default")]
    pub maac: MaacConfig,
    pub net: NetConfig,
    /// Training-only potential-based shaping (off by default; left out of
    /// the stored config, and so of the config hash, while off).
    #[serde(skip_serializing_if = "is_default")]
    pub shaping: ShapingConfig,
    #[serde(skip)]
    pub defaults: PhantomData<D>,
}

/// The values a side's settings take where a config leaves them out.
pub trait SideDefaults: Clone + std::fmt::Debug + PartialEq {
    fn play() -> Play;
    fn ppo() -> PpoConfig;
}

/// A training run's defaults: the rule-based robot plays, and PPO has the
/// paper's settings.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TrainDefaults;

impl SideDefaults for TrainDefaults {
    fn play() -> Play {
        Play::Script(ControllerSpec::Heuristic)
    }
    fn ppo() -> PpoConfig {
        PpoConfig::default()
    }
}

pub fn is_default<T: Default + PartialEq>(x: &T) -> bool {
    *x == T::default()
}

impl<D: SideDefaults> Default for SideConfig<D> {
    fn default() -> Self {
        SideConfig {
            play: D::play(),
            ppo: D::ppo(),
            maddpg: MaddpgConfig::default(),
            maac: MaacConfig::default(),
            net: NetConfig::default(),
            shaping: ShapingConfig::default(),
            defaults: PhantomData,
        }
    }
}

/// Who plays a side: a learner, or a controller that does not learn. Read
/// and written as the one string of `play = "..."`, so stored configs and
/// their hashes read as before (aliases such as `rule` read as the name
/// they stand for).
#[derive(Clone, Debug, PartialEq)]
pub enum Play {
    Learn(Algorithm),
    Script(ControllerSpec),
}

impl Play {
    /// The algorithm that learns this side, if one does.
    pub fn algorithm(&self) -> Option<Algorithm> {
        match self {
            Play::Learn(algorithm) => Some(*algorithm),
            Play::Script(_) => None,
        }
    }
}

impl FromStr for Play {
    type Err = ConfigError;
    fn from_str(text: &str) -> Result<Play, ConfigError> {
        let play = text.trim();
        if let Some(algorithm) = Algorithm::parse(play) {
            return Ok(Play::Learn(algorithm));
        }
        play.parse::<ControllerSpec>()
            .map(Play::Script)
            .map_err(|e| {
                ConfigError::new(
                    "play",
                    format!("\"{play}\""),
                    format!(
                        "{e}; or {} to learn",
                        Algorithm::ALL.map(|a| a.name()).join(" / ")
                    ),
                )
            })
    }
}

impl fmt::Display for Play {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Play::Learn(algorithm) => f.write_str(algorithm.name()),
            Play::Script(spec) => spec.fmt(f),
        }
    }
}

impl From<ControllerSpec> for Play {
    fn from(spec: ControllerSpec) -> Play {
        Play::Script(spec)
    }
}

impl Serialize for Play {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

impl<'de> Deserialize<'de> for Play {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Play, D::Error> {
        let text = String::deserialize(deserializer)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

impl<D: SideDefaults> SideConfig<D> {
    /// The same settings under other defaults (a league learner's settings
    /// as a training run's side).
    pub fn with_defaults<E: SideDefaults>(self) -> SideConfig<E> {
        SideConfig {
            play: self.play,
            ppo: self.ppo,
            maddpg: self.maddpg,
            maac: self.maac,
            net: self.net,
            shaping: self.shaping,
            defaults: PhantomData,
        }
    }
}
