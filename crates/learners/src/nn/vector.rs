//! The agent vector's fixed input maps: `ScaledVector` and the layout of
//! robots' observations concatenated (`vector_layout`).

use tch::Tensor;

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
    pub(crate) fn width_of(vector_len: usize, agents: usize, sight: usize) -> usize {
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
