//! Learners: the paper's four, recurrent PPO with a centralised (MAPPO) or
//! decentralised (IPPO) critic and the off-policy MADDPG and MAAC, and the
//! training loop that plays either side, or both, against heuristics,
//! frozen checkpoints or each other.

pub mod acting;
pub mod adam;
pub mod dagger;
pub mod extra_maps;
pub mod ippo;
pub mod kind;
pub mod learner;
pub mod maac;
pub mod maddpg;
pub mod map_sampling;
pub mod mappo;
pub mod offpolicy;
pub mod persist;
pub mod ppo;
pub mod rollout;
pub mod run_config;
pub mod shaping;
pub mod side_config;
pub mod teacher;
pub mod train;
pub mod undo;

pub use kind::kind;
pub use learner::LearnerKind;
pub use t2e_core::algorithm::Algorithm;
