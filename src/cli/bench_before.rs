//! The date of the figures `bench` prints beside today's: each of its
//! tables (the environment's in bench.rs, the planner's in bench_greedy.rs)
//! compares with rows measured then.

/// When the `before_us` figures were measured: `bench --threads 1` on the
/// Gibson maps, on a 2-core machine of the kind the docs' tables come from.
pub(super) const BEFORE_DATE: &str = "2026-11-26";
