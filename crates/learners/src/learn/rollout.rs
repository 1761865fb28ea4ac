//! What every learner's update reads and returns: one side's rollout
//! buffer, the losses of an update, and the error of an update undone.

use crate::nn::NetConfig;
use serde::Serialize;

/// What one side's robots saw and did during a rollout, [step][row] with
/// rows = worlds x robots of the side (a world's robots adjacent).
pub struct Rollout {
    pub steps: usize,
    /// Side of the pooled patches the network reads.
    pub patch_side: usize,
    pub rows: usize,
    pub vector_len: usize,
    pub hidden: usize,
    pub chunk_len: usize,
    pub patches: Vec<u8>,
    pub vectors: Vec<f32>,
    pub actions: Vec<i64>,
    /// The rule-based target's action in each row's state, where the
    /// network leans on it (`NetConfig::heuristic_prior`); 0 elsewhere.
    pub hints: Vec<i64>,
    /// The teacher's action in each row's state, where the KL pulls
    /// towards a teacher (`PpoConfig::teacher`); 0 elsewhere.
    pub teacher_hints: Vec<i64>,
    pub logp: Vec<f32>,
    /// Critic outputs (normalised units when value normalisation is on).
    pub values: Vec<f32>,
    pub rewards: Vec<f32>,
    pub dones: Vec<f32>,
    /// 1 where the step limit (not a capture) ended the episode.
    pub truncated: Vec<f32>,
    /// Critic output for the state a truncated episode reached (same units
    /// as `values`), where `truncated` is 1.
    pub final_values: Vec<f32>,
    /// 0 where a step starts an episode (the recurrent state is reset).
    pub masks: Vec<f32>,
    /// Recurrent states at the start of every chunk, [chunk][row][hidden].
    pub actor_h: Vec<f32>,
    pub critic_h: Vec<f32>,
    pub last_values: Vec<f32>,
    /// Observations of the states truncated episodes reached (where
    /// `truncated` is 1; stale elsewhere), as the network reads them: the
    /// off-policy learners bootstrap their TD targets from them.
    pub final_patches: Vec<u8>,
    pub final_vectors: Vec<f32>,
    /// Observations after the rollout's last step, and their masks (0 where
    /// that step starts an episode): the last chunk's next observations.
    pub last_patches: Vec<u8>,
    pub last_vectors: Vec<f32>,
    pub last_masks: Vec<f32>,
}

impl Rollout {
    pub fn new(
        steps: usize,
        rows: usize,
        vector_len: usize,
        net: &NetConfig,
        chunk_len: usize,
    ) -> Rollout {
        let n = steps * rows;
        let chunks = steps / chunk_len;
        let hidden = net.hidden as usize;
        Rollout {
            steps,
            patch_side: net.input_side(),
            rows,
            vector_len,
            hidden,
            chunk_len,
            patches: vec![0; n * net.input_len()],
            vectors: vec![0.0; n * vector_len],
            actions: vec![0; n],
            hints: vec![0; n],
            teacher_hints: vec![0; n],
            logp: vec![0.0; n],
            values: vec![0.0; n],
            rewards: vec![0.0; n],
            dones: vec![0.0; n],
            truncated: vec![0.0; n],
            final_values: vec![0.0; n],
            masks: vec![1.0; n],
            actor_h: vec![0.0; chunks * rows * hidden],
            critic_h: vec![0.0; chunks * rows * hidden],
            last_values: vec![0.0; rows],
            final_patches: vec![0; n * net.input_len()],
            final_vectors: vec![0.0; n * vector_len],
            last_patches: vec![0; rows * net.input_len()],
            last_vectors: vec![0.0; rows * vector_len],
            last_masks: vec![1.0; rows],
        }
    }
}

/// Losses and diagnostics of one update.
#[derive(Clone, Debug, Default, Serialize)]
pub struct UpdateStats {
    pub policy_loss: f64,
    pub value_loss: f64,
    pub entropy: f64,
    pub approx_kl: f64,
    pub clip_frac: f64,
    pub actor_grad_norm: f64,
    pub critic_grad_norm: f64,
    /// Gradient steps the numbers above average over (0: the learner did
    /// not learn this time, e.g. an off-policy replay still filling).
    pub gradient_steps: usize,
    /// A target with a teacher (`ppo.teacher`): how its greedy moves
    /// matched the teacher's on this rollout, before the update.
    pub teacher: Option<super::teacher::TeacherAgreement>,
    /// A DAgger target (`ppo.dagger_rollouts`): how its greedy moves
    /// matched the teacher's on the aggregate's states it was fitted on
    /// in this update, each minibatch counted before its gradient step.
    pub fitted: Option<super::teacher::TeacherAgreement>,
}

impl UpdateStats {
    /// Adds one actor-critic gradient step's losses, the policy's entropy
    /// and the gradient norms to the sums.
    pub fn add_step(&mut self, actor_loss: f64, critic_loss: f64, entropy: f64, norms: (f64, f64)) {
        self.policy_loss += actor_loss;
        self.value_loss += critic_loss;
        self.entropy += entropy;
        self.actor_grad_norm += norms.0;
        self.critic_grad_norm += norms.1;
        self.gradient_steps += 1;
    }

    /// Sums over gradient steps become means.
    pub fn average(&mut self) {
        let n = self.gradient_steps.max(1) as f64;
        for x in [
            &mut self.policy_loss,
            &mut self.value_loss,
            &mut self.entropy,
            &mut self.approx_kl,
            &mut self.clip_frac,
            &mut self.actor_grad_norm,
            &mut self.critic_grad_norm,
        ] {
            *x /= n;
        }
    }
}

/// An update that was undone because a loss or gradient norm was not finite.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("non-finite update, undone: {0}")]
pub struct BadUpdate(pub String);

//END
