//! One process's thread pools, sized once: the environments' rayon pool
//! and libtorch's, both to the same count. libtorch's default (every core)
//! collapses beside a busy neighbour, so a command sizes them before its
//! first parallel step.

use anyhow::{bail, Result};

/// Sizes both pools for `--threads N` (0: `OMP_NUM_THREADS` if set, else
/// the cores the load average leaves free) and returns the count and why.
pub fn size_pools(requested: usize) -> Result<(usize, String)> {
    if requested > 256 {
        bail!("--threads {requested}: at most 256");
    }
    let (threads, why) = t2e_core::util::thread_count(requested);
    // An error means this process already started the pool (a library
    // caller running a second command): that pool stays.
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global();
    tch::set_num_threads(threads as i32);
    Ok((threads, why))
}
