//! The payoff tally: a player's wins and games from the store's payoff rows
//! (captor wins per captor-target pair). One place for the side arithmetic
//! that the matchmaker (a learner's record against each member) and
//! `status` (each player's record) both need: a target's wins are the
//! games its captors did not win.

use crate::data::PairResult;
use t2e_core::env::Side;

/// Wins and games of a player who plays `side`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Record {
    pub wins: u64,
    pub games: u64,
}

impl Record {
    pub fn win_rate(&self) -> Option<f64> {
        (self.games > 0).then(|| self.wins as f64 / self.games as f64)
    }
}

/// `player`'s record, playing `side`, against `opponent` (every opponent
/// when None).
pub fn record(payoff: &[PairResult], player: i64, side: Side, opponent: Option<i64>) -> Record {
    let mut rec = Record::default();
    for r in payoff {
        let (mine, theirs) = match side {
            Side::Captors => (r.captor, r.target),
            Side::Target => (r.target, r.captor),
        };
        if mine != player || opponent.is_some_and(|o| o != theirs) {
            continue;
        }
        rec.games += r.games;
        rec.wins += match side {
            Side::Captors => r.captor_wins,
            Side::Target => r.games - r.captor_wins,
        };
    }
    rec
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(captor: i64, target: i64, captor_wins: u64, games: u64) -> PairResult {
        PairResult {
            captor,
            target,
            captor_wins,
            games,
        }
    }

    #[test]
    fn a_record_counts_each_side_from_its_own_seat() {
        // Captors 1 and 2, targets 10 and 11.
        let payoff = [pair(1, 10, 3, 4), pair(1, 11, 0, 6), pair(2, 10, 5, 5)];
        assert_eq!(
            record(&payoff, 1, Side::Captors, None),
            Record { wins: 3, games: 10 }
        );
        assert_eq!(
            record(&payoff, 1, Side::Captors, Some(11)),
            Record { wins: 0, games: 6 }
        );
        // Target 10 escaped once in 9 games: 1 of 4 against captors 1, 0 of 5 against 2.
        assert_eq!(
            record(&payoff, 10, Side::Target, None),
            Record { wins: 1, games: 9 }
        );
        assert_eq!(
            record(&payoff, 10, Side::Target, Some(2)),
            Record { wins: 0, games: 5 }
        );
        // Player 10 never played captors.
        assert_eq!(record(&payoff, 10, Side::Captors, None), Record::default());
        assert_eq!(
            record(&payoff, 11, Side::Target, None).win_rate(),
            Some(1.0)
        );
        assert_eq!(Record::default().win_rate(), None);
    }
}
