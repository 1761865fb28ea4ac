//! Environment settings and robot constants (spec §2, §3).

use crate::error::{in_range, ConfigError};
use serde::{Deserialize, Serialize};

/// The most captors an env takes. Placement puts every captor 1 m to 4 m
/// from every other; past this count that rule fails for a growing share
/// of seeds on the small maps (measured by
/// `the_most_captors_are_placed_on_every_map`), so a larger K is refused
/// where it is set rather than at some episode's reset.
pub const MAX_CAPTORS: usize = 8;

/// Simulation step (s).
pub const DT: f64 = 0.1;
/// Velocity damping per step.
pub const DAMPING: f64 = 0.25;
/// Turn per step (rad).
pub const TURN: f64 = std::f64::consts::PI / 6.0;
/// Robot radius (m), both sides.
pub const RADIUS: f64 = 0.2;
/// Wall repulsion acts on rays shorter than k r = 1.5 r.
pub const REPULSION_RANGE: f64 = 1.5 * RADIUS;
/// Wall-repulsion rays are searched up to 2 r.
pub const REPULSION_RAY_MAX: f64 = 2.0 * RADIUS;
/// Robots are in contact below this centre distance (r_a + r_b).
pub const CONTACT_DIST: f64 = 2.0 * RADIUS;
/// Capture probes sit this far from the target's centre.
pub const PROBE_DIST: f64 = 1.5 * RADIUS;
/// MPE soft contact: force constant and margin.
pub const CONTACT_FORCE: f64 = 100.0;
pub const CONTACT_MARGIN: f64 = 0.001;

/// Mechanical limits of one side's robots.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotSpec {
    pub accel: f64,
    pub max_speed: f64,
    pub mass: f64,
}

/// When an episode counts as a capture.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum CaptureRule {
    /// All 12 probe positions around the target are blocked (the paper's tables).
    Fast,
    /// |ASZ| <= pi (1.5 r / 0.05)^2 cells.
    Strict,
}

/// How the drive command becomes a force.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum DriveForce {
    /// mass * accel^2 * u: what the reference really does; the paper's tables use it.
    Squared,
    /// mass * accel * u: the single factor the paper's text implies.
    Single,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EnvConfig {
    /// K, the number of captors.
    pub num_captors: usize,
    /// v_p (m/s).
    pub captor_speed: f64,
    /// v_e (m/s): 1.0, 1.2 or 1.4 in the paper.
    pub target_speed: f64,
    /// Steps before truncation: 200 in training, 500 in evaluation.
    pub episode_length: u32,
    pub capture_rule: CaptureRule,
    pub drive_force: DriveForce,
    /// Build observations at every step (off for pure evaluation of rule-based robots).
    pub observations: bool,
    /// Inputs beyond the spec's in every robot's vector. Not read from an
    /// env table: it is a learner's choice of inputs (its `net.sight`),
    /// which whoever builds the env copies here, so a config names it once.
    #[serde(skip)]
    pub sight: super::sight::Sight,
}

impl Default for EnvConfig {
    fn default() -> Self {
        EnvConfig {
            num_captors: 3,
            captor_speed: 1.0,
            target_speed: 1.0,
            episode_length: 200,
            capture_rule: CaptureRule::Fast,
            drive_force: DriveForce::Squared,
            observations: true,
            sight: super::sight::Sight::OFF,
        }
    }
}

impl EnvConfig {
    /// Checks the settings; the error names the field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        in_range(
            "num_captors",
            self.num_captors,
            1..=MAX_CAPTORS,
            &format!("must be between 1 and {MAX_CAPTORS}"),
        )?;
        for (name, v) in [
            ("captor_speed", self.captor_speed),
            ("target_speed", self.target_speed),
        ] {
            // Above zero: a robot that cannot move makes no episode.
            if !(v.is_finite() && v > 0.0 && v <= 10.0) {
                return Err(ConfigError::new(name, v, "must be a speed in (0, 10] m/s"));
            }
        }
        self.sight.validate()?;
        if self.episode_length == 0 {
            return Err(ConfigError::new(
                "episode_length",
                0,
                "must be at least 1 step",
            ));
        }
        Ok(())
    }

    pub fn num_agents(&self) -> usize {
        self.num_captors + 1
    }

    /// Length of the agent-related observation vector: 5 + 5 K (spec
    /// §5), then the sight's numbers.
    pub fn vector_len(&self) -> usize {
        self.spec_vector_len() + self.sight.len()
    }

    /// Length of the spec's part of the vector: 5 + 5 K.
    pub fn spec_vector_len(&self) -> usize {
        5 + 5 * self.num_captors
    }

    pub fn captor_spec(&self) -> RobotSpec {
        RobotSpec {
            accel: 3.0,
            max_speed: self.captor_speed,
            mass: 1.0,
        }
    }

    pub fn target_spec(&self) -> RobotSpec {
        RobotSpec {
            accel: 4.0,
            max_speed: self.target_speed,
            mass: 1.0,
        }
    }

    /// The speed ratio v_e / v_p.
    pub fn speed_ratio(&self) -> f64 {
        self.target_speed / self.captor_speed
    }
}
