//! What one iteration reports: the row of `metrics.csv`, added up from a
//! rollout's finished episodes and clocks and each side's update.

use super::super::kind::kind;
use super::super::rollout::UpdateStats;
use super::super::teacher::TeacherAgreement;
use serde::{Deserialize, Serialize};
use t2e_core::algorithm::Algorithm;
use t2e_core::env::Side;

/// What a rollout's finished episodes and its clocks add up to.
#[derive(Default)]
pub(super) struct RolloutTally {
    pub(super) episodes: usize,
    pub(super) captures: usize,
    pub(super) len_sum: f64,
    pub(super) captor_return: f64,
    pub(super) target_return: f64,
    pub(super) time_env: f64,
    pub(super) time_inference: f64,
}

impl RolloutTally {
    /// The episode means and the rollout's clocks as a metrics row; the
    /// caller fills in the counters and the update's part.
    pub(super) fn metrics(&self, time_bootstrap: f64) -> Metrics {
        let per = |x: f64| {
            if self.episodes > 0 {
                x / self.episodes as f64
            } else {
                f64::NAN
            }
        };
        Metrics {
            episodes: self.episodes,
            capture_rate: per(self.captures as f64),
            episode_len: per(self.len_sum),
            captor_return: per(self.captor_return),
            target_return: per(self.target_return),
            time_env: self.time_env,
            time_inference: self.time_inference + time_bootstrap,
            ..Metrics::default()
        }
    }
}

/// One side's part of an update, for the metrics.
pub(super) struct SideUpdate {
    pub(super) side: Side,
    pub(super) algorithm: Algorithm,
    pub(super) learning_rate: Option<f64>,
    /// None when the learner took no gradient step.
    pub(super) stats: Option<UpdateStats>,
}

impl SideUpdate {
    pub(super) fn record(self, m: &mut Metrics) {
        match self.side {
            Side::Captors => m.captor_lr = self.learning_rate,
            Side::Target => m.target_lr = self.learning_rate,
        }
        let Some(u) = self.stats else {
            return;
        };
        if self.side == Side::Target {
            m.teacher = u.teacher;
            m.fitted = u.fitted;
        }
        let fields = match self.side {
            Side::Captors => [
                &mut m.captor_policy_loss,
                &mut m.captor_value_loss,
                &mut m.captor_entropy,
                &mut m.captor_approx_kl,
                &mut m.captor_clip_frac,
            ],
            Side::Target => [
                &mut m.target_policy_loss,
                &mut m.target_value_loss,
                &mut m.target_entropy,
                &mut m.target_approx_kl,
                &mut m.target_clip_frac,
            ],
        };
        // KL and clipping are PPO's; an off-policy learner leaves them empty.
        let ppo_only = |x: f64| (!kind(self.algorithm).off_policy()).then_some(x);
        for (f, v) in fields.into_iter().zip([
            Some(u.policy_loss),
            Some(u.value_loss),
            Some(u.entropy),
            ppo_only(u.approx_kl),
            ppo_only(u.clip_frac),
        ]) {
            *f = v;
        }
    }
}

/// One row of `metrics.csv`.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Metrics {
    pub iteration: u64,
    pub env_steps: u64,
    pub wall_s: f64,
    /// Environment steps per second of this iteration (rollout + update).
    pub steps_per_s: f64,
    pub episodes: usize,
    /// Share of the episodes that ended this iteration with a capture.
    pub capture_rate: f64,
    pub episode_len: f64,
    /// Mean undiscounted episode return per robot of each side.
    pub captor_return: f64,
    pub target_return: f64,
    /// Seconds of this iteration stepping worlds, running networks for
    /// actions and values, and updating.
    pub time_env: f64,
    pub time_inference: f64,
    pub time_update: f64,
    pub captor_policy_loss: Option<f64>,
    pub captor_value_loss: Option<f64>,
    pub captor_entropy: Option<f64>,
    pub captor_approx_kl: Option<f64>,
    pub captor_clip_frac: Option<f64>,
    pub target_policy_loss: Option<f64>,
    pub target_value_loss: Option<f64>,
    pub target_entropy: Option<f64>,
    pub target_approx_kl: Option<f64>,
    pub target_clip_frac: Option<f64>,
    /// The learners' actor learning rate this iteration (PPO's; it moves
    /// under `lr_anneal`).
    pub captor_lr: Option<f64>,
    pub target_lr: Option<f64>,
    /// A target with a teacher: its agreement with the teacher, written to
    /// `teacher.csv` rather than here, so that runs without one keep the
    /// columns they always had.
    #[serde(skip)]
    pub teacher: Option<TeacherAgreement>,
    /// A DAgger target: its agreement with the teacher on the states it
    /// was fitted on, written to `dagger.csv`.
    #[serde(skip)]
    pub fitted: Option<TeacherAgreement>,
}

/// One row of `teacher.csv` (or of `dagger.csv`): an iteration's
/// `TeacherAgreement`, with the share of the teacher's departures that the
/// policy follows.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TeacherRow {
    pub iteration: u64,
    pub env_steps: u64,
    pub decisions: u64,
    pub teacher_departures: u64,
    pub followed: u64,
    pub strayed: u64,
    pub followed_share: f64,
}

impl TeacherRow {
    /// On the new rollout, before the update (`teacher.csv`).
    pub fn of(m: &Metrics) -> Option<TeacherRow> {
        m.teacher.map(|a| TeacherRow::with(m, a))
    }

    /// On the states a DAgger target was fitted on (`dagger.csv`).
    pub fn of_fitted(m: &Metrics) -> Option<TeacherRow> {
        m.fitted.map(|a| TeacherRow::with(m, a))
    }

    fn with(m: &Metrics, a: TeacherAgreement) -> TeacherRow {
        TeacherRow {
            iteration: m.iteration,
            env_steps: m.env_steps,
            decisions: a.decisions,
            teacher_departures: a.teacher_departures,
            followed: a.followed,
            strayed: a.strayed,
            followed_share: a.followed_share(),
        }
    }
}
