//! State potentials for training-only reward shaping. A learner may add
//! gamma * phi(s') - phi(s) to the spec's reward (`learn::shaping`): shaping
//! of this form leaves the optimal policies unchanged (Ng, Harada and Russell,
//! 1999), and the environment's own reward, rules and evaluation never see it.

use super::physics::blocked_probes;
use super::TrapEnv;
use serde::{Deserialize, Serialize};

/// Which potential, as a config names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Potential {
    /// The share of the 12 capture probes that are blocked (by a wall or a
    /// captor): 1 exactly when the fast rule captures. It tells the captors
    /// how close a state is to a trap, which the distance term does not.
    Trap,
}

impl Potential {
    /// phi of the world's current state, in [0, 1], seen from the captors.
    pub fn of(self, env: &TrapEnv) -> f32 {
        match self {
            Potential::Trap => {
                let k = env.num_captors();
                let blocked = blocked_probes(env.map(), env.robots[k].pos, &env.robots[..k]);
                blocked as f32 / crate::map::prepared::NUM_RAYS as f32
            }
        }
    }
}
