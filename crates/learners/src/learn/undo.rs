//! One undo point for every learner: copies of everything an update
//! changes in some var stores and their Adams, taken before the update and
//! pasted back when it turns out non-finite. PPO takes one per update;
//! MADDPG and MAAC one per update phase (`offpolicy::Params`).

use super::adam::Adam;
use super::learner::NamedTensors;
use tch::nn::VarStore;

pub struct UndoPoint {
    weights: Vec<NamedTensors>,
    adams: Vec<(NamedTensors, u64)>,
}

impl UndoPoint {
    pub fn take(stores: &[&VarStore], adams: &[&Adam]) -> UndoPoint {
        UndoPoint {
            weights: stores
                .iter()
                .map(|vs| {
                    vs.variables()
                        .into_iter()
                        .map(|(n, t)| (n, t.detach().copy()))
                        .collect()
                })
                .collect(),
            adams: adams.iter().map(|a| (a.state_tensors(), a.steps)).collect(),
        }
    }

    /// Pastes the copies back into the same stores and Adams, in the
    /// order they were taken.
    pub fn restore(self, stores: &[&VarStore], adams: &mut [&mut Adam]) {
        assert_eq!(
            stores.len(),
            self.weights.len(),
            "the stores it was taken of"
        );
        assert_eq!(adams.len(), self.adams.len(), "the Adams it was taken of");
        for (vs, saved) in stores.iter().zip(self.weights) {
            let vars = vs.variables();
            tch::no_grad(|| {
                for (name, t) in saved {
                    let mut v = vars[&name].shallow_clone();
                    v.copy_(&t);
                }
            });
        }
        for (adam, (state, steps)) in adams.iter_mut().zip(self.adams) {
            adam.load_state(&state, steps).expect("own moments fit");
        }
    }
}
