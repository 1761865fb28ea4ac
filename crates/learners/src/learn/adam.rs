//! Adam with its moments kept as named tensors, shared by every learner.

use super::rollout::BadUpdate;
use tch::{nn, Device, Kind, Tensor};

/// A saved optimizer state that does not fit the network it is loaded into.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum OptimizerStateError {
    #[error("no optimizer moment '{0}'")]
    Missing(String),
    #[error("optimizer moment '{0}' has the wrong shape")]
    Shape(String),
}

/// Adam over the variables of one var store, by name, with its moments kept
/// as tensors so a checkpoint can carry them and a resumed run continues
/// exactly where it stopped.
pub struct Adam {
    pub lr: f64,
    pub eps: f64,
    pub beta1: f64,
    pub beta2: f64,
    pub steps: u64,
    params: Vec<(String, Tensor)>,
    m: Vec<Tensor>,
    v: Vec<Tensor>,
}

/// The first half of every learner's gradient step: clears the gradients
/// of each optimizer's variables, backpropagates `loss`, then clips each
/// optimizer's gradients to its own max norm, in the order given. Returns
/// the norms before clipping, for the caller to check (a non-finite one
/// refuses the update) before it steps.
pub fn backward_clipped(loss: &Tensor, optimizers: &mut [(&mut Adam, f64)]) -> Vec<f64> {
    for (adam, _) in optimizers.iter_mut() {
        adam.zero_grad();
    }
    loss.backward();
    optimizers
        .iter_mut()
        .map(|(adam, max_norm)| adam.clip_grad_norm(*max_norm))
        .collect()
}

/// One optimiser's step on `loss`, as the off-policy learners take them:
/// backpropagate, clip to `max_norm`, refuse a non-finite norm (naming
/// `what` is the network), then step. Returns the norm before clipping.
pub fn minimize(
    loss: &Tensor,
    adam: &mut Adam,
    max_norm: f64,
    what: &str,
) -> Result<f64, BadUpdate> {
    let norm = backward_clipped(loss, &mut [(&mut *adam, max_norm)])[0];
    if !norm.is_finite() {
        return Err(BadUpdate(format!("{what} gradient norm {norm}")));
    }
    adam.step();
    Ok(norm)
}

impl Adam {
    pub fn new(vs: &nn::VarStore, lr: f64, eps: f64) -> Adam {
        let mut params: Vec<(String, Tensor)> = vs.variables().into_iter().collect();
        params.sort_by(|a, b| a.0.cmp(&b.0));
        let m = params.iter().map(|(_, p)| p.zeros_like()).collect();
        let v = params.iter().map(|(_, p)| p.zeros_like()).collect();
        Adam {
            lr,
            eps,
            beta1: 0.9,
            beta2: 0.999,
            steps: 0,
            params,
            m,
            v,
        }
    }

    pub fn zero_grad(&mut self) {
        for (_, p) in &mut self.params {
            p.zero_grad();
        }
    }

    /// Scales the gradients to a global norm of at most `max_norm`; returns
    /// the norm before clipping.
    pub fn clip_grad_norm(&mut self, max_norm: f64) -> f64 {
        let norm = tch::no_grad(|| {
            let sq: Vec<Tensor> = self
                .params
                .iter()
                .map(|(_, p)| p.grad())
                .filter(|g| g.defined())
                .map(|g| g.square().sum(Kind::Float))
                .collect();
            if sq.is_empty() {
                0.0
            } else {
                Tensor::stack(&sq, 0)
                    .sum(Kind::Float)
                    .sqrt()
                    .double_value(&[])
            }
        });
        if norm > max_norm {
            let scale = max_norm / (norm + 1e-6);
            tch::no_grad(|| {
                for (_, p) in &self.params {
                    let mut g = p.grad();
                    if g.defined() {
                        let _ = g.g_mul_scalar_(scale);
                    }
                }
            });
        }
        norm
    }

    pub fn step(&mut self) {
        self.steps += 1;
        let t = self.steps as i32;
        let (b1, b2) = (self.beta1, self.beta2);
        let step_size = self.lr / (1.0 - b1.powi(t));
        let bias2 = (1.0 - b2.powi(t)).sqrt();
        tch::no_grad(|| {
            for (((_, p), m), v) in self.params.iter_mut().zip(&mut self.m).zip(&mut self.v) {
                let g = p.grad();
                if !g.defined() {
                    continue;
                }
                let _ = m.g_mul_scalar_(b1).g_add_(&(&g * (1.0 - b1)));
                let _ = v.g_mul_scalar_(b2).g_add_(&(g.square() * (1.0 - b2)));
                let denom = v.sqrt() / bias2 + self.eps;
                let _ = p.g_sub_(&(&*m / denom * step_size));
            }
        });
    }

    /// Moments as named tensors on the CPU (`m.NAME`, `v.NAME`).
    pub fn state_tensors(&self) -> Vec<(String, Tensor)> {
        let mut out = Vec::new();
        for (((name, _), m), v) in self.params.iter().zip(&self.m).zip(&self.v) {
            out.push((format!("m.{name}"), m.to_device(Device::Cpu)));
            out.push((format!("v.{name}"), v.to_device(Device::Cpu)));
        }
        out
    }

    pub fn load_state(
        &mut self,
        tensors: &[(String, Tensor)],
        steps: u64,
    ) -> Result<(), OptimizerStateError> {
        for (((name, p), m), v) in self.params.iter().zip(&mut self.m).zip(&mut self.v) {
            for (prefix, dst) in [("m", &mut *m), ("v", &mut *v)] {
                let key = format!("{prefix}.{name}");
                let src = tensors
                    .iter()
                    .find(|(n, _)| *n == key)
                    .ok_or_else(|| OptimizerStateError::Missing(key.clone()))?;
                if src.1.size() != p.size() {
                    return Err(OptimizerStateError::Shape(key));
                }
                tch::no_grad(|| dst.copy_(&src.1));
            }
        }
        self.steps = steps;
        Ok(())
    }
}
