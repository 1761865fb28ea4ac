//! The ASZ against the paper's own implementation, on the 600 states of
//! `../shared/reference-asz/asz-states.csv` (its README says how they were
//! made): |ASZ| of each state, and of each of one captor's four one-step
//! moves, with the per-robot arrival fields (`AszFields`), beside today's
//! one-pass labelled march (`FastMarching::asz_cells`) for comparison, and
//! the coarse ASZ (the fields on cells of 2 x 2 and 4 x 4 map cells).
//!
//! Held here (the goals of the per-robot fields, measured on these states):
//! - relative difference of |ASZ|: median <= 0.3%, p95 <= 2%, none above 10%;
//! - the planner's pick (the move of smallest |ASZ|) agrees with the
//!   reference's in >= 95% of the states where the reference's four values
//!   are not all equal.

use std::collections::BTreeMap;
use std::sync::Arc;
use t2e_core::asz::{AszFields, CoarseLattice, FastMarching, Source};
use t2e_core::map::catalog::{gibson_dir, shared_file};
use t2e_core::map::{load_png, PreparedMap};

struct State {
    map: String,
    speed_ratio: f64,
    captors: [[f64; 2]; 3],
    target: [f64; 2],
    reference: f64,
    mover: usize,
    moves: [[f64; 2]; 4],
    reference_after: [f64; 4],
}

type Maps = BTreeMap<String, Arc<PreparedMap>>;

fn load() -> Option<(Vec<State>, Maps)> {
    let (Some(path), Some(gibson)) = (shared_file("reference-asz/asz-states.csv"), gibson_dir())
    else {
        if std::env::var_os("CI").is_some() {
            panic!("../shared/reference-asz or the Gibson maps not found and CI is set");
        }
        eprintln!("note: ../shared/reference-asz not found; the ASZ reference test is skipped");
        return None;
    };
    let mut reader = csv::Reader::from_path(&path).unwrap();
    let headers = reader.headers().unwrap().clone();
    let col = |name: &str| {
        headers
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{}: no column {name}", path.display()))
    };
    let cols = (
        col("map"),
        col("speed_ratio"),
        ["c0_x", "c0_y", "c1_x", "c1_y", "c2_x", "c2_y", "t_x", "t_y"].map(col),
        col("asz_cells_reference"),
        col("mover"),
        [
            "m0_x", "m0_y", "m1_x", "m1_y", "m2_x", "m2_y", "m3_x", "m3_y",
        ]
        .map(col),
        [
            "asz_after_m0",
            "asz_after_m1",
            "asz_after_m2",
            "asz_after_m3",
        ]
        .map(col),
    );
    let mut states = Vec::new();
    let mut maps = BTreeMap::new();
    for (line, record) in reader.records().enumerate() {
        let r = record.unwrap();
        let num = |i: usize| -> f64 {
            r[i].parse().unwrap_or_else(|_| {
                panic!(
                    "{} line {}: {:?} is not a number",
                    path.display(),
                    line + 2,
                    &r[i]
                )
            })
        };
        let p = cols.2.map(num);
        let m = cols.5.map(num);
        let state = State {
            map: r[cols.0].to_string(),
            speed_ratio: num(cols.1),
            captors: [[p[0], p[1]], [p[2], p[3]], [p[4], p[5]]],
            target: [p[6], p[7]],
            reference: num(cols.3),
            mover: num(cols.4) as usize,
            moves: [[m[0], m[1]], [m[2], m[3]], [m[4], m[5]], [m[6], m[7]]],
            reference_after: cols.6.map(num),
        };
        maps.entry(state.map.clone()).or_insert_with(|| {
            Arc::new(PreparedMap::new(
                load_png(&gibson.join(&state.map)).unwrap(),
            ))
        });
        states.push(state);
    }
    assert_eq!(states.len(), 600, "{}: 600 states", path.display());
    Some((states, maps))
}

/// |ASZ| of a state and of its four moves, by one method.
fn measure(
    states: &[State],
    maps: &BTreeMap<String, Arc<PreparedMap>>,
    mut asz: impl FnMut(&PreparedMap, Source, &[Source], Option<(usize, [f64; 2])>) -> f64,
) -> Vec<(f64, [f64; 4])> {
    states
        .iter()
        .map(|s| {
            let map = &maps[&s.map];
            let target = Source {
                pos: s.target,
                speed: s.speed_ratio,
            };
            let captors = s.captors.map(|pos| Source { pos, speed: 1.0 });
            let now = asz(map, target, &captors, None);
            let after = s
                .moves
                .map(|pos| asz(map, target, &captors, Some((s.mover, pos))));
            (now, after)
        })
        .collect()
}

struct Agreement {
    median: f64,
    p95: f64,
    worst: f64,
    above_10: usize,
    picks_agree: usize,
    picks_told_apart: usize,
}

fn agreement(states: &[State], ours: &[(f64, [f64; 4])]) -> Agreement {
    let mut rel: Vec<f64> = states
        .iter()
        .zip(ours)
        .map(|(s, (now, _))| (now - s.reference).abs() / s.reference.max(1.0))
        .collect();
    rel.sort_by(f64::total_cmp);
    let pick = |v: &[f64; 4]| (0..4).min_by(|&a, &b| v[a].total_cmp(&v[b])).unwrap();
    let told_apart: Vec<usize> = (0..states.len())
        .filter(|&i| {
            states[i]
                .reference_after
                .iter()
                .any(|&v| v != states[i].reference_after[0])
        })
        .collect();
    let picks_agree = told_apart
        .iter()
        .filter(|&&i| {
            let ours = &ours[i].1;
            let want = &states[i].reference_after;
            // Our pick is right when the reference gives it its smallest value.
            want[pick(ours)] == want[pick(want)]
        })
        .count();
    Agreement {
        median: rel[rel.len() / 2],
        p95: rel[(rel.len() as f64 * 0.95) as usize],
        worst: *rel.last().unwrap(),
        above_10: rel.iter().filter(|&&r| r > 0.10).count(),
        picks_agree,
        picks_told_apart: told_apart.len(),
    }
}

fn report(name: &str, a: &Agreement) {
    eprintln!(
        "{name}: median {:.2}%, p95 {:.2}%, worst {:.1}%, {} states above 10%; picks agree in {} of {} ({:.1}%)",
        100.0 * a.median,
        100.0 * a.p95,
        100.0 * a.worst,
        a.above_10,
        a.picks_agree,
        a.picks_told_apart,
        100.0 * a.picks_agree as f64 / a.picks_told_apart as f64
    );
}

#[test]
fn per_robot_fields_agree_with_the_reference_asz() {
    let Some((states, maps)) = load() else { return };
    let mut fields = AszFields::new();
    let ours = measure(&states, &maps, |map, target, captors, moved| {
        let cells = fields.asz_cells(map, target, captors);
        match moved {
            None => cells as f64,
            Some((i, pos)) => fields.with_moved_captor(map, target, captors, i, pos) as f64,
        }
    });
    let mut march = FastMarching::new();
    let one_pass = measure(&states, &maps, |map, target, captors, moved| {
        let mut captors = captors.to_vec();
        if let Some((i, pos)) = moved {
            captors[i].pos = pos;
        }
        march.asz_cells(map, target, &captors) as f64
    });
    let exact = states
        .iter()
        .zip(&ours)
        .filter(|(s, (now, _))| *now == s.reference)
        .count();
    let exact_moves = states
        .iter()
        .zip(&ours)
        .map(|(s, (_, after))| (0..4).filter(|&m| after[m] == s.reference_after[m]).count())
        .sum::<usize>();
    eprintln!("per-robot fields: {exact} of 600 states and {exact_moves} of 2400 moves equal the reference's cell for cell count");
    let fields_agreement = agreement(&states, &ours);
    report("per-robot fields", &fields_agreement);
    report("one-pass march", &agreement(&states, &one_pass));
    // The coarse ASZ (the same fields on cells of K x K map cells, as
    // `greedy:K`, the shaping potential and the lookahead target use it),
    // its cells counted in map cells.
    let mut coarse_agreement = Vec::new();
    for k in [2usize, 4] {
        let lattices: BTreeMap<&String, CoarseLattice> = maps
            .iter()
            .map(|(n, m)| (n, CoarseLattice::new(m, k)))
            .collect();
        let mut by_map: BTreeMap<*const PreparedMap, &CoarseLattice> = BTreeMap::new();
        for (n, m) in &maps {
            by_map.insert(Arc::as_ptr(m), &lattices[n]);
        }
        let mut coarse = AszFields::new();
        let ours = measure(&states, &maps, |map, target, captors, moved| {
            let lattice = by_map[&(map as *const PreparedMap)];
            let cells = match moved {
                None => coarse.asz_cells(lattice, target, captors),
                Some((i, pos)) => coarse.with_moved_captor(lattice, target, captors, i, pos),
            };
            (cells * k * k) as f64
        });
        let a = agreement(&states, &ours);
        report(&format!("coarse fields, {k}x{k} map cells"), &a);
        coarse_agreement.push(a);
    }
    // Coarse cells close gaps narrower than a cell and count only cells
    // free all through (so they undercount): they are a controller's score,
    // not the spec's |ASZ|. Held at what they measured (2026-11-28: median
    // 3.1% and 8.7%, picks 80% and 66%), so that a change that makes them
    // worse is seen.
    for ((k, max_median, min_picks), a) in [(2, 0.04, 0.75), (4, 0.10, 0.60)]
        .iter()
        .zip(&coarse_agreement)
    {
        assert!(
            a.median <= *max_median
                && a.picks_agree as f64 >= min_picks * a.picks_told_apart as f64,
            "coarse {k}: median {:.1}%, picks {} of {}",
            100.0 * a.median,
            a.picks_agree,
            a.picks_told_apart
        );
    }
    let a = fields_agreement;
    assert!(
        a.median <= 0.003,
        "median relative difference {:.3}%",
        100.0 * a.median
    );
    assert!(
        a.p95 <= 0.02,
        "p95 relative difference {:.3}%",
        100.0 * a.p95
    );
    assert!(
        a.above_10 == 0,
        "{} states differ by more than 10% (worst {:.1}%)",
        a.above_10,
        100.0 * a.worst
    );
    assert!(
        a.picks_agree as f64 >= 0.95 * a.picks_told_apart as f64,
        "picks agree in {} of {}",
        a.picks_agree,
        a.picks_told_apart
    );
}
