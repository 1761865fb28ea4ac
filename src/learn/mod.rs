//! Learners: the paper's four, recurrent PPO with a centralised (MAPPO) or
//! decentralised (IPPO) critic and the off-policy MADDPG and MAAC, and the
//! training loop that plays either side, or both, against heuristics,
//! frozen checkpoints or each other.

pub mod acting;
pub mod adam;
pub mod config;
pub mod extra_maps;
pub mod ippo;
pub mod learner;
pub mod maac;
pub mod maddpg;
pub mod map_sampling;
pub mod mappo;
pub mod offpolicy;
pub mod persist;
pub mod ppo;
pub mod rollout;
pub mod shaping;
pub mod train;

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algorithm {
    Mappo,
    Ippo,
    Maddpg,
    Maac,
}

impl Algorithm {
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Mappo => "mappo",
            Algorithm::Ippo => "ippo",
            Algorithm::Maddpg => "maddpg",
            Algorithm::Maac => "maac",
        }
    }

    pub const ALL: [Algorithm; 4] = [
        Algorithm::Mappo,
        Algorithm::Ippo,
        Algorithm::Maddpg,
        Algorithm::Maac,
    ];

    /// The algorithm a config or sidecar names, if any.
    pub fn parse(name: &str) -> Option<Algorithm> {
        Algorithm::ALL.into_iter().find(|a| a.name() == name)
    }

    /// Whether it learns from a replay of past experience.
    pub fn off_policy(self) -> bool {
        matches!(self, Algorithm::Maddpg | Algorithm::Maac)
    }

    /// What PPO's critic reads: the whole team's observations (MAPPO) or
    /// the robot's own (IPPO, and anything else asked).
    pub fn critic_view(self) -> Box<dyn ppo::CriticView> {
        match self {
            Algorithm::Mappo => Box::new(mappo::Mappo),
            _ => Box::new(ippo::Ippo),
        }
    }
}
