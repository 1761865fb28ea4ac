//! The networks of spec §9 in tch: a CNN over the obstacle patch and an MLP
//! over the agent vector, concatenated, then an MLP and a GRU; the actor ends
//! in a categorical head over the 5 actions, the critic in one value.
//!
//! Teammates share one actor and one critic. The critic's encoder reads the
//! observations of `critic_agents` robots at once (their patches stacked as
//! channels, their vectors concatenated, the robot's own first): all
//! teammates for MAPPO's centralised critic, just the robot for IPPO's.

pub mod checkpoint;
pub mod stacked;

pub use checkpoint::{CheckpointController, CheckpointMeta, PolicySnapshot};

use crate::env::{Action, PATCH};
use serde::{Deserialize, Serialize};
use tch::nn::{self, RNN};
use tch::{Device, Kind, Tensor};

/// Network sizes. Defaults are the paper's (hidden 128, one GRU layer); the
/// patch is max-pooled before the CNN, which keeps every obstacle cell (an
/// obstacle anywhere in a pooled block marks the block) and makes the CNN 4x
/// cheaper, the difference between a CPU and a GPU budget.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct NetConfig {
    /// Width of the MLPs, of the GRU state and of each encoder's output.
    pub hidden: i64,
    /// Channels of the two stride-2 3x3 convolutions over the patch.
    pub conv_channels: [i64; 2],
    /// Max-pooling of the 48x48 patch before the CNN (1: none, 2: 24x24).
    pub patch_pool: i64,
}

impl Default for NetConfig {
    fn default() -> Self {
        NetConfig {
            hidden: 128,
            conv_channels: [16, 32],
            patch_pool: 2,
        }
    }
}

impl NetConfig {
    pub fn validate(&self) -> Result<(), String> {
        if !(8..=4096).contains(&self.hidden) {
            return Err(format!("hidden = {}: must be in 8..=4096", self.hidden));
        }
        if self.conv_channels.iter().any(|&c| !(1..=512).contains(&c)) {
            return Err(format!(
                "conv_channels = {:?}: each must be in 1..=512",
                self.conv_channels
            ));
        }
        if ![1, 2, 3, 4, 6].contains(&self.patch_pool) {
            return Err(format!(
                "patch_pool = {}: must divide 48 and leave at least 8 pixels (1, 2, 3, 4 or 6)",
                self.patch_pool
            ));
        }
        Ok(())
    }

    /// Side of the pooled patch the CNN reads.
    pub fn input_side(&self) -> usize {
        PATCH / self.patch_pool as usize
    }

    /// Bytes of one pooled patch.
    pub fn input_len(&self) -> usize {
        self.input_side() * self.input_side()
    }

    /// Multiply-adds x 2 of one forward pass of one row through a trunk
    /// with `channels` stacked patches and a `vector_len` vector, plus a
    /// head of `outputs` (the actor's 5, a critic's 1): the convolutions,
    /// the linear layers and the GRU cell. Norms and activations are left
    /// out (a few percent). A backward pass costs about twice this.
    pub fn forward_flops(&self, channels: usize, vector_len: usize, outputs: usize) -> f64 {
        let s0 = self.input_side() as f64;
        let s1 = ((s0 - 3.0) / 2.0).floor() + 1.0;
        let s2 = self.conv_out_side() as f64;
        let [c1, c2] = self.conv_channels.map(|c| c as f64);
        let (h, cin, v) = (self.hidden as f64, channels as f64, vector_len as f64);
        let conv = 2.0 * 9.0 * (s1 * s1 * c1 * cin + s2 * s2 * c2 * c1);
        let linear = 2.0 * (c2 * s2 * s2 * h + v * h + 2.0 * h * h + h * outputs as f64);
        let gru = 2.0 * 2.0 * 3.0 * h * h;
        conv + linear + gru
    }

    /// Side of the CNN's output map.
    fn conv_out_side(&self) -> i64 {
        let s = self.input_side() as i64;
        let s = (s - 3) / 2 + 1;
        (s - 3) / 2 + 1
    }
}

/// Patch CNN + vector MLP, concatenated, then one MLP layer.
#[derive(Debug)]
struct Encoder {
    conv1: nn::Conv2D,
    conv2: nn::Conv2D,
    patch_fc: nn::Linear,
    vector_norm: nn::LayerNorm,
    vector_fc: nn::Linear,
    merge_fc: nn::Linear,
}

impl Encoder {
    fn new(p: &nn::Path, cfg: &NetConfig, channels: i64, vector_len: i64) -> Encoder {
        let conv = nn::ConvConfig {
            stride: 2,
            ..Default::default()
        };
        let [c1, c2] = cfg.conv_channels;
        let side = cfg.conv_out_side();
        let h = cfg.hidden;
        Encoder {
            conv1: nn::conv2d(p / "conv1", channels, c1, 3, conv),
            conv2: nn::conv2d(p / "conv2", c1, c2, 3, conv),
            patch_fc: nn::linear(p / "patch_fc", c2 * side * side, h, Default::default()),
            // Positions are metres in a 16 m map and headings are radians:
            // normalising lets one learning rate suit every input.
            vector_norm: nn::layer_norm(p / "vector_norm", vec![vector_len], Default::default()),
            vector_fc: nn::linear(p / "vector_fc", vector_len, h, Default::default()),
            merge_fc: nn::linear(p / "merge_fc", 2 * h, h, Default::default()),
        }
    }

    /// `patches`: [B, C, S, S] u8 (0/1, pooled by `pool_patch`); `vectors`:
    /// [B, V] f32 -> [B, hidden].
    fn forward(&self, patches: &Tensor, vectors: &Tensor) -> Tensor {
        let x = patches
            .to_kind(Kind::Float)
            .apply(&self.conv1)
            .relu()
            .apply(&self.conv2)
            .relu()
            .flatten(1, -1)
            .apply(&self.patch_fc)
            .relu();
        let v = vectors
            .apply(&self.vector_norm)
            .apply(&self.vector_fc)
            .relu();
        Tensor::cat(&[x, v], 1).apply(&self.merge_fc).relu()
    }
}

/// Encoder + GRU: the recurrent trunk every network here shares in shape
/// (the off-policy learners' Q critics put their own heads on it).
#[derive(Debug)]
pub(crate) struct Trunk {
    encoder: Encoder,
    gru: nn::GRU,
    /// The GRU's weight_ih, weight_hh, bias_ih, bias_hh (shared with the
    /// GRU, which keeps its own private): for stacking frozen actors.
    gru_params: [Tensor; 4],
}

impl Trunk {
    pub(crate) fn new(p: &nn::Path, cfg: &NetConfig, channels: i64, vector_len: i64) -> Trunk {
        let gru = nn::gru(p / "gru", cfg.hidden, cfg.hidden, Default::default());
        let g = p / "gru";
        let param = |n: &str| {
            g.get(n)
                .expect("nn::gru creates its parameters under these names")
        };
        Trunk {
            encoder: Encoder::new(&(p / "encoder"), cfg, channels, vector_len),
            gru,
            gru_params: [
                param("weight_ih_l0"),
                param("weight_hh_l0"),
                param("bias_ih_l0"),
                param("bias_hh_l0"),
            ],
        }
    }

    /// (weight_ih, weight_hh, bias_ih, bias_hh) of the GRU.
    fn gru_weights(&self) -> (&Tensor, &Tensor, &Tensor, &Tensor) {
        let [a, b, c, d] = &self.gru_params;
        (a, b, c, d)
    }

    /// One step for a batch: features [B, hidden] and the next state [B, hidden].
    pub(crate) fn step(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> (Tensor, Tensor) {
        let x = self.encoder.forward(patches, vectors);
        let state = self.gru.step(&x, &nn::GRUState(h.unsqueeze(0)));
        let h = state.0.squeeze_dim(0);
        (h.shallow_clone(), h)
    }

    /// A chunk of `len` steps for `batch` sequences, inputs flattened time
    /// major ([len * batch, ...]); `masks` [len, batch] is 0 where a step starts
    /// a new episode, which zeroes the state carried into it. Returns the
    /// features of every step, [len * batch, hidden].
    pub(crate) fn unroll(
        &self,
        patches: &Tensor,
        vectors: &Tensor,
        h0: &Tensor,
        masks: &Tensor,
    ) -> Tensor {
        let len = masks.size()[0];
        let batch = masks.size()[1];
        let x = self
            .encoder
            .forward(patches, vectors)
            .view([len, batch, -1]);
        let mut h = h0.shallow_clone();
        let mut outs = Vec::with_capacity(len as usize);
        for t in 0..len {
            let m = masks.get(t).unsqueeze(1);
            let state = self
                .gru
                .step(&x.get(t), &nn::GRUState((&h * &m).unsqueeze(0)));
            h = state.0.squeeze_dim(0);
            outs.push(h.shallow_clone());
        }
        Tensor::cat(&outs, 0)
    }
}

/// The policy: one shared by all robots of a side.
#[derive(Debug)]
pub struct Actor {
    trunk: Trunk,
    head: nn::Linear,
    pub hidden: i64,
}

impl Actor {
    pub fn new(p: &nn::Path, cfg: &NetConfig, vector_len: usize) -> Actor {
        let trunk = Trunk::new(p, cfg, 1, vector_len as i64);
        // A small last layer starts the policy near uniform.
        let head = nn::linear(
            p / "head",
            cfg.hidden,
            Action::COUNT as i64,
            nn::LinearConfig {
                ws_init: nn::Init::Uniform {
                    lo: -0.01,
                    up: 0.01,
                },
                ..Default::default()
            },
        );
        Actor {
            trunk,
            head,
            hidden: cfg.hidden,
        }
    }

    /// One step: patches [B, 1, 48, 48] u8, vectors [B, V] -> (logits [B, 5], state [B, hidden]).
    pub fn step(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> (Tensor, Tensor) {
        let (x, h) = self.trunk.step(patches, vectors, h);
        (x.apply(&self.head), h)
    }

    /// Logits [len * batch, 5] of a chunk; see `Trunk::unroll`.
    pub fn unroll(
        &self,
        patches: &Tensor,
        vectors: &Tensor,
        h0: &Tensor,
        masks: &Tensor,
    ) -> Tensor {
        self.trunk
            .unroll(patches, vectors, h0, masks)
            .apply(&self.head)
    }

    /// The recurrent states of every step of a chunk, [len * batch, hidden]
    /// (the off-policy learners continue a state past a truncation).
    pub fn unroll_states(
        &self,
        patches: &Tensor,
        vectors: &Tensor,
        h0: &Tensor,
        masks: &Tensor,
    ) -> Tensor {
        self.trunk.unroll(patches, vectors, h0, masks)
    }

    /// Logits from recurrent states.
    pub fn logits(&self, states: &Tensor) -> Tensor {
        states.apply(&self.head)
    }
}

/// The value function, over `critic_agents` robots' observations.
#[derive(Debug)]
pub struct Critic {
    trunk: Trunk,
    head: nn::Linear,
    pub hidden: i64,
}

impl Critic {
    pub fn new(p: &nn::Path, cfg: &NetConfig, vector_len: usize, critic_agents: usize) -> Critic {
        Critic {
            trunk: Trunk::new(
                p,
                cfg,
                critic_agents as i64,
                (vector_len * critic_agents) as i64,
            ),
            head: nn::linear(p / "head", cfg.hidden, 1, Default::default()),
            hidden: cfg.hidden,
        }
    }

    /// One step: (values [B], state [B, hidden]).
    pub fn step(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> (Tensor, Tensor) {
        let (x, h) = self.trunk.step(patches, vectors, h);
        (x.apply(&self.head).squeeze_dim(1), h)
    }

    /// Values [len * batch] of a chunk; see `Trunk::unroll`.
    pub fn unroll(
        &self,
        patches: &Tensor,
        vectors: &Tensor,
        h0: &Tensor,
        masks: &Tensor,
    ) -> Tensor {
        self.trunk
            .unroll(patches, vectors, h0, masks)
            .apply(&self.head)
            .squeeze_dim(1)
    }

    /// The encoder alone, [B, hidden], for many steps at once (the GRU then
    /// runs step by step with `gru_step`): a rollout's values in one pass.
    pub fn encode(&self, patches: &Tensor, vectors: &Tensor) -> Tensor {
        self.trunk.encoder.forward(patches, vectors)
    }

    /// One GRU step from encoded inputs: the next state [B, hidden].
    pub fn gru_step(&self, x: &Tensor, h: &Tensor) -> Tensor {
        self.trunk
            .gru
            .step(x, &nn::GRUState(h.unsqueeze(0)))
            .0
            .squeeze_dim(0)
    }

    /// Values [B] of recurrent states [B, hidden].
    pub fn values(&self, states: &Tensor) -> Tensor {
        states.apply(&self.head).squeeze_dim(1)
    }
}

/// Runs `f` with torch's global generator seeded by `seed`, holding a
/// process-wide lock: weights initialised inside come out the same whatever
/// other trainers in the process (tests run in parallel) are doing. Torch
/// draws nothing else for training here; sampling and noise come from each
/// trainer's own ChaCha generator.
pub fn seeded<T>(seed: u64, f: impl FnOnce() -> T) -> T {
    let _held = seed_torch(seed);
    f()
}

/// Seeds torch's global generator and holds the lock `seeded` takes until
/// the guard drops: for code (tests) that draws from torch directly.
pub fn seed_torch(seed: u64) -> std::sync::MutexGuard<'static, ()> {
    static TORCH_SEED: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let held = TORCH_SEED.lock().unwrap_or_else(|e| e.into_inner());
    tch::manual_seed(seed as i64);
    held
}

/// Max-pools a 48x48 patch by `pool` into `out` ((48 / pool)^2 bytes): a
/// pooled pixel is obstacle if any cell under it is. Done once per
/// observation, outside the network, so training never re-pools.
pub fn pool_patch(patch: &[u8], pool: usize, out: &mut [u8]) {
    if pool == 1 {
        out.copy_from_slice(patch);
        return;
    }
    let side = PATCH / pool;
    for (r, row) in out.chunks_exact_mut(side).enumerate() {
        row.fill(0);
        for dr in 0..pool {
            let src = &patch[(r * pool + dr) * PATCH..(r * pool + dr + 1) * PATCH];
            for (c, o) in row.iter_mut().enumerate() {
                for &x in &src[c * pool..(c + 1) * pool] {
                    *o |= x;
                }
            }
        }
    }
}

/// Observations of `rows` robots as network inputs on `device`: pooled
/// patches [rows, channels, side, side] u8 and vectors [rows, V] f32.
pub fn obs_tensors(
    patches: &[u8],
    vectors: &[f32],
    rows: usize,
    channels: usize,
    side: usize,
    device: Device,
) -> (Tensor, Tensor) {
    let p = side as i64;
    let pt = Tensor::from_slice(patches)
        .view([rows as i64, channels as i64, p, p])
        .to_device(device);
    let vt = Tensor::from_slice(vectors)
        .view([rows as i64, -1])
        .to_device(device);
    (pt, vt)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_and_masked_unroll_match_stepping() {
        let _seed = seed_torch(0);
        let vs = nn::VarStore::new(Device::Cpu);
        let cfg = NetConfig {
            hidden: 16,
            ..NetConfig::default()
        };
        let actor = Actor::new(&vs.root().sub("actor"), &cfg, 20);
        let (len, batch) = (3i64, 2i64);
        let patches = Tensor::randint(2, [len * batch, 1, 24, 24], (Kind::Uint8, Device::Cpu));
        let vectors = Tensor::randn([len * batch, 20], (Kind::Float, Device::Cpu));
        let h0 = Tensor::randn([batch, 16], (Kind::Float, Device::Cpu));
        // Sequence 1 starts a new episode at step 2.
        let masks = Tensor::from_slice(&[1f32, 1., 1., 1., 1., 0.]).view([len, batch]);
        let logits = actor.unroll(&patches, &vectors, &h0, &masks);
        assert_eq!(logits.size(), vec![len * batch, 5]);
        // Stepping by hand with the same resets gives the same logits.
        let mut h = h0.shallow_clone();
        for t in 0..len {
            let rows = Tensor::arange_start(t * batch, (t + 1) * batch, (Kind::Int64, Device::Cpu));
            let m = masks.get(t).unsqueeze(1);
            let (l, h2) = actor.step(
                &patches.index_select(0, &rows),
                &vectors.index_select(0, &rows),
                &(&h * &m),
            );
            let diff = (&l - logits.index_select(0, &rows))
                .abs()
                .max()
                .double_value(&[]);
            assert!(diff < 1e-5, "step {t}: {diff}");
            h = h2;
        }
        let critic = Critic::new(&vs.root().sub("critic"), &cfg, 20, 3);
        let (v, h) = critic.step(
            &Tensor::zeros([4, 3, 24, 24], (Kind::Uint8, Device::Cpu)),
            &Tensor::zeros([4, 60], (Kind::Float, Device::Cpu)),
            &Tensor::zeros([4, 16], (Kind::Float, Device::Cpu)),
        );
        assert_eq!((v.size(), h.size()), (vec![4], vec![4, 16]));
    }

    #[test]
    fn flops_of_the_small_actor_by_hand() {
        // Patch 48 / 4 = 12 -> conv1 5x5x8 -> conv2 2x2x16; hidden 64; 20 inputs.
        let cfg = NetConfig {
            hidden: 64,
            conv_channels: [8, 16],
            patch_pool: 4,
        };
        let conv = 2.0 * 9.0 * (25.0 * 8.0 + 4.0 * 16.0 * 8.0);
        let linear = 2.0 * (16.0 * 4.0 * 64.0 + 20.0 * 64.0 + 2.0 * 64.0 * 64.0 + 64.0 * 5.0);
        let gru = 12.0 * 64.0 * 64.0;
        assert_eq!(cfg.forward_flops(1, 20, 5), conv + linear + gru);
    }

    #[test]
    fn pooling_keeps_every_obstacle_cell() {
        let mut patch = vec![0u8; PATCH * PATCH];
        patch[0] = 1; // top-left block
        patch[PATCH + 47] = 1; // row 1, last column: block (0, 23)
        patch[47 * PATCH + 46] = 1; // bottom-right block
        let mut out = vec![9u8; 24 * 24];
        pool_patch(&patch, 2, &mut out);
        let ones: Vec<usize> = (0..out.len()).filter(|&i| out[i] == 1).collect();
        assert_eq!(ones, vec![0, 23, 24 * 24 - 1]);
        assert_eq!(out.iter().filter(|&&x| x == 0).count(), 24 * 24 - 3);
        let mut same = vec![0u8; PATCH * PATCH];
        pool_patch(&patch, 1, &mut same);
        assert_eq!(same, patch);
    }
}
