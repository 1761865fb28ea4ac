//! Randomness: torch's global generator seeded under a lock, and drawing
//! an action from probabilities.

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
