//! The schema of a training run (`configs/*.toml`): who plays each side,
//! every learner's hyperparameters, the worlds and the budget, checked
//! field by field with errors that name the file and the field.

use super::extra_maps::ExtraMapsConfig;
use super::kind::{kind, learner_names};
use super::map_sampling::MapSampling;
use super::side_config::is_default;
pub use super::side_config::{Play, SideConfig, SideDefaults, TrainDefaults};
use serde::{Deserialize, Serialize};
use std::path::Path;
use t2e_core::algorithm::Algorithm;
use t2e_core::env::{EnvConfig, Side};
use t2e_core::error::{in_range, ConfigError, ConfigFileError, ConfigLoadError};
use t2e_core::protocol::{read_config, Protocol};
use tch::Device;

/// A training run, as written in `configs/*.toml`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrainConfig {
    /// Run name: the run folder is `runs/NAME` unless `--out` says otherwise.
    pub name: String,
    pub seed: u64,
    /// Stop after this many environment steps (all worlds together; paper: 30 M).
    pub total_env_steps: u64,
    /// Worlds stepped in parallel (paper: 16 to 32).
    pub num_envs: usize,
    /// Steps per world between updates; a multiple of each learner's chunk_len.
    pub rollout_steps: usize,
    /// Write checkpoints every this many iterations (and at the end).
    pub checkpoint_every: u64,
    /// "auto" (CUDA when tch sees a GPU), "cpu" or "cuda".
    pub device: DeviceChoice,
    /// "held-out" (train on generated maps, test on the unseen Gibson maps)
    /// or "paper" (train on the 26 Gibson maps, as the paper did). A config
    /// file must name it; the training maps must fit it (checked by content).
    pub protocol: Protocol,
    /// Training maps. Held-out: never the Gibson test set; `generated:N`
    /// makes N maps per size class with the project's generator; also
    /// `shipped` or a folder. Paper: `gibson`.
    pub maps: String,
    /// Training-only extra maps beside `maps` (off by default; left out of
    /// the stored config, and so of the config hash, while off).
    #[serde(skip_serializing_if = "is_default")]
    pub extra_maps: ExtraMapsConfig,
    /// "uniform" (every map equally often, the paper's) or
    /// "class-balanced" (every size class equally often); a training
    /// option, left out of the stored config while uniform.
    #[serde(skip_serializing_if = "is_default")]
    pub map_sampling: MapSampling,
    pub env: EnvConfig,
    pub captors: SideConfig,
    pub target: SideConfig,
}

impl Default for TrainConfig {
    fn default() -> Self {
        TrainConfig {
            name: "train".into(),
            seed: 0,
            total_env_steps: 30_000_000,
            num_envs: 32,
            rollout_steps: 100,
            checkpoint_every: 25,
            device: DeviceChoice::Auto,
            protocol: Protocol::HeldOut,
            maps: "generated:20".into(),
            extra_maps: ExtraMapsConfig::default(),
            map_sampling: MapSampling::Uniform,
            env: EnvConfig::default(),
            captors: SideConfig {
                play: Play::Learn(Algorithm::Mappo),
                ..SideConfig::default()
            },
            target: SideConfig::default(),
        }
    }
}

impl SideConfig {
    /// The recurrent chunk length `algorithm` trains on.
    pub fn chunk_len(&self, algorithm: Algorithm) -> usize {
        kind(algorithm).chunk_len(self)
    }

    /// The discount `algorithm` learns with (the shaping term uses it too).
    pub fn gamma(&self, algorithm: Algorithm) -> f64 {
        kind(algorithm).gamma(self)
    }

    /// Checks the settings of `algorithm`; the error names the field.
    fn validate_learner(&self, algorithm: Algorithm) -> Result<(), ConfigError> {
        self.net.validate().map_err(|e| e.within("net"))?;
        self.shaping.validate().map_err(|e| e.within("shaping"))?;
        let k = kind(algorithm);
        k.validate(self).map_err(|e| e.within(k.settings_table()))
    }
}

/// Worlds and steps per world of one rollout: each in range, and the
/// rollout small enough to hold (checked before anything divides by them).
pub fn check_rollout(num_envs: usize, rollout_steps: usize) -> Result<(), ConfigError> {
    in_range(
        "num_envs",
        num_envs,
        1..=4096,
        "must be in 1..=4096 (the paper uses 16 to 32)",
    )?;
    in_range(
        "rollout_steps",
        rollout_steps,
        1..=100_000,
        "must be in 1..=100000",
    )?;
    in_range(
        "num_envs x rollout_steps",
        num_envs * rollout_steps,
        1..=4_000_000,
        "a rollout of more than 4,000,000 steps does not fit in memory",
    )
}

impl TrainConfig {
    /// Reads a TOML config; errors name the file and the field.
    /// A config file as a user wrote it: it must name its protocol.
    pub fn load(path: &Path) -> Result<TrainConfig, ConfigLoadError> {
        read_config(path, true, Self::parse)
    }

    /// A run folder's own `config.toml`, written by this program. One written
    /// before configs named their protocol reads as held-out: the Gibson maps
    /// were refused for training then.
    pub fn load_stored(path: &Path) -> Result<TrainConfig, ConfigLoadError> {
        read_config(path, false, Self::parse)
    }

    /// A config's text, checked whole.
    pub fn parse(text: &str) -> Result<TrainConfig, ConfigFileError> {
        let cfg: TrainConfig = t2e_core::util::from_toml(text)?;
        cfg.validate()?;
        Ok(cfg)
    }

    /// Checks every setting; the error names the field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let mut env = self.env.clone();
        env.observations = true;
        env.validate().map_err(|e| e.within("env"))?;
        validate_name(&self.name)?;
        check_rollout(self.num_envs, self.rollout_steps)?;
        self.extra_maps
            .validate()
            .map_err(|e| e.within("extra_maps"))?;
        let per_iteration = (self.num_envs * self.rollout_steps) as u64;
        if self.total_env_steps < per_iteration {
            return Err(ConfigError::new(
                "total_env_steps",
                self.total_env_steps,
                format!(
                    "less than one iteration ({} worlds x {} steps = {per_iteration}); nothing would be trained",
                    self.num_envs, self.rollout_steps
                ),
            ));
        }
        in_range(
            "checkpoint_every",
            self.checkpoint_every,
            1..=u64::MAX,
            "must be at least 1 iteration",
        )?;
        let mut learners = 0;
        for (name, side_cfg, side) in [
            ("captors", &self.captors, Side::Captors),
            ("target", &self.target, Side::Target),
        ] {
            match &side_cfg.play {
                Play::Learn(algorithm) => {
                    learners += 1;
                    self.validate_learning_side(name, side_cfg, side, *algorithm)?;
                }
                Play::Script(spec) => spec.check(side, &env).map_err(|e| {
                    ConfigError::new(format!("{name}.play"), format!("\"{spec}\""), e.to_string())
                })?,
            }
        }
        if let (Play::Learn(_), Play::Learn(_)) = (&self.captors.play, &self.target.play) {
            t2e_core::env::Sight::check_shared(
                self.captors.net.sight,
                self.target.net.sight,
                "two learners in one run read one env's observations",
            )?;
        }
        if learners == 0 {
            return Err(ConfigError::about(
                "captors.play, target.play",
                format!(
                    "neither is a learner ({}): nothing to train",
                    learner_names("or")
                ),
            ));
        }
        Ok(())
    }

    /// The checks on one learning side that depend on the run as well (its
    /// rollout, episode length); apart from `validate` so that one reads as
    /// the list of what a run must satisfy.
    fn validate_learning_side(
        &self,
        name: &str,
        side_cfg: &SideConfig,
        side: Side,
        algorithm: Algorithm,
    ) -> Result<(), ConfigError> {
        side_cfg
            .validate_learner(algorithm)
            .map_err(|e| e.within(name))?;
        let k = kind(algorithm);
        crate::nn::prior::check(side_cfg.net.heuristic_prior, side, !k.off_policy())
            .map_err(|e| e.within("net").within(name))?;
        crate::nn::prior::check_kl(side_cfg.ppo.heuristic_kl, side, !k.off_policy())
            .map_err(|e| e.within("ppo").within(name))?;
        if let Some(teacher) = &side_cfg.ppo.teacher {
            super::teacher::check(teacher, side, !k.off_policy())
                .map_err(|e| e.within("ppo").within(name))?;
        }
        if let Some(planner) = &side_cfg.net.prior_teacher {
            super::teacher::check_prior(planner, side_cfg.ppo.teacher.as_deref())
                .map_err(|e| e.within("net").within(name))?;
        }
        let chunk_len = side_cfg.chunk_len(algorithm);
        let field = k.settings_table();
        if !self.rollout_steps.is_multiple_of(chunk_len) {
            return Err(ConfigError::new(
                "rollout_steps",
                self.rollout_steps,
                format!("not a multiple of {name}.{field}.chunk_len = {chunk_len}"),
            ));
        }
        // A replayed sequence holds the state of at most one
        // truncation to bootstrap from.
        if k.off_policy() && self.env.episode_length as usize <= chunk_len {
            return Err(ConfigError::new(
                "env.episode_length",
                self.env.episode_length,
                format!(
                    "must exceed {name}.{field}.chunk_len = {chunk_len} for {}",
                    algorithm.name()
                ),
            ));
        }
        Ok(())
    }

    /// The env its learners train in: `env` with the learners' sight
    /// (`validate` holds the two sides' equal when both learn).
    pub fn learning_env(&self) -> EnvConfig {
        let mut env = self.env.clone();
        env.observations = true;
        env.sight = [&self.captors, &self.target]
            .into_iter()
            .find(|side| matches!(side.play, Play::Learn(_)))
            .map_or(t2e_core::env::Sight::OFF, |side| side.net.sight);
        env
    }

    /// A stable hash of the settings that shape learning (FNV-1a of the
    /// canonical JSON); the name, the step budget and the device are left
    /// out, so a run can be renamed, extended or moved to a GPU and resumed.
    pub fn hash(&self) -> String {
        let mut c = self.clone();
        c.name = String::new();
        c.total_env_steps = 0;
        c.device = DeviceChoice::Auto;
        // Where the device sits, the hashed text has held "" since the
        // field was a string: stored runs and checkpoints record hashes of
        // that text, so it stays (the device never changes what is learnt).
        let json = serde_json::to_string(&c)
            .expect("config serialises")
            .replacen(r#""device":"auto""#, r#""device":"""#, 1);
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in json.bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        format!("{h:016x}")
    }

    pub fn device(&self) -> Device {
        match self.device {
            DeviceChoice::Cpu => Device::Cpu,
            DeviceChoice::Cuda => Device::Cuda(0),
            DeviceChoice::Auto => Device::cuda_if_available(),
        }
    }
}

/// Where a run trains (`device = "auto" | "cpu" | "cuda"`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum DeviceChoice {
    /// CUDA when tch sees a GPU, else the CPU.
    #[default]
    Auto,
    Cpu,
    Cuda,
}

/// A run name becomes the folder `runs/NAME`: it must stay one plain
/// component inside `runs/`.
fn validate_name(name: &str) -> Result<(), ConfigError> {
    let plain = !name.is_empty()
        && name.len() <= 100
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.' | '+'));
    if plain {
        Ok(())
    } else {
        Err(ConfigError::new(
            "name",
            format!("{name:?}"),
            "must be 1 to 100 letters, digits, '-', '_', '+' or '.', not starting with '.' (it names the folder runs/NAME)",
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::controllers::ControllerSpec;

    #[test]
    fn config_errors_name_the_field() {
        let bad: Result<TrainConfig, _> = toml::from_str("[captors.ppo]\nentropy = 0.1\n");
        assert!(
            bad.unwrap_err().to_string().contains("entropy"),
            "unknown key reported"
        );
        let cfg = TrainConfig {
            rollout_steps: 15,
            ..TrainConfig::default()
        };
        assert!(cfg
            .validate()
            .unwrap_err()
            .to_string()
            .contains("chunk_len"));
        let mut cfg = TrainConfig::default();
        cfg.captors.play = Play::Script(ControllerSpec::Heuristic);
        assert!(cfg
            .validate()
            .unwrap_err()
            .to_string()
            .contains("nothing to train"));
        let mut cfg = TrainConfig::default();
        cfg.target.play = "expert:3".parse().unwrap();
        assert_eq!(cfg.validate().unwrap_err().field, "target.play");
        let mut cfg = TrainConfig::default();
        cfg.captors.ppo.gamma = 1.5;
        assert_eq!(cfg.validate().unwrap_err().field, "captors.ppo.gamma");
        // A misspelt `play` is refused as the file is read, by its path.
        let err = t2e_core::util::from_toml::<TrainConfig>("[target]\nplay = \"mapo\"\n")
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("target.play") && err.contains("\"mapo\""),
            "{err}"
        );
        assert_eq!(TrainConfig::default().hash(), TrainConfig::default().hash());
        let other = TrainConfig {
            seed: 1,
            ..TrainConfig::default()
        };
        assert_ne!(other.hash(), TrainConfig::default().hash());
    }

    #[test]
    fn the_hash_ignores_the_device_and_keeps_the_value_stored_runs_recorded() {
        let on = |device: &str| {
            toml::from_str::<TrainConfig>(&format!("device = \"{device}\""))
                .unwrap()
                .hash()
        };
        assert_eq!(on("cpu"), on("cuda"));
        assert_eq!(on("cpu"), on("auto"));
        // The default config's hash as the code before `Device` computed
        // it: checkpoints and run folders record this value, and resume and
        // eval compare against it, so the hashed text must not move.
        assert_eq!(TrainConfig::default().hash(), "048076f336ea4704");
    }
}
