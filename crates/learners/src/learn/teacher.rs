//! `ppo.teacher`: the target a learned target's KL pulls towards when it is
//! not the rule-based one, such as the robust lookahead target. One
//! controller per world labels every state of the learner's own play with
//! the teacher's move (`Rollout::teacher_hints`); the PPO update's KL reads
//! those labels in place of the rule-based target's. The learner's states,
//! the teacher's actions: DAgger's data, collected on policy.

use crate::controllers::ControllerSpec;
use rayon::prelude::*;
use t2e_core::env::controller::Controller;
use t2e_core::env::vec_env::VecEnv;
use t2e_core::env::{Action, Side, TrapEnv};
use t2e_core::error::ConfigError;

/// Checks a side's `ppo.teacher` and returns it parsed: a target
/// controller that a target trained by MAPPO or IPPO distils. Not a
/// checkpoint: a learned teacher is a policy the learner could start from
/// instead, and its forward per world and step would be the run's cost.
pub fn check(teacher: &str, side: Side, ppo: bool) -> Result<ControllerSpec, ConfigError> {
    let bad = |rule: String| ConfigError::new("teacher", format!("\"{teacher}\""), rule);
    if side == Side::Captors {
        return Err(bad(
            "only the target has one (a target its KL pulls towards); set it under [target.ppo]"
                .into(),
        ));
    }
    if !ppo {
        return Err(bad(
            "only MAPPO and IPPO read it; drop it or play mappo / ippo".into(),
        ));
    }
    let spec: ControllerSpec = teacher.parse().map_err(|e| bad(format!("{e}")))?;
    if matches!(spec, ControllerSpec::Checkpoint(_)) {
        return Err(bad(
            "a teacher is a scripted target (robust:H:MODELS, lookahead:H, tuned:..., heuristic), not a checkpoint".into(),
        ));
    }
    spec.build(Side::Target).map_err(|e| bad(format!("{e}")))?;
    Ok(spec)
}

/// Checks a side's `net.prior_teacher` (its prior and side are
/// `prior::check`'s): a scripted target, and not beside `ppo.teacher`,
/// since the KL's rule-based anchor and the agreement counts read the
/// prior's moves as the rule's.
pub fn check_prior(planner: &str, kl_teacher: Option<&str>) -> Result<ControllerSpec, ConfigError> {
    let bad = |rule: String| ConfigError::new("prior_teacher", format!("\"{planner}\""), rule);
    if let Some(kl_teacher) = kl_teacher {
        return Err(bad(format!(
            "and ppo.teacher = \"{kl_teacher}\" are both set: with a planner as the prior, ppo.heuristic_kl already pulls towards the planner's moves; drop one"
        )));
    }
    crate::controllers::prior_teacher(planner).map_err(|e| bad(e.to_string()))
}

/// The teacher of one world: its controller and the episode it was last
/// reset for.
pub struct Teacher {
    controller: Box<dyn Controller>,
    episode: Option<u64>,
}

impl Teacher {
    /// One teacher per world, each its own controller (a controller keeps
    /// per-episode state, such as a randomised model's constants).
    pub fn per_world(spec: &ControllerSpec, worlds: usize) -> Result<Vec<Teacher>, ConfigError> {
        (0..worlds)
            .map(|_| {
                spec.build(Side::Target)
                    .map(|controller| Teacher {
                        controller,
                        episode: None,
                    })
                    .map_err(|e| ConfigError::new("teacher", format!("\"{spec}\""), e.to_string()))
            })
            .collect()
    }

    /// The teacher's move in `env`, the world's `episode`-th episode; reset
    /// first when the world started a new episode (or the run resumed).
    pub fn label(&mut self, env: &TrapEnv, episode: u64) -> Action {
        if self.episode != Some(episode) {
            self.controller.reset(env, env.seed);
            self.episode = Some(episode);
        }
        let mut out = [Action::Stop];
        self.controller.act(env, Side::Target, &mut out);
        out[0]
    }
}

/// Every world's teacher move (the target: one robot per world) as action
/// indices into `out`, the worlds in parallel.
pub fn label_worlds(teachers: &mut [Teacher], venv: &VecEnv, out: &mut [i64]) {
    // The worlds apart from the vector env, whose scripted controllers are
    // not shared between threads.
    let worlds: Vec<(&TrapEnv, u64)> = (0..teachers.len())
        .map(|e| (venv.env(e), venv.episode_index(e)))
        .collect();
    teachers
        .par_iter_mut()
        .zip(out.par_iter_mut())
        .zip(worlds.par_iter())
        .for_each(|((teacher, label), &(env, episode))| {
            *label = teacher.label(env, episode).index() as i64;
        });
}

/// How close the policy came to its teacher on one rollout, counted over
/// every target decision before the update: where the teacher departs
/// from the rule-based target, and whether the policy's greedy move
/// follows it there and keeps the rule elsewhere. A row of the run's
/// `teacher.csv`.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TeacherAgreement {
    /// Decisions counted.
    pub decisions: u64,
    /// Of those, the teacher's departures: its move is not the rule's.
    pub teacher_departures: u64,
    /// Departures where the policy's greedy move is the teacher's.
    pub followed: u64,
    /// Other decisions where the policy's greedy move is not the rule's
    /// (a departure the teacher did not make).
    pub strayed: u64,
}

impl TeacherAgreement {
    /// Counts one batch: the policy's greedy moves, the teacher's and the
    /// rule-based target's, as action indices of the same decisions.
    pub fn count(greedy: &[i64], teacher: &[i64], rule: &[i64]) -> TeacherAgreement {
        let mut a = TeacherAgreement::default();
        for ((&g, &t), &r) in greedy.iter().zip(teacher).zip(rule) {
            a.decisions += 1;
            if t != r {
                a.teacher_departures += 1;
                a.followed += u64::from(g == t);
            } else {
                a.strayed += u64::from(g != r);
            }
        }
        a
    }

    pub fn add(&mut self, other: TeacherAgreement) {
        self.decisions += other.decisions;
        self.teacher_departures += other.teacher_departures;
        self.followed += other.followed;
        self.strayed += other.strayed;
    }

    /// The share of the teacher's departures the policy follows (NaN with
    /// none).
    pub fn followed_share(&self) -> f64 {
        self.followed as f64 / self.teacher_departures as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_teacher_is_a_scripted_target_of_a_ppo_target() {
        assert!(check("robust:10:heuristic+expert:1", Side::Target, true).is_ok());
        assert!(check("still", Side::Target, true).is_ok());
        let err = |t: &str, side: Side, ppo: bool| check(t, side, ppo).unwrap_err().to_string();
        assert!(err("still", Side::Captors, true).contains("[target.ppo]"));
        assert!(err("still", Side::Target, false).contains("MAPPO and IPPO"));
        assert!(err("ckpt:runs/x", Side::Target, true).contains("not a checkpoint"));
        assert!(err("expert:3", Side::Target, true)
            .starts_with("teacher = \"expert:3\": expert:3 is a captor team"));
        assert!(err("robots", Side::Target, true).contains("unknown controller"));
    }

    #[test]
    fn agreement_counts_departures_followed_and_strays() {
        // Decisions: the teacher departs in 0, 1 and 2; the policy follows
        // it in 0 and 2 (in 1 it keeps the rule), and strays in 4.
        let greedy = [3, 2, 4, 1, 0];
        let teacher = [3, 1, 4, 1, 2];
        let rule = [2, 2, 0, 1, 2];
        let a = TeacherAgreement::count(&greedy, &teacher, &rule);
        assert_eq!(
            a,
            TeacherAgreement {
                decisions: 5,
                teacher_departures: 3,
                followed: 2,
                strayed: 1
            }
        );
        assert!((a.followed_share() - 2.0 / 3.0).abs() < 1e-12);
        let mut twice = a;
        twice.add(a);
        assert_eq!((twice.decisions, twice.followed, twice.strayed), (10, 4, 2));
    }
}
