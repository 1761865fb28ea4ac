//! The networks of spec §9 in tch: a CNN over the obstacle patch and an MLP
//! over the agent vector, concatenated, then an MLP and a GRU; the actor ends
//! in a categorical head over the 5 actions, the critic in one value.
//!
//! Teammates share one actor and one critic. The critic's encoder reads the
//! observations of `critic_agents` robots at once (their patches stacked as
//! channels, their vectors concatenated, the robot's own first): all
//! teammates for MAPPO's centralised critic, just the robot for IPPO's.

pub mod checkpoint;
mod egocentric;
pub mod policy;
pub mod prior;
pub mod run_dir;
pub mod stacked;

/// Pooling happens once per observation, outside the network.
pub use crate::env::features::pool_patch;
pub use checkpoint::CheckpointMeta;
pub(crate) use egocentric::EgocentricVector;
pub use policy::{CheckpointController, PolicyError, PolicySnapshot};

use crate::env::{Action, Sight, PATCH};
use crate::error::{in_range, ConfigError};
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
    /// How the agent vector enters the network (see `VectorInput`). Left
    /// out of the stored config while it is the reference's layer norm, so
    /// the configs and checkpoints written before it existed keep their
    /// hashes and load as they were trained.
    #[serde(skip_serializing_if = "VectorInput::is_layer_norm")]
    pub vector_input: VectorInput,
    /// The target's policy leans on the rule-based target's action: this
    /// weight is added to its logit (`prior.rs`; 0: off, the paper's).
    /// Left out of the stored config while 0, as `vector_input`.
    #[serde(skip_serializing_if = "is_zero")]
    pub heuristic_prior: f64,
    /// Inputs beyond the spec's (`crate::env::Sight`: wall rays across the
    /// map), appended to the agent vector; the env is built to write them.
    /// Left out of the stored config while off, as `vector_input`.
    #[serde(skip_serializing_if = "Sight::is_off")]
    pub sight: Sight,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl Default for NetConfig {
    fn default() -> Self {
        NetConfig {
            hidden: 128,
            conv_channels: [16, 32],
            patch_pool: 2,
            vector_input: VectorInput::LayerNorm,
            heuristic_prior: 0.0,
            sight: Sight::OFF,
        }
    }
}

/// How the agent vector (spec §5: velocities, positions, headings) is fed
/// to the vector MLP. The observation itself never changes; this is the
/// network's first layer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VectorInput {
    /// A learned layer norm over each row, as the MAPPO reference's
    /// `feature_norm`. It normalises a row by its own mean and spread, so
    /// the network sees the vector only up to a common scale and offset:
    /// how far the target is, in metres, is mixed with every other number
    /// of the row.
    #[default]
    LayerNorm,
    /// Every feature kept apart: positions divided by 8 m (half the 16 m
    /// map), velocities as they are (m/s, at most 1.4), and every heading as
    /// its sine and cosine, so 0 and 2 pi read the same.
    Scaled,
    /// Turned into the robot's own frame, as the patch already is: the
    /// others' offsets and velocities as (forward, left), their distances
    /// and bearings, headings as sines and cosines (`EgocentricVector`),
    /// then the reference's learned layer norm over those features.
    Egocentric,
}

impl VectorInput {
    pub fn is_layer_norm(&self) -> bool {
        *self == VectorInput::LayerNorm
    }
}

/// The fixed input map of `VectorInput::Scaled` for vectors of `agents`
/// robots' observations concatenated, each in `write_vector`'s layout
/// (own velocity, position, heading; then the N others' velocities,
/// relative positions, relative headings: 5 + 5N numbers).
#[derive(Debug)]
pub(crate) struct ScaledVector {
    /// Indices of the velocities and positions, and what each is multiplied by.
    linear: Tensor,
    scale: Tensor,
    /// Indices of the headings.
    angles: Tensor,
    /// Width of the output: per robot, 4 + 4N linear numbers and 2 (1 + N) for the headings.
    pub width: i64,
}

/// Metres by which positions are divided.
const POSITION_SCALE: f32 = 8.0;

/// (numbers per robot, other robots N) of `vector_len` numbers holding
/// `agents` robots' vectors in `write_vector`'s layout (5 + 5N each), each
/// followed by `sight` more (the sight's, `Sight::len`).
/// Panics on any other length: the network's shape is fixed at build time.
pub(crate) fn vector_layout(vector_len: i64, agents: i64, sight: i64) -> (i64, i64) {
    assert!(
        agents > 0 && vector_len % agents == 0,
        "vector of {vector_len} numbers for {agents} robots"
    );
    let per = vector_len / agents;
    let spec = per - sight;
    assert!(
        spec >= 5 && (spec - 5) % 5 == 0,
        "a robot's vector has 5 + 5N + {sight} numbers, not {per}"
    );
    (per, (spec - 5) / 5)
}

impl ScaledVector {
    /// `sight`: the numbers after each robot's 5 + 5N (wall rays, already
    /// in [0, 1]), passed on as they are.
    pub(crate) fn new(vector_len: i64, agents: i64, sight: usize) -> ScaledVector {
        let (per, others) = vector_layout(vector_len, agents, sight as i64);
        let (mut linear, mut scale, mut angles) = (Vec::new(), Vec::new(), Vec::new());
        for a in 0..agents {
            let base = a * per;
            let mut push = |i: i64, s: f32| {
                linear.push(base + i);
                scale.push(s);
            };
            push(0, 1.0);
            push(1, 1.0);
            push(2, 1.0 / POSITION_SCALE);
            push(3, 1.0 / POSITION_SCALE);
            for k in 0..2 * others {
                push(5 + k, 1.0);
            }
            for k in 0..2 * others {
                push(5 + 2 * others + k, 1.0 / POSITION_SCALE);
            }
            for k in 0..sight as i64 {
                push(5 + 5 * others + k, 1.0);
            }
            angles.push(base + 4);
            angles.extend((0..others).map(|k| base + 5 + 4 * others + k));
        }
        let width = Self::width_of(vector_len as usize, agents as usize, sight) as i64;
        debug_assert_eq!(width, linear.len() as i64 + 2 * angles.len() as i64);
        ScaledVector {
            linear: Tensor::from_slice(&linear),
            scale: Tensor::from_slice(&scale),
            angles: Tensor::from_slice(&angles),
            width,
        }
    }

    /// The output width for `vector_len` numbers of `agents` robots.
    fn width_of(vector_len: usize, agents: usize, sight: usize) -> usize {
        let per = vector_len / agents.max(1);
        let others = per.saturating_sub(5 + sight) / 5;
        agents * (per + 1 + others)
    }

    /// `vectors` [..., vector_len] -> [..., width].
    pub(crate) fn apply(&self, vectors: &Tensor) -> Tensor {
        let dev = vectors.device();
        let last = vectors.dim() as i64 - 1;
        let lin =
            vectors.index_select(last, &self.linear.to_device(dev)) * self.scale.to_device(dev);
        let ang = vectors.index_select(last, &self.angles.to_device(dev));
        Tensor::cat(&[lin, ang.sin(), ang.cos()], last)
    }
}

impl NetConfig {
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_range("hidden", self.hidden, 8..=4096, "must be in 8..=4096")?;
        if self.conv_channels.iter().any(|&c| !(1..=512).contains(&c)) {
            return Err(ConfigError::new(
                "conv_channels",
                format!("{:?}", self.conv_channels),
                "each must be in 1..=512",
            ));
        }
        if ![1, 2, 3, 4, 6].contains(&self.patch_pool) {
            return Err(ConfigError::new(
                "patch_pool",
                self.patch_pool,
                "must divide 48 and leave at least 8 pixels (1, 2, 3, 4 or 6)",
            ));
        }
        self.sight.validate()?;
        // NaN compares false with everything: unchecked, a NaN weight
        // would read as "off" where the prior is tested with `> 0`.
        if !(self.heuristic_prior.is_finite()
            && (0.0..=prior::MAX_WEIGHT).contains(&self.heuristic_prior))
        {
            return Err(ConfigError::new(
                "heuristic_prior",
                self.heuristic_prior,
                format!("must be a number in [0, {}] (0: off)", prior::MAX_WEIGHT),
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
        let v = match self.vector_input {
            VectorInput::LayerNorm => v,
            VectorInput::Scaled => {
                ScaledVector::width_of(vector_len, channels, self.sight.len()) as f64
            }
            VectorInput::Egocentric => {
                EgocentricVector::width_of(vector_len, channels, self.sight.len()) as f64
            }
        };
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

/// The vector's first layer, as `VectorInput` says.
#[derive(Debug)]
pub(crate) enum VectorIn {
    LayerNorm(nn::LayerNorm),
    Scaled(ScaledVector),
    Egocentric(EgocentricVector, nn::LayerNorm),
}

/// Patch CNN + vector MLP, concatenated, then one MLP layer.
#[derive(Debug)]
struct Encoder {
    conv1: nn::Conv2D,
    conv2: nn::Conv2D,
    patch_fc: nn::Linear,
    vector_input: VectorIn,
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
        // Positions are metres in a 16 m map and headings are radians:
        // either way, one learning rate must suit every input.
        let (vector_input, width) = match cfg.vector_input {
            VectorInput::LayerNorm => (
                VectorIn::LayerNorm(nn::layer_norm(
                    p / "vector_norm",
                    vec![vector_len],
                    Default::default(),
                )),
                vector_len,
            ),
            VectorInput::Scaled => {
                let s = ScaledVector::new(vector_len, channels, cfg.sight.len());
                let w = s.width;
                (VectorIn::Scaled(s), w)
            }
            VectorInput::Egocentric => {
                let e = EgocentricVector::new(vector_len, channels, cfg.sight.len());
                let w = e.width;
                let norm = nn::layer_norm(p / "vector_norm", vec![w], Default::default());
                (VectorIn::Egocentric(e, norm), w)
            }
        };
        Encoder {
            conv1: nn::conv2d(p / "conv1", channels, c1, 3, conv),
            conv2: nn::conv2d(p / "conv2", c1, c2, 3, conv),
            patch_fc: nn::linear(p / "patch_fc", c2 * side * side, h, Default::default()),
            vector_input,
            vector_fc: nn::linear(p / "vector_fc", width, h, Default::default()),
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
        let v = match &self.vector_input {
            VectorIn::LayerNorm(norm) => vectors.apply(norm),
            VectorIn::Scaled(s) => s.apply(vectors),
            VectorIn::Egocentric(e, norm) => e.apply(vectors).apply(norm),
        };
        let v = v.apply(&self.vector_fc).relu();
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

/// Draws an action index from (unnormalised) probabilities, as every policy
/// that samples does: learners while training, league opponents, sampled
/// checkpoints.
pub fn sample(p: &[f32], rng: &mut rand_chacha::ChaCha8Rng) -> usize {
    use rand::Rng;
    let mut u = rng.gen::<f32>() * p.iter().sum::<f32>();
    for (i, &x) in p.iter().enumerate() {
        if u < x {
            return i;
        }
        u -= x;
    }
    p.len() - 1
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
    fn a_nan_or_out_of_range_prior_is_refused_not_read_as_off() {
        for bad in [f64::NAN, f64::INFINITY, -1.0, prior::MAX_WEIGHT + 1.0] {
            let net = NetConfig {
                heuristic_prior: bad,
                ..NetConfig::default()
            };
            let err = net.validate().unwrap_err().to_string();
            assert!(err.contains("heuristic_prior"), "{bad}: {err}");
        }
        for good in [0.0, 2.0, prior::MAX_WEIGHT] {
            let net = NetConfig {
                heuristic_prior: good,
                ..NetConfig::default()
            };
            assert!(net.validate().is_ok(), "{good}");
        }
    }

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
            ..Default::default()
        };
        let conv = 2.0 * 9.0 * (25.0 * 8.0 + 4.0 * 16.0 * 8.0);
        let linear = 2.0 * (16.0 * 4.0 * 64.0 + 20.0 * 64.0 + 2.0 * 64.0 * 64.0 + 64.0 * 5.0);
        let gru = 12.0 * 64.0 * 64.0;
        assert_eq!(cfg.forward_flops(1, 20, 5), conv + linear + gru);
    }

    #[test]
    fn scaled_vector_by_hand() {
        use std::f32::consts::{FRAC_PI_2, PI, TAU};
        // One captor of 3:1: own velocity, position, heading; the 3 others'
        // velocities, relative positions and relative headings.
        let mut v = vec![0.5f32, -1.0, 4.0, -8.0, TAU];
        v.extend([1., 2., 3., 4., 5., 6.]);
        v.extend([8., 16., -8., 0., 24., 4.]);
        v.extend([0., FRAC_PI_2, -PI]);
        let want: Vec<f32> = vec![
            0.5, -1.0, 0.5, -1.0, // own velocity, position / 8
            1., 2., 3., 4., 5., 6., // velocities
            1., 2., -1., 0., 3., 0.5, // relative positions / 8
            0., 0., 1., 0., // sines of TAU, 0, pi/2, -pi
            1., 1., 0., -1., // cosines
        ];
        let s = ScaledVector::new(20, 1, 0);
        assert_eq!((s.width, ScaledVector::width_of(20, 1, 0)), (24, 24));
        let got = Vec::<f32>::try_from(s.apply(&Tensor::from_slice(&v).view([1, 20])).view([-1]))
            .unwrap();
        for (i, (g, w)) in got.iter().zip(&want).enumerate() {
            assert!((g - w).abs() < 1e-5, "feature {i}: {g} against {w}");
        }
        // A centralised critic's view: two robots' vectors side by side map
        // robot by robot, linear parts first, then every sine, every cosine.
        let two = ScaledVector::new(40, 2, 0);
        assert_eq!((two.width, ScaledVector::width_of(40, 2, 0)), (48, 48));
        let mut vv = v.clone();
        vv.extend(v.iter().map(|x| -x));
        let got =
            Vec::<f32>::try_from(two.apply(&Tensor::from_slice(&vv).view([1, 40])).view([-1]))
                .unwrap();
        let neg: Vec<f32> = want.iter().map(|x| -x).collect();
        assert_eq!(&got[..16], &want[..16]);
        assert_eq!(&got[16..32], &neg[..16]);
        // sin(-x) = -sin(x); cos(-x) = cos(x).
        for k in 0..4 {
            assert!((got[32 + k] - want[16 + k]).abs() < 1e-5);
            assert!((got[36 + k] + want[16 + k]).abs() < 1e-5);
            assert!((got[40 + k] - want[20 + k]).abs() < 1e-5);
            assert!((got[44 + k] - want[20 + k]).abs() < 1e-5);
        }
        // It has no weights, and the layer norm's are gone with it.
        let vs = nn::VarStore::new(Device::Cpu);
        let cfg = NetConfig {
            hidden: 8,
            vector_input: VectorInput::Scaled,
            ..NetConfig::default()
        };
        let _ = Actor::new(&vs.root(), &cfg, 20);
        let names: Vec<String> = vs.variables().into_keys().collect();
        assert!(
            names.iter().all(|n| !n.contains("vector_norm")),
            "{names:?}"
        );
        assert_eq!(
            vs.variables()["encoder.vector_fc.weight"].size(),
            vec![8, 24]
        );
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
