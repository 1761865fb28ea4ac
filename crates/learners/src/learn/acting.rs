//! Acting: turning the observations of many worlds into a batch for one
//! network. A side's robots of the chosen worlds become adjacent rows (world
//! by world), patches pooled as the network reads them; the trainer's own
//! learners and the league's frozen opponents both act through this, one
//! forward pass per network over all the worlds it plays in.

use crate::nn::{pool_patch, NetConfig};
use t2e_core::env::{Side, VecEnv, PATCH_LEN};

/// Copies one side's observations out of the vector env, a world's robots
/// adjacent, pooling each patch for the side's network.
pub fn gather_side(
    venv: &VecEnv,
    side: Side,
    net: &NetConfig,
    vectors: &mut [f32],
    patches: &mut [u8],
) {
    let worlds: Vec<usize> = (0..venv.num_envs()).collect();
    gather_worlds(
        venv,
        &venv.vectors,
        &venv.patches,
        &worlds,
        side,
        net,
        vectors,
        patches,
    );
}

/// `gather_side` for some worlds only, from `src_vectors` / `src_patches`
/// laid out as the vector env's buffers ([world][agent][...]).
#[allow(clippy::too_many_arguments)]
pub fn gather_worlds(
    venv: &VecEnv,
    src_vectors: &[f32],
    src_patches: &[u8],
    worlds: &[usize],
    side: Side,
    net: &NetConfig,
    vectors: &mut [f32],
    patches: &mut [u8],
) {
    let k = venv.cfg.num_captors;
    let (na, vl) = (k + 1, venv.cfg.vector_len());
    let (pool, pl) = (net.patch_pool as usize, net.input_len());
    let team = side.agents(k).len();
    for (w, &e) in worlds.iter().enumerate() {
        for (j, agent) in side.agents(k).enumerate() {
            let (row, src) = (w * team + j, e * na + agent);
            vectors[row * vl..(row + 1) * vl]
                .copy_from_slice(&src_vectors[src * vl..(src + 1) * vl]);
            pool_patch(
                &src_patches[src * PATCH_LEN..(src + 1) * PATCH_LEN],
                pool,
                &mut patches[row * pl..(row + 1) * pl],
            );
        }
    }
}

pub use crate::nn::sample;

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn sampling_follows_the_probabilities() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let p = [0.1f32, 0.0, 0.6, 0.3, 0.0];
        let mut counts = [0usize; 5];
        for _ in 0..20_000 {
            counts[sample(&p, &mut rng)] += 1;
        }
        assert_eq!((counts[1], counts[4]), (0, 0));
        for (c, q) in counts.iter().zip(p) {
            assert!(
                (*c as f64 / 20_000.0 - q as f64).abs() < 0.015,
                "{counts:?}"
            );
        }
    }
}
