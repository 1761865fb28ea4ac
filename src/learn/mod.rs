//! Learners: recurrent PPO with a centralised (MAPPO) or decentralised
//! (IPPO) critic, and the training loop that plays either side, or both,
//! against heuristics, frozen checkpoints or each other.

pub mod acting;
pub mod ippo;
pub mod mappo;
pub mod persist;
pub mod ppo;
pub mod train;

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Algorithm {
    Mappo,
    Ippo,
}

impl Algorithm {
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::Mappo => "mappo",
            Algorithm::Ippo => "ippo",
        }
    }

    pub fn critic_view(self) -> Box<dyn ppo::CriticView> {
        match self {
            Algorithm::Mappo => Box::new(mappo::Mappo),
            Algorithm::Ippo => Box::new(ippo::Ippo),
        }
    }
}
