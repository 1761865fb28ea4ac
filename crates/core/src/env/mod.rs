//! The T2E environment (spec §2–§6) with a PettingZoo-style parallel API:
//! `reset(seed)` and `step(actions)` -> observations, rewards, terminations,
//! truncations, infos. Agents are ordered captors first, target last.
//! `VecEnv` steps many worlds in parallel with auto-reset.

pub mod action;
pub mod config;
pub mod controller;
pub mod features;
pub mod observe;
pub mod physics;
pub mod placement;
pub mod potential;
mod robot;
pub mod sight;
mod trap_env;
pub mod vec_env;

pub use action::Action;
pub use config::{CaptureRule, DriveForce, EnvConfig, RobotSpec, MAX_CAPTORS};
pub use controller::{Controller, OneGameAtATime, Side};
pub use observe::{PATCH, PATCH_LEN};
pub use physics::Robot;
pub use placement::PlacementError;
pub use sight::Sight;
pub use trap_env::{rewards, Observation, StepInfo, StepResult, TrapEnv};
pub use vec_env::VecEnv;
