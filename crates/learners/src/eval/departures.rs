//! Where a target departs from the rule-based target: its decisions and
//! departures counted by the state they were taken in. A learned or
//! planned target that departs only when a captor is close, or only once
//! its safe zone has shrunk, is told apart from one that departs anywhere;
//! the share alone (`Summary::target_departure`) says neither.
//!
//! Two views of the same decisions, each cut into fixed bins so that two
//! evaluations are compared bin by bin:
//! - the distance from the target's centre to its nearest captor's (m);
//! - the target's |ASZ| (m^2) in the state it decided in, counted only at
//!   the steps where the evaluation measures it (`--soa-every`).

use serde::{Deserialize, Serialize};

/// Upper edges (m) of the nearest-captor distance bins; the last bin is
/// open. The fast capture rule's probes sit 0.3 m from the target, and a
/// captor covers about 0.1 m a step at 1 m/s.
pub const CAPTOR_DISTANCE_EDGES_M: [f64; 3] = [1.0, 2.0, 4.0];

/// Upper edges (m^2) of the |ASZ| bins; the last bin is open. The strict
/// capture rule's threshold is about 0.28 m^2; a large Gibson map starts
/// its episodes with tens of m^2.
pub const ASZ_EDGES_M2: [f64; 3] = [2.0, 8.0, 32.0];

/// Decisions and departures in one bin.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tally {
    pub decisions: u32,
    pub departures: u32,
}

impl Tally {
    fn add(&mut self, departed: bool) {
        self.decisions += 1;
        self.departures += u32::from(departed);
    }

    fn merge(&mut self, other: Tally) {
        self.decisions += other.decisions;
        self.departures += other.departures;
    }
}

/// One episode's (or a setting's) decisions by where they were taken.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct DeparturePlaces {
    /// By nearest-captor distance, bins split at `CAPTOR_DISTANCE_EDGES_M`.
    pub by_captor_distance: [Tally; 4],
    /// By |ASZ|, bins split at `ASZ_EDGES_M2`; only decisions whose state's
    /// |ASZ| was measured.
    pub by_asz: [Tally; 4],
}

/// The bin of `value` among `edges` (ascending upper edges, the last bin open).
fn bin(value: f64, edges: &[f64; 3]) -> usize {
    edges.iter().take_while(|&&edge| value >= edge).count()
}

/// A bin's label: "[lo, hi)" in the unit given, the last one "≥ lo".
fn label(edges: &[f64; 3], i: usize, unit: &str) -> String {
    match i {
        0 => format!("< {} {unit}", edges[0]),
        3 => format!(">= {} {unit}", edges[2]),
        _ => format!("{}-{} {unit}", edges[i - 1], edges[i]),
    }
}

impl DeparturePlaces {
    /// Counts one decision: the target's distance to its nearest captor,
    /// its |ASZ| if measured in this state, and whether it departed.
    pub fn record(&mut self, captor_distance_m: f64, asz_m2: Option<f64>, departed: bool) {
        self.by_captor_distance[bin(captor_distance_m, &CAPTOR_DISTANCE_EDGES_M)].add(departed);
        if let Some(asz) = asz_m2 {
            self.by_asz[bin(asz, &ASZ_EDGES_M2)].add(departed);
        }
    }

    pub fn merge(&mut self, other: &DeparturePlaces) {
        for (a, b) in self
            .by_captor_distance
            .iter_mut()
            .zip(other.by_captor_distance)
        {
            a.merge(b);
        }
        for (a, b) in self.by_asz.iter_mut().zip(other.by_asz) {
            a.merge(b);
        }
    }

    /// Every bin as a row: (view, bin label, tally); the rows of
    /// departures.csv and of the summary's table.
    pub fn rows(&self) -> Vec<(&'static str, String, Tally)> {
        let mut rows = Vec::with_capacity(8);
        for (i, t) in self.by_captor_distance.iter().enumerate() {
            rows.push((
                "nearest_captor",
                label(&CAPTOR_DISTANCE_EDGES_M, i, "m"),
                *t,
            ));
        }
        for (i, t) in self.by_asz.iter().enumerate() {
            rows.push(("asz", label(&ASZ_EDGES_M2, i, "m^2"), *t));
        }
        rows
    }
}

/// The departure share (%) of a tally; None without decisions.
pub fn share(t: Tally) -> Option<f64> {
    (t.decisions > 0).then(|| 100.0 * t.departures as f64 / t.decisions as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decisions_fall_in_the_bin_their_state_belongs_to() {
        let mut p = DeparturePlaces::default();
        // 0.5 m from a captor, |ASZ| 1 m^2, departed.
        p.record(0.5, Some(1.0), true);
        // On an edge: 1.0 m goes to the second bin, 8 m^2 to the third.
        p.record(1.0, Some(8.0), false);
        // Far, |ASZ| not measured in this state.
        p.record(10.0, None, true);
        assert_eq!(
            p.by_captor_distance,
            [
                Tally {
                    decisions: 1,
                    departures: 1
                },
                Tally {
                    decisions: 1,
                    departures: 0
                },
                Tally::default(),
                Tally {
                    decisions: 1,
                    departures: 1
                },
            ]
        );
        assert_eq!(
            p.by_asz,
            [
                Tally {
                    decisions: 1,
                    departures: 1
                },
                Tally::default(),
                Tally {
                    decisions: 1,
                    departures: 0
                },
                Tally::default(),
            ]
        );
        let mut twice = p;
        twice.merge(&p);
        assert_eq!(
            twice.by_captor_distance[3],
            Tally {
                decisions: 2,
                departures: 2
            }
        );
        assert_eq!(share(twice.by_asz[0]), Some(100.0));
        assert_eq!(share(twice.by_asz[1]), None);
        let labels: Vec<String> = p.rows().into_iter().map(|(_, l, _)| l).collect();
        assert_eq!(labels[0], "< 1 m");
        assert_eq!(labels[1], "1-2 m");
        assert_eq!(labels[3], ">= 4 m");
        assert_eq!(labels[4], "< 2 m^2");
        assert_eq!(labels[7], ">= 32 m^2");
    }
}
