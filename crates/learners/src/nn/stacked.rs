//! Several frozen actors of one architecture evaluated in one forward pass.
//!
//! A league learner plays many opponents at once, each in a few worlds. One
//! pass per opponent leaves a handful of rows per pass, and at that size
//! libtorch's fixed cost per operator dominates (measured: about 3x the cost
//! per row of the learner's own 48-row pass). Here the G opponents' weights
//! are stacked along a leading group axis: the convolutions become grouped
//! convolutions (group g sees channel g) and the linear layers and the GRU
//! batched matrix products, so G opponents cost one pass of ~25 operators
//! over G x R rows, R being the most rows any one of them plays this step.
//!
//! Numerically this is the same network as `Actor::step` (a test checks it
//! to 1e-5 against each opponent's own pass).

use super::config::{NetConfig, VectorInput};
use super::egocentric::EgocentricVector;
use super::net::{Actor, VectorIn};
use super::vector::ScaledVector;
use t2e_core::env::Action;
use tch::{Kind, Tensor};

/// One actor's weights, laid out for stacking (linear weights transposed to
/// [in, out], biases as [1, out]). Prepared once when an opponent is loaded,
/// so a restack is a plain copy.
#[derive(Debug)]
pub struct PreparedActor {
    pub net: NetConfig,
    pub vector_len: i64,
    tensors: Vec<Tensor>,
}

/// Order of `PreparedActor::tensors`.
const CONV1_W: usize = 0;
const CONV1_B: usize = 1;
const CONV2_W: usize = 2;
const CONV2_B: usize = 3;
const PATCH_W: usize = 4;
const PATCH_B: usize = 5;
const NORM_W: usize = 6;
const NORM_B: usize = 7;
const VECTOR_W: usize = 8;
const VECTOR_B: usize = 9;
const MERGE_W: usize = 10;
const MERGE_B: usize = 11;
const IH_W: usize = 12;
const IH_B: usize = 13;
const HH_W: usize = 14;
const HH_B: usize = 15;
const HEAD_W: usize = 16;
const HEAD_B: usize = 17;

impl PreparedActor {
    pub fn new(actor: &Actor, net: &NetConfig, vector_len: usize) -> PreparedActor {
        let e = &actor.trunk.encoder;
        let gru = actor.trunk.gru_weights();
        let linear = |l: &tch::nn::Linear| {
            let b = l.bs.as_ref().expect("linear layers have biases");
            (l.ws.tr().contiguous(), b.view([1, -1]))
        };
        let (pw, pb) = linear(&e.patch_fc);
        let (vw, vb) = linear(&e.vector_fc);
        let (mw, mb) = linear(&e.merge_fc);
        let (hw, hb) = linear(&actor.head);
        // A scaled vector has no weights of its own: ones and zeros keep the
        // layout (and stack), and `step` does not read them.
        let (norm_w, norm_b) = match &e.vector_input {
            VectorIn::LayerNorm(norm) | VectorIn::Egocentric(_, norm) => (
                norm.ws.as_ref().expect("affine layer norm").shallow_clone(),
                norm.bs.as_ref().expect("affine layer norm").shallow_clone(),
            ),
            VectorIn::Scaled(_) => (
                Tensor::ones([1], (Kind::Float, tch::Device::Cpu)),
                Tensor::zeros([1], (Kind::Float, tch::Device::Cpu)),
            ),
        };
        let tensors = vec![
            e.conv1.ws.shallow_clone(),
            e.conv1.bs.as_ref().expect("conv bias").shallow_clone(),
            e.conv2.ws.shallow_clone(),
            e.conv2.bs.as_ref().expect("conv bias").shallow_clone(),
            pw,
            pb,
            norm_w.view([1, -1]),
            norm_b.view([1, -1]),
            vw,
            vb,
            mw,
            mb,
            gru.0.tr().contiguous(),
            gru.2.view([1, -1]),
            gru.1.tr().contiguous(),
            gru.3.view([1, -1]),
            hw,
            hb,
        ];
        let tensors = tensors.into_iter().map(|t| t.detach().copy()).collect();
        PreparedActor {
            net: net.clone(),
            vector_len: vector_len as i64,
            tensors,
        }
    }

    /// Actors stack only with actors of the same shape.
    pub fn same_shape(&self, other: &PreparedActor) -> bool {
        self.net == other.net && self.vector_len == other.vector_len
    }
}

/// `VectorIn` without its weights (they are stacked with the others).
#[derive(Debug)]
enum StackedVectorIn {
    LayerNorm,
    Scaled(ScaledVector),
    Egocentric(EgocentricVector),
}

/// G actors' weights stacked along a leading group axis.
#[derive(Debug)]
pub struct StackedActors {
    pub groups: i64,
    pub hidden: i64,
    pub input_side: i64,
    pub vector_len: i64,
    /// What the vector goes through before the first linear layer.
    vector_input: StackedVectorIn,
    /// conv weights [G*c_out, c_in, 3, 3], biases [G*c_out]; the rest [G, ...].
    tensors: Vec<Tensor>,
}

/// Why actors cannot run as one stacked network.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum StackError {
    #[error("no actors to stack")]
    Empty,
    #[error("cannot stack networks of different shapes ({0})")]
    Shapes(String),
}

impl StackedActors {
    /// Stacks actors of one shape (checked).
    pub fn new(actors: &[&PreparedActor]) -> Result<StackedActors, StackError> {
        let first = actors.first().ok_or(StackError::Empty)?;
        if let Some(odd) = actors.iter().find(|a| !a.same_shape(first)) {
            return Err(StackError::Shapes(format!(
                "{:?}, {} inputs vs {:?}, {} inputs",
                first.net, first.vector_len, odd.net, odd.vector_len
            )));
        }
        let tensors: Vec<Tensor> = (0..first.tensors.len())
            .map(|i| {
                let parts: Vec<&Tensor> = actors.iter().map(|a| &a.tensors[i]).collect();
                match i {
                    // Grouped convolutions want the groups concatenated.
                    CONV1_W | CONV1_B | CONV2_W | CONV2_B => Tensor::cat(&parts, 0),
                    _ => Tensor::stack(&parts, 0),
                }
            })
            .collect();
        Ok(StackedActors {
            groups: actors.len() as i64,
            hidden: first.net.hidden,
            input_side: first.net.input_side() as i64,
            vector_len: first.vector_len,
            vector_input: match first.net.vector_input {
                VectorInput::LayerNorm => StackedVectorIn::LayerNorm,
                VectorInput::Scaled => StackedVectorIn::Scaled(ScaledVector::new(
                    first.vector_len,
                    1,
                    first.net.sight.len(),
                )),
                VectorInput::Egocentric => StackedVectorIn::Egocentric(EgocentricVector::new(
                    first.vector_len,
                    1,
                    first.net.sight.len(),
                )),
            },
            tensors,
        })
    }

    /// One step of every group. `patches` [G, R, side, side] (u8),
    /// `vectors` [G, R, vector_len], `h` [G, R, hidden]; returns logits
    /// [G, R, actions] and the new state. Padding rows (zeros) are harmless:
    /// they only produce numbers nobody reads.
    pub fn step(&self, patches: &Tensor, vectors: &Tensor, h: &Tensor) -> (Tensor, Tensor) {
        let t = &self.tensors;
        let g = self.groups;
        let rows = vectors.size()[1];
        // Group g's rows become channel g of the grouped convolution.
        let x = patches
            .transpose(0, 1)
            .to_kind(Kind::Float)
            .conv2d(&t[CONV1_W], Some(&t[CONV1_B]), [2, 2], [0, 0], [1, 1], g)
            .relu()
            .conv2d(&t[CONV2_W], Some(&t[CONV2_B]), [2, 2], [0, 0], [1, 1], g)
            .relu()
            .view([rows, g, -1])
            .transpose(0, 1);
        let x = t[PATCH_B].baddbmm(&x, &t[PATCH_W], 1, 1).relu();
        let norm = |v: &Tensor| {
            let width = *v.size().last().expect("vectors have a last axis");
            v.layer_norm([width], None::<Tensor>, None::<Tensor>, 1e-5, false) * &t[NORM_W]
                + &t[NORM_B]
        };
        let v = match &self.vector_input {
            StackedVectorIn::Scaled(s) => s.apply(vectors),
            StackedVectorIn::LayerNorm => norm(vectors),
            StackedVectorIn::Egocentric(e) => norm(&e.apply(vectors)),
        };
        let v = t[VECTOR_B].baddbmm(&v, &t[VECTOR_W], 1, 1).relu();
        let x = Tensor::cat(&[x, v], 2);
        let x = t[MERGE_B].baddbmm(&x, &t[MERGE_W], 1, 1).relu();
        // PyTorch's GRU: gates r, z, n; n = tanh(W_in x + b_in + r * (W_hn h + b_hn)).
        let gi = t[IH_B].baddbmm(&x, &t[IH_W], 1, 1).chunk(3, 2);
        let gh = t[HH_B].baddbmm(h, &t[HH_W], 1, 1).chunk(3, 2);
        let r = (&gi[0] + &gh[0]).sigmoid();
        let z = (&gi[1] + &gh[1]).sigmoid();
        let n = (&gi[2] + r * &gh[2]).tanh();
        let h_new = &n + z * (h - &n);
        let logits = t[HEAD_B].baddbmm(&h_new, &t[HEAD_W], 1, 1);
        debug_assert_eq!(logits.size()[2], Action::COUNT as i64);
        (logits, h_new)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tch::{nn, Device};

    #[test]
    fn stacked_actors_match_each_actors_own_pass() {
        stacked_pass_matches(crate::nn::VectorInput::LayerNorm);
    }

    #[test]
    fn stacked_scaled_actors_match_each_actors_own_pass() {
        stacked_pass_matches(crate::nn::VectorInput::Scaled);
    }

    #[test]
    fn stacked_egocentric_actors_match_each_actors_own_pass() {
        stacked_pass_matches(crate::nn::VectorInput::Egocentric);
    }

    fn stacked_pass_matches(vector_input: crate::nn::VectorInput) {
        let _seed = crate::nn::seed_torch(3);
        let cfg = NetConfig {
            hidden: 16,
            conv_channels: [4, 8],
            patch_pool: 2,
            vector_input,
            ..NetConfig::default()
        };
        let vl = 20usize;
        let stores: Vec<(nn::VarStore, Actor)> = (0..3)
            .map(|_| {
                let vs = nn::VarStore::new(Device::Cpu);
                let a = Actor::new(&vs.root(), &cfg, vl);
                // Non-trivial layer-norm affine and biases, so a mix-up shows.
                tch::no_grad(|| {
                    for (_, mut t) in vs.variables() {
                        let noise = Tensor::randn(t.size(), (Kind::Float, Device::Cpu)) * 0.3;
                        let _ = t.g_add_(&noise);
                    }
                });
                (vs, a)
            })
            .collect();
        let prepared: Vec<PreparedActor> = stores
            .iter()
            .map(|(_, a)| PreparedActor::new(a, &cfg, vl))
            .collect();
        let stacked = StackedActors::new(&prepared.iter().collect::<Vec<_>>()).unwrap();
        let side = cfg.input_side() as i64;
        let rows_of = [3i64, 1, 2];
        let r = 3i64;
        let patches = Tensor::randint(2, [3, r, side, side], (Kind::Uint8, Device::Cpu));
        let vectors = Tensor::randn([3, r, vl as i64], (Kind::Float, Device::Cpu));
        let h = Tensor::randn([3, r, 16], (Kind::Float, Device::Cpu));
        let (logits, h_new) = tch::no_grad(|| stacked.step(&patches, &vectors, &h));
        for (g, (_, actor)) in stores.iter().enumerate() {
            let n = rows_of[g];
            let gi = g as i64;
            let p = patches.get(gi).narrow(0, 0, n).unsqueeze(1);
            let v = vectors.get(gi).narrow(0, 0, n);
            let h0 = h.get(gi).narrow(0, 0, n);
            let (want_logits, want_h) = tch::no_grad(|| actor.step(&p, &v, &h0));
            let got_logits = logits.get(gi).narrow(0, 0, n);
            let got_h = h_new.get(gi).narrow(0, 0, n);
            let dl = f64::try_from((got_logits - &want_logits).abs().max()).unwrap();
            let dh = f64::try_from((got_h - &want_h).abs().max()).unwrap();
            assert!(
                // Grouped and plain kernels sum in different orders: allow f32 rounding.
                dl < 1e-4 && dh < 1e-4,
                "group {g}: logits differ by {dl}, state by {dh}"
            );
            assert!(
                f64::try_from(want_logits.abs().max()).unwrap() > 1e-3,
                "test weights too small to tell"
            );
        }
        let other = NetConfig {
            hidden: 32,
            ..cfg.clone()
        };
        let vs = nn::VarStore::new(Device::Cpu);
        let odd = PreparedActor::new(&Actor::new(&vs.root(), &other, vl), &other, vl);
        assert!(StackedActors::new(&[&prepared[0], &odd]).is_err());
    }
}
