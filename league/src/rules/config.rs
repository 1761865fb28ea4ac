//! A league's configuration (`configs/league-*.toml`): the two main
//! learners, matchmaking, snapshots, the curriculum and the budget. Every
//! field has a documented default; typos and impossible values are errors
//! that name the file and the field.

use crate::rules::curriculum::CurriculumConfig;
use crate::rules::evaluator_config::EvaluatorConfig;
use crate::rules::matchmaking::MatchmakingConfig;
use crate::rules::members::MembersConfig;

use serde::{Deserialize, Serialize};
use std::path::Path;
use t2e_core::env::{EnvConfig, Side};
use t2e_core::error::{in_interval, in_range, ConfigError, ConfigFileError, ConfigLoadError};
use t2e_core::protocol::{read_config, Protocol};
use t2e_learners::controllers::ControllerSpec;
use t2e_learners::learn::ppo::PpoConfig;
use t2e_learners::learn::train::Play;
use t2e_learners::learn::train::{SideConfig, SideDefaults, TrainConfig};
use t2e_learners::learn::Algorithm;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LeagueConfig {
    /// The league's name: its directory is `runs/league/NAME` by default.
    pub name: String,
    /// Seeds every learner's episodes and every opponent draw.
    pub seed: u64,
    /// Each learner stops after this many environment steps of its own.
    pub env_steps_per_learner: u64,
    /// "held-out" or "paper" (`t2e_core::protocol`): a config file must name
    /// it, and the training maps must fit it.
    pub protocol: Protocol,
    /// Training maps: held-out, never the Gibson test set (`generated:N`,
    /// `shipped`, a folder); paper, `gibson`.
    pub maps: String,
    /// K, the number of captors.
    pub num_captors: usize,
    /// Steps before a training episode is cut off (the paper trains at 200).
    pub episode_length: u32,
    /// Threads of each learner process, for libtorch's intra-op pool and
    /// rayon alike; 0 = the machine's cores divided among the learners.
    pub threads_per_learner: usize,
    /// Worlds per learner, steps per world between updates, and how many
    /// iterations between a learner's own checkpoints (its resume point).
    pub num_envs: usize,
    pub rollout_steps: usize,
    pub checkpoint_every: u64,
    /// Snapshots play greedily (most likely action) instead of sampling.
    pub greedy_opponents: bool,
    /// Opponent networks kept loaded per learner.
    pub opponent_cache: usize,
    /// A main learner more than this many env steps ahead of the other main
    /// learner waits for it (0: never), so each side trains against the
    /// other's current strength. Unpaced, the faster side (the one-robot
    /// target runs about 2.5x the captors' env steps/s) spends its budget
    /// against the other's early snapshots.
    pub pace_env_steps: u64,
    pub captors: LearnerConfig,
    pub target: LearnerConfig,
    pub matchmaking: MatchmakingConfig,
    pub snapshots: SnapshotConfig,
    pub exploiters: ExploiterConfig,
    pub curriculum: CurriculumConfig,
    pub evaluator: EvaluatorConfig,
    /// Extra permanent heuristic members (stored only when set).
    #[serde(skip_serializing_if = "MembersConfig::is_empty")]
    pub members: MembersConfig,
}

/// One main learner: the learner-settings struct a training run's sides
/// use, under the league's defaults (MAPPO; PPO in 4 minibatches).
pub type LearnerConfig = SideConfig<LeagueDefaults>;

/// What a league's learner gets where its config leaves a field out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LeagueDefaults;

impl SideDefaults for LeagueDefaults {
    fn play() -> Play {
        Play::Learn(Algorithm::Mappo)
    }
    fn ppo() -> PpoConfig {
        PpoConfig {
            minibatches: 4,
            ..PpoConfig::default()
        }
    }
}

/// When a learner adds a frozen copy of itself to the pool.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SnapshotConfig {
    /// Env steps between checks.
    pub every_env_steps: u64,
    /// Snapshot when the learner won at least this share of its matches
    /// since the last snapshot...
    pub win_rate: f64,
    /// ...or when this many env steps passed since the last one anyway.
    pub timeout_env_steps: u64,
}

impl Default for SnapshotConfig {
    fn default() -> Self {
        SnapshotConfig {
            every_env_steps: 50_000,
            win_rate: 0.55,
            timeout_env_steps: 200_000,
        }
    }
}

/// Main exploiters (AlphaStar): a learner per side that plays only the other
/// side's main learner (its latest snapshot), adds a snapshot of itself to
/// the pool when it beats it often enough or after a timeout, and then
/// starts again from its initial weights. Their snapshots show the main
/// learners their own weaknesses. Off by default: each is one more process
/// on the machine's cores.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExploiterConfig {
    pub captors: bool,
    pub target: bool,
    /// Snapshot (then reset) when the exploiter won at least this share of
    /// its matches against the main learner since its last snapshot, after
    /// at least `snapshots.every_env_steps`...
    pub win_rate: f64,
    /// ...or after this many env steps anyway.
    pub timeout_env_steps: u64,
    /// The target exploiter's `heuristic_prior` (0: none), in place of the
    /// main target's (`[target.net]`): a main target held near the
    /// rule-based one by its prior still wants an exploiter that is free
    /// to find the captors' weaknesses. Left out: the main target's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_prior: Option<f64>,
    /// false: the target exploiter never goes back to its initial weights
    /// and adds a snapshot of itself every `snapshots.every_env_steps`,
    /// winning or not (`win_rate` and `timeout_env_steps` then apply to
    /// the captor exploiter only). It becomes a second target line that
    /// keeps learning against captors-main, as naive co-evolution's target
    /// does, and whose snapshots the main captors draw by PFSP. Left out
    /// (true): it resets after each snapshot, as AlphaStar's exploiters do.
    #[serde(skip_serializing_if = "is_true")]
    pub target_resets: bool,
}

fn is_true(b: &bool) -> bool {
    *b
}

impl Default for ExploiterConfig {
    fn default() -> Self {
        ExploiterConfig {
            captors: false,
            target: false,
            win_rate: 0.7,
            timeout_env_steps: 200_000,
            target_prior: None,
            target_resets: true,
        }
    }
}

impl ExploiterConfig {
    pub fn enabled(&self, side: Side) -> bool {
        match side {
            Side::Captors => self.captors,
            Side::Target => self.target,
        }
    }
}

impl Default for LeagueConfig {
    fn default() -> Self {
        LeagueConfig {
            name: "league".into(),
            seed: 0,
            env_steps_per_learner: 2_000_000,
            protocol: Protocol::HeldOut,
            maps: "generated:20".into(),
            num_captors: 3,
            episode_length: 200,
            threads_per_learner: 0,
            num_envs: 32,
            rollout_steps: 100,
            checkpoint_every: 5,
            greedy_opponents: false,
            opponent_cache: 8,
            pace_env_steps: 20_000,
            captors: LearnerConfig::default(),
            target: LearnerConfig::default(),
            matchmaking: MatchmakingConfig::default(),
            snapshots: SnapshotConfig::default(),
            exploiters: ExploiterConfig::default(),
            curriculum: CurriculumConfig::default(),
            evaluator: EvaluatorConfig::default(),
            members: MembersConfig::default(),
        }
    }
}

impl LeagueConfig {
    /// A config file as a user wrote it: it must name its protocol.
    pub fn load(path: &Path) -> Result<LeagueConfig, ConfigLoadError> {
        read_config(path, true, Self::parse)
    }

    /// A league directory's own `config.toml`, written by this program. One
    /// written before configs named their protocol reads as held-out: the
    /// Gibson maps were refused for training then.
    pub fn load_stored(path: &Path) -> Result<LeagueConfig, ConfigLoadError> {
        read_config(path, false, Self::parse)
    }

    pub fn parse(text: &str) -> Result<LeagueConfig, ConfigFileError> {
        let cfg: LeagueConfig = t2e_core::util::from_toml(text)?;
        cfg.validate()?;
        Ok(cfg)
    }

    pub fn learner(&self, side: Side) -> &LearnerConfig {
        match side {
            Side::Captors => &self.captors,
            Side::Target => &self.target,
        }
    }

    pub fn train_config(&self, side: Side) -> TrainConfig {
        let learner = self.learner(side);
        let learn = learner.clone().with_defaults();
        let other = SideConfig {
            play: Play::Script(ControllerSpec::Still),
            ..SideConfig::default()
        };
        let (captors, target) = match side {
            Side::Captors => (learn, other),
            Side::Target => (other, learn),
        };
        TrainConfig {
            name: format!("{}-main", side.name()),
            seed: self.seed
                ^ match side {
                    Side::Captors => 0xC0,
                    Side::Target => 0x7A,
                },
            total_env_steps: self.env_steps_per_learner,
            num_envs: self.num_envs,
            rollout_steps: self.rollout_steps,
            checkpoint_every: self.checkpoint_every,
            device: t2e_learners::learn::run_config::DeviceChoice::Cpu,
            protocol: self.protocol,
            maps: self.maps.clone(),
            extra_maps: Default::default(),
            map_sampling: Default::default(),
            env: EnvConfig {
                num_captors: self.num_captors,
                target_speed: self.curriculum.stages.first().copied().unwrap_or(1.0),
                episode_length: self.episode_length,
                ..EnvConfig::default()
            },
            captors,
            target,
        }
    }

    /// Validation shares nothing with training: no validation map is a
    /// training map (`maps`) and no validation team is a league member
    /// (`[members]`). The test side (Gibson maps, `greedy:2`) is refused by
    /// `EvaluatorConfig::validate`; the maps' content by the evaluator.
    fn check_validation_apart(&self) -> Result<(), ConfigError> {
        if let Some(spec) = &self.evaluator.validation_maps {
            let shared = spec == &self.maps
                || match (
                    t2e_core::map::catalog::generated_set(spec),
                    t2e_core::map::catalog::generated_set(&self.maps),
                ) {
                    (Some((vs, vc)), Some((ts, tc))) => {
                        vs.start < ts.end && ts.start < vs.end && vc.iter().any(|c| tc.contains(c))
                    }
                    _ => false,
                };
            if shared {
                return Err(ConfigError::new(
                    "evaluator.validation_maps",
                    format!("\"{spec}\""),
                    format!("shares maps with the training maps (maps = \"{}\"); validation plays maps the league never trained on (generated:N@S with seeds past the training maps', e.g. generated:8@1001)", self.maps),
                ));
            }
        }
        for member_side in [Side::Target, Side::Captors] {
            let validation = self
                .evaluator
                .validation(member_side)
                .map_err(|e| e.within("evaluator"))?;
            let members = self
                .members
                .of(member_side.other())
                .map_err(|e| e.within("members"))?;
            if let Some((name, _)) = validation
                .iter()
                .find(|(_, v)| members.iter().any(|(_, m)| m == v))
            {
                return Err(ConfigError::new(
                    match member_side {
                        Side::Target => "evaluator.validation_captors",
                        Side::Captors => "evaluator.validation_targets",
                    },
                    format!("\"{name}\""),
                    "also a member of the league ([members]), which the league trains against; validation plays teams the league never meets",
                ));
            }
        }
        Ok(())
    }

    // Long on purpose: one check per field, in the order docs/reference/league-config.md lists them, so a reader finds each rule beside its neighbours.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.matchmaking
            .validate()
            .map_err(|e| e.within("matchmaking"))?;
        self.curriculum
            .validate()
            .map_err(|e| e.within("curriculum"))?;
        self.evaluator
            .validate()
            .map_err(|e| e.within("evaluator"))?;
        let held_out = [Side::Target, Side::Captors]
            .into_iter()
            .map(|member_side| {
                let specs = self.evaluator.held_out(member_side)?;
                Ok((member_side.other(), specs))
            })
            .collect::<Result<Vec<_>, ConfigError>>()
            .map_err(|e| e.within("evaluator"))?;
        self.members
            .validate(&held_out)
            .map_err(|e| e.within("members"))?;
        self.check_validation_apart()?;
        t2e_core::env::Sight::check_shared(
            self.captors.net.sight,
            self.target.net.sight,
            "every player of a league meets the others in one env's observations",
        )?;
        if self.matchmaking.members_share > 0.0 && self.members.is_empty() {
            return Err(ConfigError::new(
                "matchmaking.members_share",
                self.matchmaking.members_share,
                "the league has no extra members to give it to (add [members])",
            ));
        }
        in_interval(
            "snapshots.win_rate",
            self.snapshots.win_rate,
            0.0,
            1.0,
            true,
        )?;
        in_interval(
            "exploiters.win_rate",
            self.exploiters.win_rate,
            0.0,
            1.0,
            true,
        )?;
        if let Some(prior) = self.exploiters.target_prior {
            in_interval(
                "exploiters.target_prior",
                prior,
                0.0,
                t2e_learners::nn::prior::MAX_WEIGHT,
                true,
            )?;
            if !self.exploiters.target {
                return Err(ConfigError::new(
                    "exploiters.target_prior",
                    prior,
                    "the league has no target exploiter (exploiters.target = false)",
                ));
            }
        }
        if self.matchmaking.target_exploiter_share > 0.0 && !self.exploiters.target {
            return Err(ConfigError::new(
                "matchmaking.target_exploiter_share",
                self.matchmaking.target_exploiter_share,
                "the league has no target exploiter (exploiters.target = false)",
            ));
        }
        if !self.exploiters.target_resets && !self.exploiters.target {
            return Err(ConfigError::new(
                "exploiters.target_resets",
                false,
                "the league has no target exploiter (exploiters.target = false)",
            ));
        }
        let at_least_one = 1..=u64::MAX;
        in_range(
            "exploiters.timeout_env_steps",
            self.exploiters.timeout_env_steps,
            at_least_one.clone(),
            "must be at least 1",
        )?;
        in_range(
            "snapshots.every_env_steps",
            self.snapshots.every_env_steps,
            at_least_one.clone(),
            "must be at least 1",
        )?;
        in_range(
            "snapshots.timeout_env_steps",
            self.snapshots.timeout_env_steps,
            at_least_one,
            "must be at least 1",
        )?;
        // The worlds and the rollout first: the budget check below divides
        // by them, and must not blame the budget for an impossible rollout.
        t2e_learners::learn::train::check_rollout(self.num_envs, self.rollout_steps)?;
        let per_iteration = (self.num_envs * self.rollout_steps) as u64;
        if self.env_steps_per_learner < per_iteration.max(1) {
            return Err(ConfigError::new(
                "env_steps_per_learner",
                self.env_steps_per_learner,
                format!(
                    "less than one iteration ({} worlds x {} steps)",
                    self.num_envs, self.rollout_steps
                ),
            ));
        }
        in_range(
            "opponent_cache",
            self.opponent_cache,
            1..=usize::MAX,
            "must hold at least one network",
        )?;
        in_range(
            "threads_per_learner",
            self.threads_per_learner,
            0..=256,
            "at most 256",
        )?;
        for side in [Side::Captors, Side::Target] {
            let play = &self.learner(side).play;
            if play.algorithm().is_none() {
                return Err(ConfigError::new(
                    format!("{}.play", side.name()),
                    format!("\"{play}\""),
                    format!(
                        "a league's learner learns: {}",
                        t2e_learners::learn::kind::learner_names("or")
                    ),
                ));
            }
            self.train_config(side).validate()?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rules::players::Seat;

    #[test]
    fn a_league_learner_is_a_training_side_with_the_leagues_defaults() {
        // Left out: MAPPO, PPO in 4 minibatches (a training side: the
        // rule-based robot, 1 minibatch), from one struct.
        let league = LeagueConfig::parse("[captors.net]\nhidden = 32\n").unwrap();
        assert_eq!(league.captors.play, Play::Learn(Algorithm::Mappo));
        assert_eq!(league.captors.ppo.minibatches, 4);
        assert_eq!(league.captors.net.hidden, 32);
        let side: SideConfig = t2e_core::util::from_toml("[net]\nhidden = 32\n").unwrap();
        assert_eq!(side.play, Play::Script(ControllerSpec::Heuristic));
        assert_eq!(side.ppo.minibatches, 1);
        // The league's learner reaches its training run unchanged.
        let train = league.train_config(Side::Captors);
        assert_eq!(train.captors.play, league.captors.play);
        assert_eq!(
            (train.captors.ppo.minibatches, train.captors.net.hidden),
            (4, 32)
        );
        // `algorithm`, the name league configs used, reads as `play`; it is
        // written as `play`.
        let old = LeagueConfig::parse("[target]\nalgorithm = \"ippo\"\n").unwrap();
        assert_eq!(old.target.play, Play::Learn(Algorithm::Ippo));
        let text = toml::to_string_pretty(&old).unwrap();
        assert!(text.contains("play = \"ippo\""), "{text}");
        assert_eq!(LeagueConfig::parse(&text).unwrap(), old);
        // A league's learners learn.
        let err = LeagueConfig::parse("[target]\nplay = \"heuristic\"\n")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("target.play = \"heuristic\""), "{err}");
    }

    #[test]
    fn the_target_exploiter_takes_its_own_prior_and_nothing_else_changes() {
        let text = "[target.net]\nheuristic_prior = 10.0\n[exploiters]\ntarget = true\n";
        let main_only = LeagueConfig::parse(text).unwrap();
        let seat = |side| Seat::exploiter(side);
        let prior = |cfg: &LeagueConfig, s: Seat| {
            crate::rules::roles::SeatRules::of(cfg, s)
                .train_config(cfg)
                .target
                .net
                .heuristic_prior
        };
        // Left out, the exploiter leans on the main target's prior, and the
        // stored config (its hash) is what it was.
        assert_eq!(prior(&main_only, seat(Side::Target)), 10.0);
        assert!(!toml::to_string(&main_only)
            .unwrap()
            .contains("target_prior"));
        let free = LeagueConfig::parse(&format!("{text}target_prior = 0.0\n")).unwrap();
        assert_eq!(prior(&free, seat(Side::Target)), 0.0);
        assert_eq!(prior(&free, Seat::main(Side::Target)), 10.0);
        assert_eq!(
            crate::rules::roles::SeatRules::of(&free, seat(Side::Captors)).train_config(&free),
            crate::rules::roles::SeatRules::of(&main_only, seat(Side::Captors))
                .train_config(&main_only)
        );
        // Out of range, or with no target exploiter to take it: refused, named.
        for (bad, why) in [
            (format!("{text}target_prior = -1.0\n"), "must be"),
            (format!("{text}target_prior = inf\n"), "must be"),
            (format!("{text}target_prior = 21.0\n"), "must be"),
            (
                "[exploiters]\ntarget_prior = 0.0\n".to_string(),
                "no target exploiter",
            ),
        ] {
            let err = LeagueConfig::parse(&bad).unwrap_err().to_string();
            assert!(
                err.starts_with("exploiters.target_prior") && err.contains(why),
                "{err}"
            );
        }
    }

    #[test]
    fn configs_validate_and_typos_name_the_field() {
        LeagueConfig::default().validate().unwrap();
        let err = LeagueConfig::parse("[matchmaking]\nweighting = \"hard\"\npp = 2\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("pp"), "{err}");
        let err = LeagueConfig::parse("[curriculum]\nstages = [1.2, 1.0]\n")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("curriculum.stages[1]"), "{err}");
        let err = LeagueConfig::parse("[target.ppo]\nentropy_coef = nan\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("target.ppo.entropy_coef"), "{err}");
        let err = LeagueConfig::parse("[target]\nalgorithm = \"mapo\"\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("target.algorithm") && err.contains("mappo / ippo / maddpg / maac"),
            "{err}"
        );
        let err = LeagueConfig::parse("env_steps_per_learner = 0\n")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("env_steps_per_learner = 0"), "{err}");
        // An impossible rollout is named as such, not blamed on the budget.
        let err = LeagueConfig::parse("num_envs = 100000\n")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("num_envs = 100000"), "{err}");
        let err = LeagueConfig::parse("rollout_steps = 0\n")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("rollout_steps = 0"), "{err}");
        let err = LeagueConfig::parse("[evaluator]\nepisodes = 0\n")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("evaluator.episodes = 0"), "{err}");
        LeagueConfig::parse("[evaluator]\nenabled = false\nepisodes = 0\n").unwrap();
        // Held-out opponents: controllers of the right side, never a member.
        let cfg = LeagueConfig::parse(
            "[evaluator]\nheld_out_captors = [\"greedy:2\", \"random\"]\nheld_out_targets = [\"still\"]\n",
        )
        .unwrap();
        let names = |side| -> Vec<String> {
            cfg.evaluator
                .held_out(side)
                .unwrap()
                .into_iter()
                .map(|(n, _)| n)
                .collect()
        };
        assert_eq!(names(Side::Target), ["greedy:2", "random"]);
        assert_eq!(names(Side::Captors), ["still"]);
        for (text, says) in [
            (
                "held_out_captors = [\"greedy:x\"]",
                "evaluator.held_out_captors = \"greedy:x\"",
            ),
            (
                "held_out_captors = [\"heuristic\"]",
                "permanent league member",
            ),
            ("held_out_targets = [\"rule\"]", "permanent league member"),
            (
                "held_out_targets = [\"greedy:9\"]",
                "evaluator.held_out_targets = \"greedy:9\"",
            ),
            ("held_out_captors = [\"random\", \"random\"]", "named twice"),
            ("held_out_captors = [\"ckpt:\"]", "needs a path"),
        ] {
            let err = LeagueConfig::parse(&format!("[evaluator]\n{text}\n"))
                .unwrap_err()
                .to_string();
            assert!(err.contains(says), "{text}: {err}");
        }
        // Left out of the stored config while empty: leagues stored before
        // the field existed compare equal to their config.toml.
        let stored = toml::to_string(&LeagueConfig::default()).unwrap();
        assert!(!stored.contains("held_out"), "{stored}");
        assert!(!stored.contains("members"), "{stored}");
        // Extra members: named by their field, never also held out.
        let err = LeagueConfig::parse("[members]\ncaptors = [\"greedy:99\"]\n")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("members.captors = \"greedy:99\""), "{err}");
        let err = LeagueConfig::parse(
            "[members]\ncaptors = [\"greedy:2\"]\n[evaluator]\nheld_out_captors = [\"greedy:2\"]\n",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.starts_with("members.captors = \"greedy:2\": also a held-out"),
            "{err}"
        );
        let err = LeagueConfig::parse("[members]\ncaptor = [\"greedy:4\"]\n")
            .unwrap_err()
            .to_string();
        assert!(err.contains("captor"), "{err}");
        let err = LeagueConfig::parse("[matchmaking]\ntarget_exploiter_share = 0.3\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("matchmaking.target_exploiter_share = 0.3"),
            "{err}"
        );
        assert!(err.contains("no target exploiter"), "{err}");
        let err = LeagueConfig::parse("[matchmaking]\nmembers_share = 0.2\n")
            .unwrap_err()
            .to_string();
        assert!(err.starts_with("matchmaking.members_share = 0.2"), "{err}");
        let cfg = LeagueConfig::parse("[members]\ncaptors = [\"greedy:4\"]\n").unwrap();
        assert!(toml::to_string(&cfg)
            .unwrap()
            .contains("captors = [\"greedy:4\"]"));
        let shipped = Path::new(t2e_core::PROJECT_ROOT).join("configs/league-default.toml");
        LeagueConfig::load(&shipped).unwrap();
    }

    #[test]
    fn a_teacher_reaches_the_target_learner_and_is_checked() {
        let cfg = LeagueConfig::parse(
            "[target.ppo]\nheuristic_kl = 2.0\nteacher = \"robust:10:heuristic+expert:1\"\n",
        )
        .unwrap();
        assert_eq!(
            cfg.train_config(Side::Target).target.ppo.teacher.as_deref(),
            Some("robust:10:heuristic+expert:1")
        );
        for (text, says) in [
            (
                "heuristic_kl = 2.0\nteacher = \"ckpt:x\"",
                "not a checkpoint",
            ),
            ("teacher = \"still\"", "set heuristic_kl too"),
        ] {
            let err = LeagueConfig::parse(&format!("[target.ppo]\n{text}\n"))
                .unwrap_err()
                .to_string();
            assert!(
                err.starts_with("target.ppo.teacher") && err.contains(says),
                "{text}: {err}"
            );
        }
    }

    #[test]
    fn validation_shares_no_team_and_no_map_with_training_or_test() {
        let ok = "maps = \"generated:20\"\n[evaluator]\nvalidation_maps = \"generated:4@1001\"\nvalidation_captors = [\"expert:1\", \"expert:2\", \"greedy:4\"]\n";
        let cfg = LeagueConfig::parse(ok).unwrap();
        assert_eq!(cfg.evaluator.validation(Side::Target).unwrap().len(), 3);
        for (text, says) in [
            // A member of the league is not a team it never met.
            (
                "validation_maps = \"generated:4@1001\"\nvalidation_captors = [\"heuristic\"]",
                "evaluator.validation_captors = \"heuristic\": the expert heuristic is a member",
            ),
            (
                "validation_maps = \"generated:4@1001\"\nvalidation_targets = [\"rule\"]",
                "evaluator.validation_targets = \"rule\": the rule-based target is a member",
            ),
            // The test's own planner (a relative, greedy:4, is accepted above).
            (
                "validation_maps = \"generated:4@1001\"\nvalidation_captors = [\"greedy:2\"]",
                "evaluator.validation_captors = \"greedy:2\": the ASZ-greedy planner on 0.1 m cells is the test panel's team",
            ),
            // Also a held-out opponent.
            (
                "validation_maps = \"generated:4@1001\"\nvalidation_captors = [\"random\"]\nheld_out_captors = [\"random\"]",
                "evaluator.validation_captors = \"random\": also a held-out opponent",
            ),
            // A test map.
            (
                "validation_maps = \"gibson\"\nvalidation_captors = [\"expert:1\"]",
                "evaluator.validation_maps = \"gibson\": the Gibson maps are the test maps",
            ),
            (
                "validation_maps = \"large\"\nvalidation_captors = [\"expert:1\"]",
                "evaluator.validation_maps = \"large\": the Gibson maps are the test maps",
            ),
            // A training map.
            (
                "validation_maps = \"generated:4@18\"\nvalidation_captors = [\"expert:1\"]",
                "evaluator.validation_maps = \"generated:4@18\": shares maps with the training maps",
            ),
            (
                "validation_maps = \"generated:20:small\"\nvalidation_captors = [\"expert:1\"]",
                "evaluator.validation_maps = \"generated:20:small\": shares maps",
            ),
            // Half a panel.
            ("validation_captors = [\"expert:1\"]", "need validation_maps"),
            ("validation_maps = \"generated:4@1001\"", "no validation team"),
            ("validation_maps = \"generated:4@1001\"\nvalidation_targets = [\"expert:3\"]", "captor team"),
        ] {
            let err = LeagueConfig::parse(&format!("maps = \"generated:20\"\n[evaluator]\n{text}\n"))
                .unwrap_err().to_string();
            assert!(err.contains(says), "{text}:\n{err}");
        }
        // A validation team that the config also makes a member.
        let err = LeagueConfig::parse(
            "maps = \"generated:20\"\n[members]\ncaptors = [\"expert:5\"]\n[evaluator]\nvalidation_maps = \"generated:4@1001\"\nvalidation_captors = [\"expert:5\"]\n",
        )
        .unwrap_err().to_string();
        assert!(
            err.starts_with(
                "evaluator.validation_captors = \"expert:5\": also a member of the league"
            ),
            "{err}"
        );
        // Other seeds and other classes of the generator are other maps.
        LeagueConfig::parse("maps = \"generated:20:small\"\n[evaluator]\nvalidation_maps = \"generated:4:large\"\nvalidation_captors = [\"expert:1\"]\n").unwrap();
        LeagueConfig::parse("maps = \"generated:20\"\n[evaluator]\nvalidation_maps = \"generated:4@21\"\nvalidation_captors = [\"expert:1\"]\n").unwrap();
        // Left out of the stored config while unset.
        let stored = toml::to_string(&LeagueConfig::default()).unwrap();
        assert!(!stored.contains("validation"), "{stored}");
    }
}
