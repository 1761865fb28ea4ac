//! Matchmaking, after AlphaStar's league: each world of a learner samples
//! its opponent when its episode starts. Opponents come from the other
//! side's pool (frozen snapshots and the permanent heuristic members) by
//! prioritised fictitious self-play (PFSP), or, for a configured share of
//! episodes, the other side's current main learner. Pure functions: the
//! caller supplies the head-to-head record and a seed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use t2e_core::env::vec_env::episode_seed;
use t2e_core::error::{in_interval, in_range, ConfigError};

/// How PFSP turns P[learner wins] = x into a sampling weight.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Weighting {
    /// f_hard(x) = (1 - x)^p: mostly the opponents the learner loses to.
    Hard,
    /// f_var(x) = x (1 - x): the opponents at the learner's level.
    Var,
    /// Every member alike (fictitious self-play).
    Uniform,
}

/// Every knob of matchmaking, with the league's defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MatchmakingConfig {
    pub weighting: Weighting,
    /// Exponent p of f_hard (AlphaStar: 2).
    pub p: f64,
    /// Share of episodes against the other side's current main learner.
    pub main_share: f64,
    /// Share of episodes against the other side's extra heuristic members
    /// (`[members]`), drawn uniformly: PFSP alone would rarely draw a
    /// member the learner mostly beats. 0 (the default, left out of the
    /// stored config) leaves every draw as it was.
    #[serde(skip_serializing_if = "is_zero")]
    pub members_share: f64,
    /// Share of the main captors' episodes against the target exploiter's
    /// newest snapshot (`[exploiters] target = true`). PFSP rarely draws a
    /// target line the captors mostly beat (a prior-free exploiter that
    /// never resets got 17-20% of captors-main's games), yet such a line is
    /// what keeps naive co-evolution's captors hard to exploit. The main
    /// target and the exploiters ignore it. 0 (the default, left out of
    /// the stored config) leaves every draw as it was.
    #[serde(skip_serializing_if = "is_zero")]
    pub target_exploiter_share: f64,
    /// Share of the PFSP probability spread evenly over all members, so no
    /// member starves (a member never drawn never gets a win rate).
    pub floor: f64,
    /// Opponent slots per window of `episode_length` steps: each window the
    /// learner draws this many opponents from the distribution above, and
    /// each world starting an episode plays one of them, uniformly. The
    /// marginal per episode is unchanged (slots are independent draws from
    /// it), but at most 2 x slots networks are in play at once (episodes
    /// begun in the previous window still run), so they fit one stacked
    /// forward pass with many rows each instead of one pass of a few rows
    /// per opponent (`bench --opponents`). Like an AlphaStar actor, the
    /// learner then faces few opponents at a time and many over a run.
    /// Measured in the default league (16 worlds): opponent inference cost
    /// per row 0.95x the learner's own with 1 slot, 1.16x with 2, 1.40x with
    /// 0 (stacked) and 1.50x before stacking. 0 = every world draws from the
    /// whole distribution.
    pub slots: usize,
}

impl Default for MatchmakingConfig {
    fn default() -> Self {
        MatchmakingConfig {
            weighting: Weighting::Hard,
            p: 2.0,
            main_share: 0.35,
            members_share: 0.0,
            target_exploiter_share: 0.0,
            floor: 0.05,
            slots: 1,
        }
    }
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

impl MatchmakingConfig {
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_interval("p", self.p, 0.0, 16.0, false)?;
        for (name, v) in [
            ("main_share", self.main_share),
            ("members_share", self.members_share),
            ("target_exploiter_share", self.target_exploiter_share),
            ("floor", self.floor),
        ] {
            in_interval(name, v, 0.0, 1.0, true)?;
        }
        // The shares split [0, 1) in turn: the error names the last one set.
        if self.main_share + self.members_share + self.target_exploiter_share > 1.0 {
            let (name, share, before) = if self.target_exploiter_share > 0.0 {
                let before = format!(
                    "main_share = {} and members_share = {}",
                    self.main_share, self.members_share
                );
                (
                    "target_exploiter_share",
                    self.target_exploiter_share,
                    before,
                )
            } else {
                let before = format!("main_share = {}", self.main_share);
                ("members_share", self.members_share, before)
            };
            return Err(ConfigError::new(
                name,
                share,
                format!("with {before} the shares exceed 1"),
            ));
        }
        in_range(
            "slots",
            self.slots,
            0..=64,
            "must be in 0..=64 (0 = no slots)",
        )
    }
}

/// A pool member as the learner sees it: its (decayed) wins and games.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    pub player: i64,
    /// The learner's wins against this member (may be decayed, fractional).
    pub wins: f64,
    pub games: f64,
}

impl Candidate {
    /// P[learner beats this member]; 0.5 before any game.
    pub fn win_rate(&self) -> f64 {
        if self.games > 0.0 {
            (self.wins / self.games).clamp(0.0, 1.0)
        } else {
            0.5
        }
    }
}

/// The PFSP sampling probabilities of `pool`: f(win rate), normalised,
/// mixed with `floor` of uniform. All-zero weights (the learner beats every
/// member, say) fall back to uniform. Empty pool: empty vector.
pub fn pfsp_probabilities(pool: &[Candidate], cfg: &MatchmakingConfig) -> Vec<f64> {
    let n = pool.len();
    if n == 0 {
        return Vec::new();
    }
    let f = |x: f64| match cfg.weighting {
        Weighting::Hard => (1.0 - x).powf(cfg.p),
        Weighting::Var => x * (1.0 - x),
        Weighting::Uniform => 1.0,
    };
    let weights: Vec<f64> = pool.iter().map(|c| f(c.win_rate())).collect();
    let total: f64 = weights.iter().sum();
    let uniform = 1.0 / n as f64;
    weights
        .iter()
        .map(|w| {
            let pfsp = if total > 0.0 && total.is_finite() {
                w / total
            } else {
                uniform
            };
            (1.0 - cfg.floor) * pfsp + cfg.floor * uniform
        })
        .collect()
}

/// Who a world plays next.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Opponent {
    /// The other side's current main learner (its latest snapshot).
    Main,
    /// A pool member, by player id.
    Member(i64),
}

/// The seed of one opponent draw: from (league seed, learner, world,
/// episode) only, so a league replays whatever the scheduling.
pub fn draw_seed(league_seed: u64, learner: i64, world: usize, episode: u64) -> u64 {
    episode_seed(
        league_seed ^ (learner as u64).rotate_left(17),
        world,
        episode,
    ) ^ 0x4c45_4147_5545
}

/// The seed of slot `slot`'s draw in window `window` (a window being
/// `episode_length` steps of the learner's vector env).
pub fn slot_seed(league_seed: u64, learner: i64, slot: usize, window: u64) -> u64 {
    draw_seed(league_seed, learner, usize::MAX - slot, window) ^ 0x534c_4f54
}

/// Which of `slots` slots the episode with draw seed `seed` plays: uniform.
pub fn pick_slot(slots: usize, seed: u64) -> usize {
    let u: f64 = ChaCha8Rng::seed_from_u64(seed ^ 0x5049_434b).gen();
    ((u * slots as f64) as usize).min(slots.saturating_sub(1))
}

/// The members a learner plays for a fixed share of its episodes, beside
/// PFSP over the whole pool.
#[derive(Clone, Copy, Debug, Default)]
pub struct Fixed<'a> {
    /// The other side's main learner's newest snapshot (`main_share`); None
    /// until it has one. An empty pool plays it.
    pub main: Option<i64>,
    /// The other side's extra heuristic members, drawn uniformly in
    /// `members_share` of the episodes (by PFSP in the rest, like any member).
    pub extras: &'a [i64],
    /// The target exploiter's newest snapshot (`target_exploiter_share`),
    /// for the main captors; None until it has one, or for other learners.
    pub target_exploiter: Option<i64>,
}

/// Draws an opponent for one episode. The shares split [0, 1) in the order
/// main, extras, target exploiter, then PFSP; a share whose member is
/// missing falls to PFSP.
pub fn choose_opponent(
    pool: &[Candidate],
    fixed: Fixed,
    cfg: &MatchmakingConfig,
    seed: u64,
) -> Option<Opponent> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let u: f64 = rng.gen();
    if fixed.main.is_some() && (pool.is_empty() || u < cfg.main_share) {
        return Some(Opponent::Main);
    }
    let extras = fixed.extras;
    let extras_end = cfg.main_share + cfg.members_share;
    if !extras.is_empty() && (cfg.main_share..extras_end).contains(&u) {
        let v: f64 = rng.gen();
        let i = ((v * extras.len() as f64) as usize).min(extras.len() - 1);
        return Some(Opponent::Member(extras[i]));
    }
    if let Some(exploiter) = fixed.target_exploiter {
        if (extras_end..extras_end + cfg.target_exploiter_share).contains(&u) {
            return Some(Opponent::Member(exploiter));
        }
    }
    let probs = pfsp_probabilities(pool, cfg);
    if probs.is_empty() {
        return None;
    }
    let mut x: f64 = rng.gen::<f64>() * probs.iter().sum::<f64>();
    for (c, p) in pool.iter().zip(&probs) {
        if x < *p {
            return Some(Opponent::Member(c.player));
        }
        x -= p;
    }
    Some(Opponent::Member(pool[pool.len() - 1].player))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fixed(main: Option<i64>, extras: &[i64]) -> Fixed<'_> {
        Fixed {
            main,
            extras,
            target_exploiter: None,
        }
    }

    fn cand(player: i64, wins: f64, games: f64) -> Candidate {
        Candidate {
            player,
            wins,
            games,
        }
    }

    #[test]
    fn pfsp_weights_match_hand_computed_values() {
        let pool = [cand(1, 1.0, 4.0), cand(2, 3.0, 4.0), cand(3, 0.0, 0.0)];
        // Win rates 0.25, 0.75, 0.5 (no games yet).
        let hard = MatchmakingConfig {
            floor: 0.0,
            ..Default::default()
        };
        // (1-x)^2: 0.5625, 0.0625, 0.25; total 0.875.
        let p = pfsp_probabilities(&pool, &hard);
        for (got, want) in p.iter().zip([0.5625 / 0.875, 0.0625 / 0.875, 0.25 / 0.875]) {
            assert!((got - want).abs() < 1e-12, "{p:?}");
        }
        let var = MatchmakingConfig {
            weighting: Weighting::Var,
            floor: 0.0,
            ..Default::default()
        };
        // x(1-x): 0.1875, 0.1875, 0.25; total 0.625.
        let p = pfsp_probabilities(&pool, &var);
        for (got, want) in p.iter().zip([0.3, 0.3, 0.4]) {
            assert!((got - want).abs() < 1e-12, "{p:?}");
        }
        // The floor: 10% spread evenly.
        let floored = MatchmakingConfig {
            floor: 0.1,
            ..Default::default()
        };
        let p = pfsp_probabilities(&pool, &floored);
        assert!((p[1] - (0.9 * 0.0625 / 0.875 + 0.1 / 3.0)).abs() < 1e-12);
        assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn degenerate_pools_still_give_a_distribution() {
        // The learner beats everyone: f_hard is 0 everywhere -> uniform.
        let beaten = [cand(1, 5.0, 5.0), cand(2, 9.0, 9.0)];
        let cfg = MatchmakingConfig {
            floor: 0.0,
            ..Default::default()
        };
        assert_eq!(pfsp_probabilities(&beaten, &cfg), vec![0.5, 0.5]);
        // Var is 0 at both ends too.
        let var = MatchmakingConfig {
            weighting: Weighting::Var,
            floor: 0.0,
            ..Default::default()
        };
        assert_eq!(
            pfsp_probabilities(&[cand(1, 0.0, 3.0), cand(2, 3.0, 3.0)], &var),
            vec![0.5, 0.5]
        );
        assert!(pfsp_probabilities(&[], &cfg).is_empty());
        assert_eq!(choose_opponent(&[], fixed(None, &[]), &cfg, 1), None);
        assert_eq!(
            choose_opponent(&[], fixed(Some(7), &[]), &cfg, 1),
            Some(Opponent::Main)
        );
    }

    #[test]
    fn draws_follow_the_probabilities_and_replay_from_their_seed() {
        let pool = [cand(1, 1.0, 4.0), cand(2, 3.0, 4.0), cand(3, 0.0, 0.0)];
        let cfg = MatchmakingConfig::default();
        let p = pfsp_probabilities(&pool, &cfg);
        let mut counts = [0usize; 4];
        let n = 40_000;
        for episode in 0..n {
            let seed = draw_seed(9, 2, 3, episode);
            let o = choose_opponent(&pool, fixed(Some(99), &[]), &cfg, seed).unwrap();
            assert_eq!(
                choose_opponent(&pool, fixed(Some(99), &[]), &cfg, seed),
                Some(o),
                "replays"
            );
            counts[match o {
                Opponent::Main => 0,
                Opponent::Member(id) => id as usize,
            }] += 1;
        }
        let share = |c: usize| c as f64 / n as f64;
        assert!(
            (share(counts[0]) - cfg.main_share).abs() < 0.01,
            "{counts:?}"
        );
        for i in 0..3 {
            let want = (1.0 - cfg.main_share) * p[i];
            assert!(
                (share(counts[i + 1]) - want).abs() < 0.01,
                "{counts:?} vs {p:?}"
            );
        }
        assert_ne!(
            draw_seed(9, 2, 3, 0),
            draw_seed(9, 3, 3, 0),
            "learners draw apart"
        );
    }

    #[test]
    fn extra_members_get_their_share_and_zero_changes_no_draw() {
        // Member 3 is the extra heuristic: 0.35 main, 0.25 uniform over
        // the extras, and the rest (0.40) by PFSP over all three.
        let pool = [cand(1, 1.0, 4.0), cand(2, 3.0, 4.0), cand(3, 4.0, 4.0)];
        let cfg = MatchmakingConfig {
            members_share: 0.25,
            ..MatchmakingConfig::default()
        };
        let p = pfsp_probabilities(&pool, &cfg);
        let n = 40_000;
        let mut counts = [0usize; 4];
        for episode in 0..n {
            let seed = draw_seed(9, 2, 3, episode);
            counts[match choose_opponent(&pool, fixed(Some(99), &[3]), &cfg, seed).unwrap() {
                Opponent::Main => 0,
                Opponent::Member(id) => id as usize,
            }] += 1;
            // Without a share, the extras change nothing: the same draw as
            // a league without them.
            let plain = MatchmakingConfig::default();
            assert_eq!(
                choose_opponent(&pool, fixed(Some(99), &[3]), &plain, seed),
                choose_opponent(&pool, fixed(Some(99), &[]), &plain, seed)
            );
        }
        let share = |c: usize| c as f64 / n as f64;
        assert!((share(counts[0]) - 0.35).abs() < 0.01, "{counts:?}");
        // The learner beats member 3 every time: PFSP gives it only the floor.
        let want3 = 0.25 + 0.40 * p[2];
        assert!((share(counts[3]) - want3).abs() < 0.01, "{counts:?} {p:?}");
        assert!((share(counts[1]) - 0.40 * p[0]).abs() < 0.01, "{counts:?}");
        let bad = MatchmakingConfig {
            members_share: 0.7,
            ..MatchmakingConfig::default()
        };
        assert!(bad.validate().unwrap_err().to_string().contains("exceed 1"));
    }

    #[test]
    fn slots_keep_the_marginal_and_bound_the_opponents_in_play() {
        let pool = [cand(1, 1.0, 4.0), cand(2, 3.0, 4.0), cand(3, 0.0, 0.0)];
        let cfg = MatchmakingConfig {
            slots: 3,
            ..MatchmakingConfig::default()
        };
        let p = pfsp_probabilities(&pool, &cfg);
        let (windows, worlds) = (8_000u64, 8usize);
        let mut counts = [0usize; 4];
        for window in 0..windows {
            let slots: Vec<Opponent> = (0..cfg.slots)
                .map(|s| {
                    choose_opponent(
                        &pool,
                        fixed(Some(99), &[]),
                        &cfg,
                        slot_seed(9, 2, s, window),
                    )
                    .unwrap()
                })
                .collect();
            let mut in_play = std::collections::HashSet::new();
            for world in 0..worlds {
                let o = slots[pick_slot(slots.len(), draw_seed(9, 2, world, window))];
                in_play.insert(o);
                counts[match o {
                    Opponent::Main => 0,
                    Opponent::Member(id) => id as usize,
                }] += 1;
            }
            assert!(in_play.len() <= cfg.slots, "window {window}: {in_play:?}");
        }
        // Slots are independent draws and worlds pick one uniformly, so each
        // episode's opponent still follows the PFSP mixture (draws within a
        // window are correlated, hence the looser tolerance).
        let share = |c: usize| c as f64 / (windows as usize * worlds) as f64;
        assert!(
            (share(counts[0]) - cfg.main_share).abs() < 0.02,
            "{counts:?}"
        );
        for i in 0..3 {
            let want = (1.0 - cfg.main_share) * p[i];
            assert!(
                (share(counts[i + 1]) - want).abs() < 0.02,
                "{counts:?} vs {p:?}"
            );
        }
        let picks: std::collections::HashSet<usize> = (0..200)
            .map(|e| pick_slot(3, draw_seed(1, 1, 0, e)))
            .collect();
        assert_eq!(picks.len(), 3, "every slot gets picked");
    }

    #[test]
    fn the_target_exploiter_gets_its_share_after_main_and_extras_and_zero_changes_no_draw() {
        // Member 4 is the target exploiter's newest snapshot, member 3 an
        // extra heuristic: [0, 0.35) main, [0.35, 0.45) the extra,
        // [0.45, 0.75) the exploiter, [0.75, 1) PFSP over all four.
        let pool = [
            cand(1, 1.0, 4.0),
            cand(2, 3.0, 4.0),
            cand(3, 4.0, 4.0),
            cand(4, 3.0, 4.0),
        ];
        let cfg = MatchmakingConfig {
            members_share: 0.1,
            target_exploiter_share: 0.3,
            ..MatchmakingConfig::default()
        };
        let with_line = Fixed {
            main: Some(99),
            extras: &[3],
            target_exploiter: Some(4),
        };
        let p = pfsp_probabilities(&pool, &cfg);
        let n = 40_000;
        let mut counts = [0usize; 5];
        for episode in 0..n {
            let seed = draw_seed(9, 2, 3, episode);
            counts[match choose_opponent(&pool, with_line, &cfg, seed).unwrap() {
                Opponent::Main => 0,
                Opponent::Member(id) => id as usize,
            }] += 1;
            // Without a share, the exploiter changes nothing; without a
            // snapshot yet, its share goes to PFSP and main keeps its own.
            let plain = MatchmakingConfig {
                members_share: 0.1,
                ..MatchmakingConfig::default()
            };
            assert_eq!(
                choose_opponent(&pool, with_line, &plain, seed),
                choose_opponent(&pool, fixed(Some(99), &[3]), &plain, seed)
            );
            let no_snapshot = choose_opponent(&pool, fixed(Some(99), &[3]), &cfg, seed);
            if no_snapshot == Some(Opponent::Main) {
                assert_eq!(choose_opponent(&pool, with_line, &cfg, seed), no_snapshot);
            }
        }
        let share = |c: usize| c as f64 / n as f64;
        assert!((share(counts[0]) - 0.35).abs() < 0.01, "{counts:?}");
        assert!((share(counts[1]) - 0.25 * p[0]).abs() < 0.01, "{counts:?}");
        assert!(
            (share(counts[3]) - (0.1 + 0.25 * p[2])).abs() < 0.01,
            "{counts:?}"
        );
        // The learner wins 3 of 4 against the exploiter: PFSP adds little.
        let want4 = 0.3 + 0.25 * p[3];
        assert!((share(counts[4]) - want4).abs() < 0.01, "{counts:?} {p:?}");
        let bad = MatchmakingConfig {
            members_share: 0.3,
            target_exploiter_share: 0.4,
            ..MatchmakingConfig::default()
        };
        let err = bad.validate().unwrap_err().to_string();
        assert!(err.starts_with("target_exploiter_share = 0.4"), "{err}");
        assert!(err.contains("exceed 1"), "{err}");
    }
}
