//! The evaluation protocol end to end on real maps.

use std::sync::Arc;
use t2e_core::map::{self, PreparedMap};
use t2e_learners::controllers::ControllerSpec;
use t2e_learners::eval::{self, EvalSetting};

fn shipped_small() -> Arc<Vec<Arc<PreparedMap>>> {
    let entries = map::resolve("shipped:small").unwrap();
    Arc::new(
        entries
            .iter()
            .map(|e| Arc::new(PreparedMap::new(e.load().unwrap())))
            .collect(),
    )
}

#[test]
fn same_seed_same_records_and_paired_starts() {
    let maps = shipped_small();
    let setting = EvalSetting {
        episodes: 12,
        episode_length: 150,
        soa_every: 5,
        ..EvalSetting::default()
    };
    let (a, ra) = eval::run(&setting, &maps, "shipped:small", false).unwrap();
    let (b, rb) = eval::run(&setting, &maps, "shipped:small", false).unwrap();
    assert_eq!(ra, rb, "evaluation is reproducible");
    assert_eq!(a, b);
    // Another captor controller faces the same seeds and maps.
    let random = EvalSetting {
        captors: ControllerSpec::Random,
        ..setting.clone()
    };
    let (_, rr) = eval::run(&random, &maps, "shipped:small", false).unwrap();
    for (x, y) in ra.iter().zip(&rr) {
        assert_eq!((x.seed, &x.map), (y.seed, &y.map));
    }
    assert!(
        ra.iter().any(|r| r.map != ra[0].map),
        "episodes sample maps from the set"
    );
}

#[test]
fn heuristic_captors_beat_random_ones() {
    let maps = shipped_small();
    let base = EvalSetting {
        episodes: 40,
        episode_length: 300,
        soa_every: 1,
        ..EvalSetting::default()
    };
    let (heur, records) = eval::run(&base, &maps, "small", false).unwrap();
    let random = EvalSetting {
        captors: ControllerSpec::Random,
        ..base.clone()
    };
    let (rand, _) = eval::run(&random, &maps, "small", false).unwrap();
    assert!(
        heur.sr >= 40.0,
        "expert captors trap the rule-based target often: SR {}",
        heur.sr
    );
    assert!(
        rand.sr < heur.sr - 25.0,
        "random captors {} vs expert {}",
        rand.sr,
        heur.sr
    );
    assert!(heur.time < rand.time);
    assert!(heur.sr_low <= heur.sr && heur.sr <= heur.sr_high);
    for r in records.iter().filter(|r| r.captured) {
        assert_eq!(
            r.soa_m2.len() as u32,
            r.steps + 1,
            "one SoA sample per step plus the start"
        );
    }
}

/// The fast rule is local (probes blocked by walls or robots) and can fire
/// while a doorway still leaves the target a safe zone; the strict rule ends
/// an episode exactly when |ASZ| falls to pi (1.5 r / 0.05)^2 cells.
#[test]
fn strict_capture_ends_episodes_at_the_asz_threshold() {
    let maps = shipped_small();
    let strict = EvalSetting {
        episodes: 30,
        episode_length: 300,
        soa_every: 1,
        capture_rule: t2e_core::env::CaptureRule::Strict,
        ..EvalSetting::default()
    };
    let (summary, records) = eval::run(&strict, &maps, "small", false).unwrap();
    assert!(summary.sr > 0.0, "some strict captures happen");
    let threshold =
        t2e_core::asz::cells_to_m2(t2e_core::asz::strict_capture_cells(0.2).floor() as usize);
    for r in &records {
        let last = *r.soa_m2.last().unwrap();
        if r.captured {
            assert!(last <= threshold + 1e-9, "captured at |ASZ| {last} m^2");
            assert!(
                r.soa_m2[..r.soa_m2.len() - 1]
                    .iter()
                    .all(|&s| s > threshold),
                "no earlier step was below the threshold"
            );
        } else {
            assert!(r.soa_m2.iter().all(|&s| s > threshold));
        }
    }
}

/// The departure rate counts the target's decisions that are not the
/// rule-based target's: none measured for the rule-based target itself,
/// every decision for a target that stands still (the rule-based target
/// never stops), and for the lookahead target, whose ties keep the rule's
/// action, a share strictly between.
#[test]
fn a_targets_departures_from_the_rule_based_target_are_counted_per_decision() {
    let maps = shipped_small();
    let base = EvalSetting {
        episodes: 4,
        episode_length: 60,
        soa_every: 0,
        ..EvalSetting::default()
    };
    let (rule, records) = eval::run(&base, &maps, "shipped:small", false).unwrap();
    assert_eq!(rule.target_departure, None);
    assert!(records.iter().all(|r| r.target_departures.is_none()));
    let still = EvalSetting {
        target: ControllerSpec::Still,
        ..base.clone()
    };
    let (s, records) = eval::run(&still, &maps, "shipped:small", false).unwrap();
    assert_eq!(s.target_departure, Some(100.0));
    for r in &records {
        // One decision per step the episode ran.
        let steps = if r.captured { r.steps } else { 60 };
        assert_eq!(r.target_departures, Some((steps, steps)), "{r:?}");
        // Every decision has a nearest-captor bin; without --soa-every no
        // state's |ASZ| is measured, so none has an |ASZ| bin.
        let places = r.target_departure_places.expect("measured with the share");
        let by_distance: u32 = places.by_captor_distance.iter().map(|t| t.decisions).sum();
        assert_eq!(by_distance, steps);
        assert!(places
            .by_captor_distance
            .iter()
            .all(|t| t.departures == t.decisions));
        assert!(places.by_asz.iter().all(|t| t.decisions == 0));
    }
    // A capture needs a captor within a metre (the probes sit 0.3 m out),
    // so a caught target decided at least once in the nearest bin.
    let places = s.target_departure_places.unwrap();
    if records.iter().any(|r| r.captured) {
        assert!(places.by_captor_distance[0].decisions > 0, "{places:?}");
    }
    let total: u32 = records.iter().map(|r| r.target_departures.unwrap().1).sum();
    assert_eq!(
        places
            .by_captor_distance
            .iter()
            .map(|t| t.decisions)
            .sum::<u32>(),
        total
    );
    // Measuring |ASZ| every step places every decision by |ASZ| too.
    let measured = EvalSetting {
        soa_every: 1,
        ..still.clone()
    };
    let (m, _) = eval::run(&measured, &maps, "shipped:small", false).unwrap();
    let places = m.target_departure_places.unwrap();
    assert_eq!(
        places.by_asz.iter().map(|t| t.decisions).sum::<u32>(),
        total
    );
    assert_eq!(rule.target_departure_places, None);
    let look = EvalSetting {
        target: "lookahead:3".parse().unwrap(),
        ..base
    };
    let (l, _) = eval::run(&look, &maps, "shipped:small", false).unwrap();
    let d = l.target_departure.unwrap();
    assert!(d > 0.0 && d < 100.0, "{d}");
}
