//! How a training run draws its episodes' maps from its own map set
//! (`map_sampling` of a training config). Uniform over maps is the paper's
//! way; `class-balanced` gives each size class the same share of episodes.
//! Under the paper protocol the 26 Gibson maps are 13 small, 8 medium and
//! 5 large, so uniform draws play large maps in 19% of the episodes, and
//! large maps are where the CPU default stayed under the paper's SR. Which
//! maps are trained on, the environment and the evaluation do not change;
//! a run that balances says so in its config (and hash).

use serde::{Deserialize, Serialize};
use std::sync::Arc;
use t2e_core::map::{PreparedMap, SizeClass};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MapSampling {
    /// Every map equally often (the paper's).
    #[default]
    Uniform,
    /// Every size class equally often (by traversable area, spec §3's
    /// thresholds), maps uniform within their class.
    ClassBalanced,
}

/// The most listings of one map in a balanced list.
const MAX_COPIES: usize = 1000;

/// How many times to list each map of a class with `counts[k]` maps so
/// that the classes are drawn equally often: `L / counts[k]` for the least
/// common multiple L of the non-zero counts when that fits in MAX_COPIES
/// listings per map, else the nearest whole numbers to `MAX_COPIES x
/// min / counts[k]`. 0 for an empty class. Pure.
pub fn balanced_copies(counts: &[usize]) -> Vec<usize> {
    let nonzero: Vec<usize> = counts.iter().copied().filter(|&n| n > 0).collect();
    let Some(&min) = nonzero.iter().min() else {
        return vec![0; counts.len()];
    };
    let lcm = nonzero.iter().try_fold(1usize, |acc, &n| {
        let l = acc / gcd(acc, n) * n;
        (l / min <= MAX_COPIES).then_some(l)
    });
    counts
        .iter()
        .map(|&n| match (n, lcm) {
            (0, _) => 0,
            (n, Some(l)) => l / n,
            (n, None) => ((MAX_COPIES * min) as f64 / n as f64).round().max(1.0) as usize,
        })
        .collect()
}

fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}

/// The list the worlds draw their maps from, uniformly.
pub fn sampling_list(maps: &[Arc<PreparedMap>], how: MapSampling) -> Arc<Vec<Arc<PreparedMap>>> {
    match how {
        MapSampling::Uniform => Arc::new(maps.to_vec()),
        MapSampling::ClassBalanced => {
            let classes = [SizeClass::Small, SizeClass::Medium, SizeClass::Large];
            let class_of: Vec<usize> = maps
                .iter()
                .map(|m| {
                    let c = m.grid.size_class();
                    classes.iter().position(|&k| k == c).expect("three classes")
                })
                .collect();
            let counts: Vec<usize> = (0..3)
                .map(|k| class_of.iter().filter(|&&c| c == k).count())
                .collect();
            let copies = balanced_copies(&counts);
            let mut list = Vec::new();
            for (map, &k) in maps.iter().zip(&class_of) {
                for _ in 0..copies[k] {
                    list.push(map.clone());
                }
            }
            Arc::new(list)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_gibson_counts_balance_exactly() {
        // 13 small, 8 medium, 5 large: lcm 520, so 40, 65 and 104 listings,
        // 520 per class.
        assert_eq!(balanced_copies(&[13, 8, 5]), vec![40, 65, 104]);
        assert_eq!(balanced_copies(&[20, 20, 20]), vec![1, 1, 1]);
        assert_eq!(balanced_copies(&[4, 0, 2]), vec![1, 0, 2]);
        assert_eq!(balanced_copies(&[0, 0, 0]), vec![0, 0, 0]);
    }

    #[test]
    fn counts_whose_lcm_is_too_large_come_close() {
        // lcm(997, 991, 983) is far past 1000 listings per map.
        let counts = [997, 991, 983];
        let copies = balanced_copies(&counts);
        let per_class: Vec<f64> = counts
            .iter()
            .zip(&copies)
            .map(|(&n, &c)| (n * c) as f64)
            .collect();
        let total: f64 = per_class.iter().sum();
        for share in per_class {
            assert!(
                (share / total - 1.0 / 3.0).abs() < 0.001,
                "{share} of {total}"
            );
        }
        assert!(copies.iter().all(|&c| c <= MAX_COPIES));
    }
}
