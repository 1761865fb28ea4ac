//! IPPO: PPO with decentralised critics. Teammates still share one actor and
//! one critic, but the critic sees only the robot's own observation, exactly
//! what its actor sees. Everything else is the PPO of `ppo.rs`.

use super::ppo::{CriticView, PpoKind};
use t2e_core::algorithm::Algorithm;
use tch::Tensor;

pub struct Ippo;

pub const KIND: PpoKind = PpoKind {
    algorithm: Algorithm::Ippo,
    view: || Box::new(Ippo),
};

impl CriticView for Ippo {
    fn critic_agents(&self, _team: usize) -> usize {
        1
    }

    fn critic_inputs(&self, patches: &Tensor, vectors: &Tensor, _team: usize) -> (Tensor, Tensor) {
        (patches.shallow_clone(), vectors.shallow_clone())
    }
}
