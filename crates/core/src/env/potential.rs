//! State potentials for training-only reward shaping. A learner may add
//! gamma * phi(s') - phi(s) to the spec's reward (`learn::shaping`): shaping
//! of this form leaves the optimal policies unchanged (Ng, Harada and Russell,
//! 1999), and the environment's own reward, rules and evaluation never see it.

use super::physics::blocked_probes;
use super::trap_env::TrapEnv;
use crate::asz::{AszFields, CoarseLattice, Lattice};
use serde::{Deserialize, Serialize};
use std::cell::RefCell;

/// Which potential, as a config names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Potential {
    /// The share of the 12 capture probes that are blocked (by a wall or a
    /// captor): 1 exactly when the fast rule captures. It tells the captors
    /// how close a state is to a trap, which the distance term does not.
    Trap,
    /// 1 - |ASZ| / free area: how much of the map the target can no longer
    /// reach first. It rises as the captors cut off escape routes, long
    /// before any probe is blocked. The per-robot fields of the ASZ
    /// (`AszFields`) on cells of 0.2 m (`ASZ_COARSENING`), about 16x fewer
    /// than the spec's, so a training step pays one coarse ASZ per world.
    Asz,
}

/// Map cells per side of a cell of the ASZ potential's march.
pub const ASZ_COARSENING: usize = 4;

/// The fields' buffers and the coarse lattices (with their free cells) of the
/// maps seen, per thread: the vector env steps its worlds on rayon's
/// threads, and its worlds play many maps at once (26 in the paper's
/// protocol), so one lattice per map is kept, the oldest dropped past
/// `ASZ_LATTICES`.
struct AszScratch {
    fields: AszFields,
    lattices: Vec<(CoarseLattice, usize)>,
}

const ASZ_LATTICES: usize = 64;

thread_local! {
    static ASZ_SCRATCH: RefCell<AszScratch> = RefCell::new(AszScratch {
        fields: AszFields::new(),
        lattices: Vec::new(),
    });
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
            Potential::Asz => ASZ_SCRATCH.with_borrow_mut(|scratch| {
                let map = env.map();
                let at = match scratch
                    .lattices
                    .iter()
                    .position(|(l, _)| l.covers(map, ASZ_COARSENING))
                {
                    Some(at) => at,
                    None => {
                        if scratch.lattices.len() == ASZ_LATTICES {
                            scratch.lattices.remove(0);
                        }
                        let lattice = CoarseLattice::new(map, ASZ_COARSENING);
                        let free = lattice.obstacle().iter().filter(|&&o| o == 0).count();
                        scratch.lattices.push((lattice, free));
                        scratch.lattices.len() - 1
                    }
                };
                let (lattice, free) = &scratch.lattices[at];
                let (captors, target) = env.asz_sources();
                let asz = scratch.fields.asz_cells(lattice, target, &captors);
                1.0 - (asz as f32 / (*free).max(1) as f32).min(1.0)
            }),
        }
    }
}
