//! The networks of spec §9 in tch: a CNN over the obstacle patch and an MLP
//! over the agent vector, concatenated, then an MLP and a GRU; the actor ends
//! in a categorical head over the 5 actions, the critic in one value.
//!
//! Teammates share one actor and one critic. The critic's encoder reads the
//! observations of `critic_agents` robots at once (their patches stacked as
//! channels, their vectors concatenated, the robot's own first): all
//! teammates for MAPPO's centralised critic, just the robot for IPPO's.

pub mod checkpoint;
mod config;
mod egocentric;
mod net;
pub mod policy;
pub mod prior;
pub mod run_dir;
mod seeding;
pub mod stacked;
mod vector;

pub use checkpoint::CheckpointMeta;
pub use policy::{CheckpointController, PolicyError, PolicySnapshot};
/// Pooling happens once per observation, outside the network.
pub use t2e_core::env::features::pool_patch;

pub use config::{NetConfig, VectorInput};
pub(crate) use net::Trunk;
pub use net::{obs_tensors, Actor, Critic};
pub use seeding::{sample, seed_torch, seeded};

#[cfg(test)]
mod tests {
    use super::vector::ScaledVector;
    use super::*;
    use t2e_core::env::PATCH;
    use tch::{nn, Device, Kind, Tensor};

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
