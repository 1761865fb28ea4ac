//! The networks: encoder (patch CNN + vector MLP), GRU trunk, actor and
//! critic heads, and the observations as their input tensors.

use super::config::{NetConfig, VectorInput};
use super::egocentric::EgocentricVector;
use super::vector::ScaledVector;
use t2e_core::env::Action;
use tch::nn::{self, RNN};
use tch::{Device, Kind, Tensor};

/// The vector's first layer, as `VectorInput` says.
#[derive(Debug)]
pub(crate) enum VectorIn {
    LayerNorm(nn::LayerNorm),
    Scaled(ScaledVector),
    Egocentric(EgocentricVector, nn::LayerNorm),
}

/// Patch CNN + vector MLP, concatenated, then one MLP layer.
#[derive(Debug)]
pub(super) struct Encoder {
    pub(super) conv1: nn::Conv2D,
    pub(super) conv2: nn::Conv2D,
    pub(super) patch_fc: nn::Linear,
    pub(super) vector_input: VectorIn,
    pub(super) vector_fc: nn::Linear,
    pub(super) merge_fc: nn::Linear,
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
    pub(super) encoder: Encoder,
    pub(super) gru: nn::GRU,
    /// The GRU's weight_ih, weight_hh, bias_ih, bias_hh (shared with the
    /// GRU, which keeps its own private): for stacking frozen actors.
    pub(super) gru_params: [Tensor; 4],
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
    pub(super) fn gru_weights(&self) -> (&Tensor, &Tensor, &Tensor, &Tensor) {
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
    pub(super) trunk: Trunk,
    pub(super) head: nn::Linear,
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
