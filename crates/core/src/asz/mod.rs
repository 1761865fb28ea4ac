//! Arrival times and the Absolutely Safe Zone (spec §3).
//!
//! The ASZ itself is `AszFields` (fields.rs): one arrival field per robot,
//! as the spec defines it and the paper's code computes it. Everything that
//! reads |ASZ| uses it: the environment (SoA, the strict capture rule, the
//! Python `asz_area` and infos), the ASZ-greedy planner on the spec's cells
//! (`greedy`), the shaping potential, the lookahead target and the renders.
//!
//! march.rs holds one first-order Fast Marching pass (Sethian) with
//! labelled fronts, each cell claimed by the front that arrives first. With
//! one front it is the geodesic distance the planner falls back on
//! (`distance_field`). With every robot's front it is a one-pass |ASZ|
//! (`asz_cells`) that closes the narrow gaps between captor regions which
//! per-robot fields keep open. It stays for `greedy:K` on coarse cells,
//! where its fronts start from the 2 x 2 cells around each robot and so
//! move with every move (fields there, each in the one cell holding its
//! robot, made the planner far weaker), and as the baseline the fields are
//! measured against (the reference conformance test, `bench`).

mod coarse;
mod field_queue;
mod fields;
mod march;

pub use coarse::CoarseLattice;
pub use fields::{AszFields, DistanceField};
pub use march::{
    cells_to_m2, strict_capture_cells, FastMarching, Lattice, Seeds, Source, NO_LABEL,
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{Grid, PreparedMap, CELL_SIZE};

    /// Free rectangle rows r0..r1, cols c0..c1 of a 320-cell grid.
    fn room(r0: usize, r1: usize, c0: usize, c1: usize) -> Grid {
        Grid::with_free_rects("room", 320, &[(r0..r1, c0..c1)])
    }

    /// First-order FMM on a 4-neighbour grid overestimates distances off the
    /// axes, most along the diagonals (measured here: at most 0.083 m over a
    /// 14 m x 14 m room, 2.1% beyond 3 m from the source, 1.1% on the
    /// diagonal at 6.5 m). Accepted: |fmm - euclid| <= 0.025 d + 0.05 m, and
    /// under 3% beyond 3 m.
    #[test]
    fn open_room_distances_match_euclid_within_first_order_error() {
        let map = PreparedMap::new(room(20, 300, 20, 300));
        let mut fm = FastMarching::new();
        let from = map.grid.cell_center(160, 160);
        fm.distance_field(&map, from);
        let mut worst_rel: f64 = 0.0;
        let mut axis_err: f64 = 0.0;
        for r in (20..300).step_by(7) {
            for c in (20..300).step_by(7) {
                let p = map.grid.cell_center(r, c);
                let d = (p[0] - from[0]).hypot(p[1] - from[1]);
                let t = fm.time(map.padded_index(r as isize, c as isize)) as f64;
                assert!(
                    (t - d).abs() <= 0.025 * d + 0.05,
                    "cell ({r},{c}): fmm {t} vs {d}"
                );
                assert!(
                    t >= d - 1e-3,
                    "first-order FMM never underestimates: {t} < {d}"
                );
                if d > 3.0 {
                    worst_rel = worst_rel.max((t - d) / d);
                }
                if r == 160 || c == 160 {
                    axis_err = axis_err.max((t - d).abs());
                }
            }
        }
        assert!(
            axis_err < 1e-4,
            "along the axes the march is exact, got {axis_err}"
        );
        assert!(worst_rel < 0.03, "relative error beyond 3 m: {worst_rel}");
    }

    #[test]
    fn l_shaped_corridor_matches_hand_computed_geodesic() {
        // Horizontal arm: rows 100..120, cols 100..260; vertical arm: rows 100..260, cols 240..260.
        let mut g = room(100, 120, 100, 260);
        for r in 100..260 {
            for c in 240..260 {
                g.set_free(r, c, true);
            }
        }
        let map = PreparedMap::new(g);
        let a = map.grid.cell_center(110, 110); // in the horizontal arm
        let b = map.grid.cell_center(250, 250); // bottom of the vertical arm
                                                // The shortest path bends around the inner corner, the grid vertex at
                                                // the top-left of cell (120, 240).
        let half = map.grid.extent() / 2.0;
        let corner = [240.0 * CELL_SIZE - half, half - 120.0 * CELL_SIZE];
        let dist = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
        let geodesic = dist(a, corner) + dist(corner, b);
        let euclid = dist(a, b);
        let mut fm = FastMarching::new();
        fm.distance_field(&map, a);
        let t = fm.time(map.padded_index(250, 250)) as f64;
        assert!(geodesic - euclid > 0.9, "the corridor must force a detour");
        // Measured: 13.100 m against 13.038 m (0.5%); accepted within 1%.
        assert!(
            (t - geodesic).abs() <= 0.01 * geodesic,
            "fmm {t} vs geodesic {geodesic}"
        );
    }

    #[test]
    fn asz_is_the_whole_room_without_captors_and_empty_when_boxed_in() {
        let g = room(100, 140, 100, 160);
        let free = g.free_cells();
        let map = PreparedMap::new(g);
        let mut fm = FastMarching::new();
        let target = Source {
            pos: map.grid.cell_center(120, 130),
            speed: 1.0,
        };
        assert_eq!(fm.asz_cells(&map, target, &[]), free);

        // Target in a dead end 1 cell wide and 3 long; a captor in its mouth
        // reaches every other cell first.
        let mut g = room(100, 140, 100, 160);
        for r in 97..100 {
            g.set_free(r, 130, true);
        }
        let map = PreparedMap::new(g);
        let target = Source {
            pos: map.grid.cell_center(97, 130),
            speed: 1.0,
        };
        let captor = Source {
            pos: map.grid.cell_center(99, 130),
            speed: 1.0,
        };
        let boxed = fm.asz_cells(&map, target, &[captor]);
        assert!(boxed <= 2, "target boxed in a dead end keeps {boxed} cells");

        // Equal distance: ties go to the captor. Target and captor mirror each
        // other around the middle column of a 1-row corridor.
        let g = room(100, 101, 100, 111);
        let map = PreparedMap::new(g);
        let target = Source {
            pos: map.grid.cell_center(100, 100),
            speed: 1.0,
        };
        let captor = Source {
            pos: map.grid.cell_center(100, 110),
            speed: 1.0,
        };
        assert_eq!(fm.asz_cells(&map, target, &[captor]), 5);
    }

    #[test]
    fn faster_target_wins_more_and_asz_matches_separate_marches() {
        let map = PreparedMap::new(room(60, 260, 60, 260));
        let mut fm = FastMarching::new();
        let captors: Vec<Source> = [(100, 100), (100, 220), (230, 160)]
            .iter()
            .map(|&(r, c)| Source {
                pos: map.grid.cell_center(r, c),
                speed: 1.0,
            })
            .collect();
        let pos = map.grid.cell_center(150, 150);
        let slow = fm.asz_cells(&map, Source { pos, speed: 1.0 }, &captors);
        let fast = fm.asz_cells(&map, Source { pos, speed: 1.4 }, &captors);
        assert!(fast > slow && slow > 0, "slow {slow}, fast {fast}");

        // The reference's way: one march per robot, then compare arrival times.
        let times = |fm: &mut FastMarching, p: [f64; 2], v: f64| {
            fm.distance_field(&map, p);
            (0..map.obstacle.len())
                .map(|c| fm.time(c) as f64 / v)
                .collect::<Vec<_>>()
        };
        let te = times(&mut fm, pos, 1.4);
        let tp: Vec<Vec<f64>> = captors.iter().map(|s| times(&mut fm, s.pos, 1.0)).collect();
        let separate = (0..te.len())
            .filter(|&c| te[c].is_finite() && tp.iter().all(|t| te[c] < t[c]))
            .count();
        let diff = (separate as f64 - fast as f64).abs() / separate as f64;
        assert!(
            diff < 0.01,
            "one pass {fast} vs separate marches {separate}"
        );
    }
}
