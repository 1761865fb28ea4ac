//! The curriculum over the target's speed: stages of speed ratio (1.0, 1.2,
//! 1.4 by default). The league moves to the next stage when the main captors
//! win at least `promote_at` of their last `window` matches at the current
//! stage against the pool's targets; a share of episodes keeps replaying
//! earlier stages so nothing is forgotten.

use serde::{Deserialize, Serialize};
use std::collections::VecDeque;
use t2e_core::env::Side;
use t2e_core::error::{in_interval, in_range, ConfigError};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CurriculumConfig {
    /// Speed ratios v_e / v_p, in order.
    pub stages: Vec<f64>,
    /// Captor win rate over the window that moves the league on.
    pub promote_at: f64,
    /// Matches of the main captors at the current stage that count.
    pub window: usize,
    /// Share of episodes played at an earlier stage (uniformly among them).
    pub replay_share: f64,
    /// The captor learners' own replay share; unset, `replay_share`. The
    /// captors are tested at the first stage's speed while the target is
    /// made hard by the later ones, so a larger share here keeps the
    /// captors practising the speeds they are judged at and leaves the
    /// target's curriculum as it is. Promotion still counts only the main
    /// captors' matches at the current stage.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub captors_replay_share: Option<f64>,
}

impl Default for CurriculumConfig {
    fn default() -> Self {
        CurriculumConfig {
            stages: vec![1.0, 1.2, 1.4],
            promote_at: 0.6,
            window: 400,
            replay_share: 0.2,
            captors_replay_share: None,
        }
    }
}

impl CurriculumConfig {
    /// The replay share of one side's learners.
    pub fn replay_share(&self, side: Side) -> f64 {
        match side {
            Side::Captors => self.captors_replay_share.unwrap_or(self.replay_share),
            Side::Target => self.replay_share,
        }
    }

    pub fn validate(&self) -> Result<(), ConfigError> {
        if self.stages.is_empty() {
            return Err(ConfigError::new(
                "stages",
                "[]",
                "needs at least one speed ratio",
            ));
        }
        for (i, &s) in self.stages.iter().enumerate() {
            let field = format!("stages[{i}]");
            in_interval(&field, s, 0.0, 10.0, false)
                .map_err(|_| ConfigError::new(&field, s, "must be a speed ratio in (0, 10]"))?;
            if i > 0 && s <= self.stages[i - 1] {
                return Err(ConfigError::new(field, s, "stages must increase"));
            }
        }
        in_interval("promote_at", self.promote_at, 0.0, 1.0, false)?;
        in_range(
            "window",
            self.window,
            1..=usize::MAX,
            "must be at least 1 match",
        )?;
        if !(self.replay_share.is_finite() && (0.0..1.0).contains(&self.replay_share)) {
            return Err(ConfigError::new(
                "replay_share",
                self.replay_share,
                "must be in [0, 1)",
            ));
        }
        if let Some(share) = self.captors_replay_share {
            if !(share.is_finite() && (0.0..1.0).contains(&share)) {
                return Err(ConfigError::new(
                    "captors_replay_share",
                    share,
                    "must be in [0, 1) (the main captors must play the current stage for the league to move on)",
                ));
            }
        }
        Ok(())
    }
}

/// Where the curriculum stands: the stage and the window of main-captor
/// results at it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Curriculum {
    pub stage: usize,
    pub recent: VecDeque<bool>,
}

impl Curriculum {
    pub fn new() -> Curriculum {
        Curriculum {
            stage: 0,
            recent: VecDeque::new(),
        }
    }

    /// The current stage's speed ratio.
    pub fn speed(&self, cfg: &CurriculumConfig) -> f64 {
        cfg.stages[self.stage.min(cfg.stages.len() - 1)]
    }

    /// Records one match of the main captors; returns the new stage when it
    /// moves on. Matches at other speeds (replays) do not count.
    pub fn record(
        &mut self,
        cfg: &CurriculumConfig,
        speed: f64,
        captors_won: bool,
    ) -> Option<usize> {
        if speed != self.speed(cfg) {
            return None;
        }
        self.recent.push_back(captors_won);
        while self.recent.len() > cfg.window {
            self.recent.pop_front();
        }
        let wins = self.recent.iter().filter(|&&w| w).count();
        let full = self.recent.len() == cfg.window;
        if full
            && wins as f64 >= cfg.promote_at * cfg.window as f64
            && self.stage + 1 < cfg.stages.len()
        {
            self.stage += 1;
            self.recent.clear();
            return Some(self.stage);
        }
        None
    }

    /// The speed of one episode of `side`'s learner, from a uniform draw `u`
    /// in [0, 1): an earlier stage with that side's replay share (once there
    /// is one).
    pub fn sample_speed(&self, cfg: &CurriculumConfig, side: Side, u: f64) -> f64 {
        let stage = self.stage.min(cfg.stages.len() - 1);
        let share = cfg.replay_share(side);
        if stage > 0 && u < share {
            let earlier = ((u / share) * stage as f64) as usize;
            return cfg.stages[earlier.min(stage - 1)];
        }
        cfg.stages[stage]
    }
}

impl Default for Curriculum {
    fn default() -> Self {
        Curriculum::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_on_at_the_win_rate_over_a_full_window_and_replays_earlier_stages() {
        let cfg = CurriculumConfig {
            window: 4,
            promote_at: 0.75,
            replay_share: 0.2,
            ..Default::default()
        };
        let mut c = Curriculum::new();
        assert_eq!(c.speed(&cfg), 1.0);
        // Three wins are not a full window.
        for _ in 0..3 {
            assert_eq!(c.record(&cfg, 1.0, true), None);
        }
        // A replay at another speed does not count.
        assert_eq!(c.record(&cfg, 1.2, true), None);
        // The fourth match fills the window: 3 of 4 = 0.75 moves on.
        assert_eq!(c.record(&cfg, 1.0, false), Some(1));
        // Below the rate it does not: 2 of 4, then the window slides.
        let mut slow = Curriculum::new();
        for r in [true, false, true, false, false] {
            assert_eq!(slow.record(&cfg, 1.0, r), None);
        }
        assert_eq!(slow.recent.len(), 4, "the window keeps the last 4");
        assert_eq!(c.stage, 1);
        assert_eq!(c.speed(&cfg), 1.2);
        assert!(c.recent.is_empty(), "a new stage starts a new window");
        // Stage 1: u < 0.2 replays stage 0, else plays 1.2.
        assert_eq!(c.sample_speed(&cfg, Side::Target, 0.1), 1.0);
        assert_eq!(c.sample_speed(&cfg, Side::Target, 0.5), 1.2);
        // The last stage stays.
        c.stage = 2;
        assert_eq!(c.record(&cfg, 1.4, true), None);
        for _ in 0..10 {
            c.record(&cfg, 1.4, true);
        }
        assert_eq!(c.stage, 2);
        // Stage 2 replays 1.0 and 1.2 evenly within the replay share.
        assert_eq!(c.sample_speed(&cfg, Side::Target, 0.05), 1.0);
        assert_eq!(c.sample_speed(&cfg, Side::Target, 0.15), 1.2);
    }

    #[test]
    fn bad_settings_name_the_field() {
        let bad = CurriculumConfig {
            stages: vec![1.0, 1.0],
            ..Default::default()
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("stages[1]"));
        let bad = CurriculumConfig {
            promote_at: f64::NAN,
            ..Default::default()
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("promote_at"));
        let bad = CurriculumConfig {
            replay_share: 1.0,
            ..Default::default()
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .starts_with("replay_share"));
        for share in [1.0, -0.1, f64::INFINITY] {
            let bad = CurriculumConfig {
                captors_replay_share: Some(share),
                ..Default::default()
            };
            let err = bad.validate().unwrap_err().to_string();
            assert!(err.starts_with("captors_replay_share"), "{err}");
        }
    }

    #[test]
    fn the_captors_replay_share_is_theirs_alone() {
        let cfg = CurriculumConfig {
            replay_share: 0.2,
            captors_replay_share: Some(0.8),
            ..Default::default()
        };
        let mut c = Curriculum::new();
        // At the first stage there is nothing earlier: both sides play 1.0.
        assert_eq!(c.sample_speed(&cfg, Side::Captors, 0.5), 1.0);
        assert_eq!(c.sample_speed(&cfg, Side::Target, 0.5), 1.0);
        c.stage = 2;
        // u = 0.5: within the captors' 0.8, at 0.5 / 0.8 * 2 = 1.25 -> stage 1;
        // past the target's 0.2 -> the current stage.
        assert_eq!(c.sample_speed(&cfg, Side::Captors, 0.5), 1.2);
        assert_eq!(c.sample_speed(&cfg, Side::Target, 0.5), 1.4);
        // u = 0.3: 0.3 / 0.8 * 2 = 0.75 -> stage 0 for the captors.
        assert_eq!(c.sample_speed(&cfg, Side::Captors, 0.3), 1.0);
        assert_eq!(c.sample_speed(&cfg, Side::Captors, 0.85), 1.4);
        // Unset, the captors use the common share.
        let common = CurriculumConfig {
            captors_replay_share: None,
            ..cfg.clone()
        };
        assert_eq!(c.sample_speed(&common, Side::Captors, 0.5), 1.4);
        // u = 0.05: 0.05 / 0.2 * 2 = 0.5 -> stage 0; u = 0.1 -> 1.0 -> stage 1.
        assert_eq!(c.sample_speed(&common, Side::Captors, 0.05), 1.0);
        assert_eq!(c.sample_speed(&common, Side::Captors, 0.1), 1.2);
    }
}
