//! `NetConfig`: the networks' sizes and inputs, as a config and a
//! checkpoint's meta.json record them.

use super::egocentric::EgocentricVector;
use super::prior;
use super::vector::ScaledVector;
use serde::{Deserialize, Serialize};
use t2e_core::env::{Sight, PATCH};
use t2e_core::error::{in_range, ConfigError};

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
    /// Whose move the prior's weight goes to: a scripted target's spec
    /// (`robust:10:heuristic+expert:1+expert:2`) in place of the rule-based
    /// target's. The policy is then that planner's plus what it learns, and
    /// pays the planner's cost at every decision, wherever it plays: the
    /// planner is part of the network, as the prior is (`prior.rs`). None:
    /// the rule-based target, and left out of the stored config.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prior_teacher: Option<String>,
    /// Inputs beyond the spec's (`t2e_core::env::Sight`: wall rays across the
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
            prior_teacher: None,
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
        if let Some(teacher) = &self.prior_teacher {
            if self.heuristic_prior == 0.0 {
                return Err(ConfigError::new(
                    "prior_teacher",
                    format!("\"{teacher}\""),
                    "is the move the prior leans on, and heuristic_prior is 0 (off): set heuristic_prior or drop prior_teacher",
                ));
            }
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
    pub(crate) fn conv_out_side(&self) -> i64 {
        let s = self.input_side() as i64;
        let s = (s - 3) / 2 + 1;
        (s - 3) / 2 + 1
    }
}
