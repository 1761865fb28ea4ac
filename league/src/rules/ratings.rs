//! Ratings on one scale for captor teams and targets, from their
//! head-to-head matches (a captor team "wins" a match by capturing).
//!
//! - Live: Weng-Lin (a Bayesian rating with an uncertainty per player, from
//!   the skillratings crate), updated by every recorded match. Chosen over
//!   Elo because `status` shows each rating with its uncertainty, and a new
//!   snapshot's few games should move it fast and say it is unsure.
//! - Batch: a Bradley-Terry fit over the whole payoff table, since the live
//!   ratings come from matches the matchmaker chose (PFSP favours hard
//!   opponents), which biases them. The fit uses (possibly decayed) wins and
//!   games per captor-target pair and a weak prior (one drawn game against a
//!   fixed reference player of rating 0), so an undefeated player stays
//!   finite. Elo units: a 400-point gap is 10:1 odds.

use skillratings::weng_lin::{weng_lin, WengLinConfig, WengLinRating};
use skillratings::Outcomes;

/// A live rating: mean and uncertainty (one standard deviation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rating {
    pub mu: f64,
    pub sigma: f64,
}

impl Default for Rating {
    fn default() -> Self {
        let r = WengLinRating::new();
        Rating {
            mu: r.rating,
            sigma: r.uncertainty,
        }
    }
}

/// The ratings after one match between a captor team and a target.
pub fn update(captors: Rating, target: Rating, captors_won: bool) -> (Rating, Rating) {
    let (c, t) = weng_lin(
        &WengLinRating {
            rating: captors.mu,
            uncertainty: captors.sigma,
        },
        &WengLinRating {
            rating: target.mu,
            uncertainty: target.sigma,
        },
        if captors_won {
            &Outcomes::WIN
        } else {
            &Outcomes::LOSS
        },
        &WengLinConfig::new(),
    );
    (
        Rating {
            mu: c.rating,
            sigma: c.uncertainty,
        },
        Rating {
            mu: t.rating,
            sigma: t.uncertainty,
        },
    )
}

/// Games between two players: `wins` of them won by `a`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairRecord {
    pub a: usize,
    pub b: usize,
    pub wins: f64,
    pub games: f64,
}

/// Bradley-Terry strengths (Elo units, the reference player at 0) of
/// `players` players from their pair records, by Hunter's MM iterations.
pub fn bradley_terry(players: usize, pairs: &[PairRecord]) -> Vec<f64> {
    const PRIOR_GAMES: f64 = 1.0;
    let mut wins = vec![PRIOR_GAMES / 2.0; players];
    for p in pairs {
        wins[p.a] += p.wins;
        wins[p.b] += p.games - p.wins;
    }
    let mut strength = vec![1.0f64; players];
    for _ in 0..2000 {
        let mut denom = vec![0.0f64; players];
        for i in 0..players {
            denom[i] = PRIOR_GAMES / (strength[i] + 1.0);
        }
        for p in pairs.iter().filter(|p| p.games > 0.0) {
            let d = p.games / (strength[p.a] + strength[p.b]);
            denom[p.a] += d;
            denom[p.b] += d;
        }
        let mut change = 0.0f64;
        for i in 0..players {
            let next = (wins[i] / denom[i]).clamp(1e-12, 1e12);
            change = change.max((next.ln() - strength[i].ln()).abs());
            strength[i] = next;
        }
        if change < 1e-10 {
            break;
        }
    }
    strength.iter().map(|s| 400.0 * s.log10()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weng_lin_moves_the_winner_up_and_shrinks_uncertainty() {
        let (c, t) = update(Rating::default(), Rating::default(), true);
        assert!(c.mu > 25.0 && t.mu < 25.0);
        assert!(c.sigma < Rating::default().sigma && t.sigma < Rating::default().sigma);
        // Symmetric for a loss.
        let (c2, t2) = update(Rating::default(), Rating::default(), false);
        assert!((c2.mu - t.mu).abs() < 1e-12 && (t2.mu - c.mu).abs() < 1e-12);
    }

    #[test]
    fn bradley_terry_recovers_odds_and_keeps_the_undefeated_finite() {
        // A beats B 3 times in 4 over 4000 games: odds 3, 400 log10 3 = 190.85 apart.
        let r = bradley_terry(
            2,
            &[PairRecord {
                a: 0,
                b: 1,
                wins: 3000.0,
                games: 4000.0,
            }],
        );
        assert!(((r[0] - r[1]) - 190.85).abs() < 1.0, "{r:?}");
        // Transitivity through a common opponent: A-B odds 3, B-C odds 3 -> A-C odds 9.
        let r = bradley_terry(
            3,
            &[
                PairRecord {
                    a: 0,
                    b: 1,
                    wins: 3000.0,
                    games: 4000.0,
                },
                PairRecord {
                    a: 1,
                    b: 2,
                    wins: 3000.0,
                    games: 4000.0,
                },
            ],
        );
        assert!(((r[0] - r[2]) - 381.7).abs() < 2.0, "{r:?}");
        // Never lost: large but finite; no games: at the reference.
        let r = bradley_terry(
            3,
            &[PairRecord {
                a: 0,
                b: 1,
                wins: 10.0,
                games: 10.0,
            }],
        );
        assert!(r.iter().all(|x| x.is_finite()) && r[0] > r[1], "{r:?}");
        assert!(r[2].abs() < 1e-6, "{r:?}");
    }
}
