//! The paper's evaluation protocol (spec §8): many seeded episodes of one
//! setting, in parallel, summarised as Time, SR (with a 95% Wilson interval),
//! Path Len and the size of the Absolutely Safe Zone over time (SoA).

use crate::controllers::ControllerError;
use crate::controllers::ControllerSpec;
use crate::error::{LearnError, ResultExt};
use departures::DeparturePlaces;
use t2e_core::asz::{cells_to_m2, AszFields};
use t2e_core::env::vec_env::episode_seed;
use t2e_core::env::{Action, CaptureRule, EnvConfig, Side, TrapEnv};
use t2e_core::error::{in_interval, ConfigError};
use t2e_core::map::PreparedMap;

pub mod cross_table;
pub mod departures;
pub mod paper_table;
pub mod tune;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// One evaluation setting (one cell of the paper's tables).
#[derive(Clone, Debug)]
pub struct EvalSetting {
    pub captors: ControllerSpec,
    pub target: ControllerSpec,
    pub num_captors: usize,
    /// v_e / v_p with v_p = 1 m/s.
    pub speed_ratio: f64,
    pub episodes: usize,
    pub episode_length: u32,
    pub seed: u64,
    pub capture_rule: CaptureRule,
    /// Measure |ASZ| every n-th step (0: never). One multi-label march per
    /// measurement; the strict rule measures every step anyway.
    pub soa_every: u32,
}

impl Default for EvalSetting {
    fn default() -> Self {
        EvalSetting {
            captors: ControllerSpec::Heuristic,
            target: ControllerSpec::Heuristic,
            num_captors: 3,
            speed_ratio: 1.0,
            episodes: 500,
            episode_length: 500,
            seed: 0,
            capture_rule: CaptureRule::Fast,
            soa_every: 1,
        }
    }
}

impl EvalSetting {
    /// Checks the numbers a user gave; the error names the option.
    pub fn validate(&self) -> Result<(), ConfigError> {
        // Options, not a file's fields: `--episodes 0: ...`.
        let option = |name: &str, value: &dyn std::fmt::Display, rule: &str| ConfigError {
            field: format!("{name} {value}"),
            value: None,
            rule: rule.into(),
        };
        if self.episodes == 0 {
            return Err(option(
                "--episodes",
                &0,
                "needs at least one episode (an SR of 0 episodes is no result)",
            ));
        }
        if self.episodes > 10_000_000 {
            return Err(option("--episodes", &self.episodes, "at most 10,000,000"));
        }
        if in_interval("speed_ratio", self.speed_ratio, 0.0, 10.0, false).is_err() {
            return Err(option(
                "--speed-ratio",
                &self.speed_ratio,
                "must be a number in (0, 10]",
            ));
        }
        self.env_config().validate().map_err(|e| ConfigError {
            field: format!("evaluation setting: {}", e.field),
            ..e
        })
    }

    pub fn env_config(&self) -> EnvConfig {
        EnvConfig {
            num_captors: self.num_captors,
            captor_speed: 1.0,
            target_speed: self.speed_ratio,
            episode_length: self.episode_length,
            capture_rule: self.capture_rule,
            observations: false,
            ..EnvConfig::default()
        }
    }
}

/// Everything that changes a setting's numbers: two settings with the same
/// identity give the same table row, and two with different identities never
/// share an output folder or a resumed result.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettingIdentity {
    pub captors: String,
    /// SHA-256 of the captor checkpoint's actor weights (None for heuristics).
    pub captors_sha256: Option<String>,
    /// SHA-256 of the captor checkpoint's `meta.json`: the sidecar names the
    /// protocol and learner the table rows show, so an edited sidecar is
    /// another setting. (Missing in identities written before it existed,
    /// which therefore match no setting of this build.)
    pub captors_meta_sha256: Option<String>,
    pub target: String,
    pub target_sha256: Option<String>,
    pub target_meta_sha256: Option<String>,
    pub num_captors: usize,
    /// Exact v_e / v_p.
    pub speed_ratio: f64,
    pub capture_rule: CaptureRule,
    pub episode_length: u32,
    pub episodes: usize,
    pub seed: u64,
    pub soa_every: u32,
    /// The map set as named, and (name, content hash) of every map in it.
    pub maps: String,
    pub map_hashes: Vec<(String, String)>,
    /// The code that played the episodes (crate version + git commit).
    pub code_version: String,
}

impl SettingIdentity {
    pub fn of(
        setting: &EvalSetting,
        maps_label: &str,
        maps: &[Arc<PreparedMap>],
    ) -> Result<SettingIdentity, ControllerError> {
        type Hashes = (Option<String>, Option<String>);
        let hashes = |spec: &ControllerSpec, side: Side| -> Result<Hashes, ControllerError> {
            match spec {
                ControllerSpec::Checkpoint(c) => {
                    let snap = c.snapshot(side)?;
                    Ok((
                        snap.meta.files.get("actor.safetensors").cloned(),
                        Some(snap.meta_sha256.clone()),
                    ))
                }
                _ => Ok((None, None)),
            }
        };
        let (captors_sha256, captors_meta_sha256) = hashes(&setting.captors, Side::Captors)?;
        let (target_sha256, target_meta_sha256) = hashes(&setting.target, Side::Target)?;
        Ok(SettingIdentity {
            captors: setting.captors.to_string(),
            captors_sha256,
            captors_meta_sha256,
            target: setting.target.to_string(),
            target_sha256,
            target_meta_sha256,
            num_captors: setting.num_captors,
            speed_ratio: setting.speed_ratio,
            capture_rule: setting.capture_rule,
            episode_length: setting.episode_length,
            episodes: setting.episodes,
            seed: setting.seed,
            soa_every: setting.soa_every,
            maps: maps_label.to_string(),
            map_hashes: maps
                .iter()
                .map(|m| (m.grid.name.clone(), m.grid.content_hash()))
                .collect(),
            code_version: crate::nn::checkpoint::code_version(),
        })
    }

    /// First 12 hex digits of the SHA-256 of the identity's JSON.
    pub fn short_hash(&self) -> String {
        let json = serde_json::to_string(self).expect("identity serialises");
        t2e_core::util::sha256_hex(json.as_bytes())[..12].to_string()
    }
}

/// A speed ratio as written in tables and folder names: every digit it
/// needs, at least one decimal (1.0, 1.2, 1.04).
pub fn ratio_label(ratio: f64) -> String {
    let s = format!("{ratio}");
    if s.contains(['.', 'e', 'E']) || !ratio.is_finite() {
        s
    } else {
        format!("{s}.0")
    }
}

/// What happened in one test episode.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct EpisodeRecord {
    pub episode: usize,
    pub seed: u64,
    pub map: String,
    /// Steps taken; a failed episode counts the full episode length.
    pub steps: u32,
    pub captured: bool,
    /// Mean distance travelled per captor (m).
    pub captor_path_len: f64,
    /// |ASZ| in m^2 at steps 0, soa_every, 2 soa_every, ... while the episode runs.
    pub soa_m2: Vec<f64>,
    /// The target's decisions, and how many of them differ from the
    /// rule-based target's in the same state: (departures, decisions).
    /// None when the target is the rule-based one (never departs).
    pub target_departures: Option<(u32, u32)>,
    /// The same decisions by where they were taken (nearest captor, |ASZ|);
    /// None where `target_departures` is.
    pub target_departure_places: Option<DeparturePlaces>,
}

/// The table row of one setting.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    pub captors: String,
    /// What plays the captors: a checkpoint's algorithm (MAPPO, IPPO), else
    /// the controller (`captors_learner`).
    #[serde(default = "unknown_protocol")]
    pub captors_learner: String,
    /// SHA-256 of the captor checkpoint's actor weights (None for
    /// heuristics, and in summaries written before the field): `ckpt:RUN`
    /// names the run's newest checkpoint, so two summaries under one name
    /// can hold other weights, and a table must not join them in one row.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub captors_sha256: Option<String>,
    pub target: String,
    pub num_captors: usize,
    pub speed_ratio: f64,
    pub maps: String,
    /// The protocol the learned players were trained under (`training_protocol`).
    #[serde(default = "unknown_protocol")]
    pub protocol: String,
    pub episodes: usize,
    pub episode_length: u32,
    pub seed: u64,
    pub capture_rule: CaptureRule,
    pub soa_every: u32,
    /// Mean episode length (steps), failures counted as the full length.
    pub time: f64,
    /// Capture rate (%).
    pub sr: f64,
    /// 95% Wilson interval of SR (%).
    pub sr_low: f64,
    pub sr_high: f64,
    /// Mean distance travelled per captor per episode (m).
    pub path_len: f64,
    /// Mean |ASZ| (m^2) over every measured step of every episode; None without SoA.
    pub mean_soa_m2: Option<f64>,
    /// (step, mean |ASZ| m^2 over the episodes still running, episodes running).
    pub soa_curve: Vec<(u32, f64, usize)>,
    /// Share (%) of the target's decisions, over all episodes, that differ
    /// from the rule-based target's in the same state: how far a learned
    /// target is from a copy. None for the rule-based target itself and in
    /// summaries written before the field.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_departure: Option<f64>,
    /// The target's decisions and departures over all episodes, by where
    /// they were taken (`departures::DeparturePlaces`). None where
    /// `target_departure` is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_departure_places: Option<DeparturePlaces>,
}

/// 95% Wilson score interval for `successes` out of `n`, as fractions.
pub fn wilson_interval(successes: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_963_984_540_054_f64;
    let nf = n as f64;
    let p = successes as f64 / nf;
    let denom = 1.0 + z * z / nf;
    let centre = (p + z * z / (2.0 * nf)) / denom;
    let half = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt() / denom;
    // At 0 or n successes one bound is p exactly; rounding may put it a
    // hair on the wrong side.
    ((centre - half).clamp(0.0, p), (centre + half).clamp(p, 1.0))
}

/// Plays test episode `episode` of a setting: seed, map and placement come
/// from the setting's seed and the episode index alone, so two controllers
/// evaluated with the same seed face the same starts.
pub fn play_episode(
    setting: &EvalSetting,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
    episode: usize,
    asz_fields: &mut AszFields,
) -> Result<EpisodeRecord, LearnError> {
    let mut env = TrapEnv::new(setting.env_config(), maps.clone())?;
    let mut captors = setting.captors.build(Side::Captors)?;
    let mut target = setting.target.build(Side::Target)?;
    let seed = episode_seed(setting.seed, 0, episode as u64);
    env.reset_state(seed)?;
    captors.reset(&env, seed);
    target.reset(&env, seed);
    let k = setting.num_captors;
    let mut actions = vec![Action::Stop; k + 1];
    let mut rewards = vec![0f32; k + 1];
    let mut soa = Vec::new();
    let measure = |env: &TrapEnv, asz_fields: &mut AszFields| {
        let (c, t) = env.asz_sources();
        cells_to_m2(asz_fields.asz_cells(&**env.map(), t, &c))
    };
    if setting.soa_every > 0 {
        soa.push(measure(&env, asz_fields));
    }
    let measured = setting.target != ControllerSpec::Heuristic;
    let mut departures = measured.then_some((0u32, 0u32));
    let mut places = measured.then(DeparturePlaces::default);
    while !env.is_done() {
        captors.act(&env, Side::Captors, &mut actions[..k]);
        target.act(&env, Side::Target, &mut actions[k..]);
        if let (Some((departed, decisions)), Some(places)) = (&mut departures, &mut places) {
            let departs = actions[k] != t2e_core::heuristics::target_action(&env);
            *decisions += 1;
            *departed += u32::from(departs);
            let target_pos = env.target().pos;
            let nearest = env
                .captors()
                .iter()
                .map(|c| t2e_core::env::physics::dist(c.pos, target_pos))
                .fold(f64::INFINITY, f64::min);
            // The last |ASZ| pushed is this state's when this step is measured.
            let asz_now = (setting.soa_every > 0 && env.steps % setting.soa_every == 0)
                .then(|| soa.last().copied())
                .flatten();
            places.record(nearest, asz_now, departs);
        }
        let info = env.step_state(&actions, &mut rewards);
        if setting.soa_every > 0 && env.steps % setting.soa_every == 0 {
            soa.push(match info.asz_cells {
                Some(c) => cells_to_m2(c),
                None => measure(&env, asz_fields),
            });
        }
    }
    Ok(EpisodeRecord {
        episode,
        seed,
        map: env.map().grid.name.clone(),
        steps: if env.captured {
            env.steps
        } else {
            setting.episode_length
        },
        captured: env.captured,
        captor_path_len: env.path_len[..k].iter().sum::<f64>() / k as f64,
        soa_m2: soa,
        target_departures: departures,
        target_departure_places: places,
    })
}

/// Runs all episodes of a setting in parallel, with a progress bar when `progress`.
pub fn run(
    setting: &EvalSetting,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
    maps_label: &str,
    progress: bool,
) -> Result<(Summary, Vec<EpisodeRecord>), LearnError> {
    setting.validate()?;
    let cfg = setting.env_config();
    setting
        .captors
        .check(Side::Captors, &cfg)
        .context("--captors")?;
    setting
        .target
        .check(Side::Target, &cfg)
        .context("--target")?;
    if setting.captors.is_checkpoint() || setting.target.is_checkpoint() {
        // Episodes already run in parallel; torch's own threads would fight them.
        tch::set_num_threads(1);
    }
    let bar = if progress {
        let b = ProgressBar::new(setting.episodes as u64);
        b.set_style(
            ProgressStyle::with_template(
                "{msg} [{bar:30}] {pos}/{len} episodes, {per_sec}, eta {eta}",
            )
            .unwrap()
            .progress_chars("=> "),
        );
        b.set_message(format!(
            "{} vs {} {}:1 x{} {}",
            setting.captors, setting.target, setting.num_captors, setting.speed_ratio, maps_label
        ));
        b
    } else {
        ProgressBar::hidden()
    };
    let records = (0..setting.episodes)
        .into_par_iter()
        .map_init(AszFields::new, |fm, i| {
            let r = play_episode(setting, maps, i, fm);
            bar.inc(1);
            r
        })
        .collect::<Result<Vec<_>, LearnError>>()?;
    bar.finish_and_clear();
    Ok((summarise(setting, maps_label, &records), records))
}

fn unknown_protocol() -> String {
    "unknown".into()
}

/// Under which protocol the setting's learned players were trained, from
/// their checkpoints' sidecars: "held-out" or "paper"; "-" when no learned
/// player takes part (heuristics are not trained on any maps); both named
/// when captors and target differ.
pub fn training_protocol(setting: &EvalSetting) -> String {
    let of = |spec: &ControllerSpec, side: Side| match spec {
        ControllerSpec::Checkpoint(c) => Some(
            c.snapshot(side)
                .map(|s| s.meta.protocol.name().to_string())
                .unwrap_or_else(|_| "unknown".into()),
        ),
        _ => None,
    };
    match (
        of(&setting.captors, Side::Captors),
        of(&setting.target, Side::Target),
    ) {
        (None, None) => "-".into(),
        (Some(p), None) | (None, Some(p)) => p,
        (Some(c), Some(t)) if c == t => c,
        (Some(c), Some(t)) => format!("captors {c}, target {t}"),
    }
}

/// SHA-256 of the captors' actor weights, for a checkpoint.
pub fn captors_weights(spec: &ControllerSpec) -> Option<String> {
    match spec {
        ControllerSpec::Checkpoint(c) => c
            .snapshot(Side::Captors)
            .ok()
            .and_then(|s| s.meta.files.get("actor.safetensors").cloned()),
        _ => None,
    }
}

/// The learner (checkpoint algorithm) or controller behind the captors.
pub fn captors_learner(spec: &ControllerSpec) -> String {
    match spec {
        ControllerSpec::Checkpoint(c) => c
            .snapshot(Side::Captors)
            .map(|s| s.meta.algorithm.name().to_uppercase())
            .unwrap_or_else(|_| "unknown".into()),
        ControllerSpec::Heuristic => "expert heuristic".into(),
        ControllerSpec::Greedy { coarsening: 1 } => "ASZ-greedy".into(),
        ControllerSpec::Greedy { coarsening } => {
            format!("ASZ-greedy on {:.2} m cells", 0.05 * *coarsening as f64)
        }
        other => other.to_string(),
    }
}

/// The share (%) of all the target's decisions over `records` that differ
/// from the rule-based target's in the same state; None where not measured.
pub fn departure_share(records: &[EpisodeRecord]) -> Option<f64> {
    let (mut departed, mut decisions) = (0u64, 0u64);
    for (d, n) in records.iter().filter_map(|r| r.target_departures) {
        departed += d as u64;
        decisions += n as u64;
    }
    (decisions > 0).then(|| 100.0 * departed as f64 / decisions as f64)
}

/// The target's decisions over `records` by where they were taken; None
/// where not measured.
pub fn departure_places(records: &[EpisodeRecord]) -> Option<DeparturePlaces> {
    let mut all: Option<DeparturePlaces> = None;
    for p in records
        .iter()
        .filter_map(|r| r.target_departure_places.as_ref())
    {
        all.get_or_insert_with(DeparturePlaces::default).merge(p);
    }
    all
}

pub fn summarise(setting: &EvalSetting, maps_label: &str, records: &[EpisodeRecord]) -> Summary {
    let n = records.len().max(1) as f64;
    let captures = records.iter().filter(|r| r.captured).count();
    let (lo, hi) = wilson_interval(captures, records.len());
    let longest = records.iter().map(|r| r.soa_m2.len()).max().unwrap_or(0);
    let mut curve = Vec::with_capacity(longest);
    let (mut soa_sum, mut soa_n) = (0.0, 0usize);
    for t in 0..longest {
        let vals: Vec<f64> = records
            .iter()
            .filter_map(|r| r.soa_m2.get(t).copied())
            .collect();
        soa_sum += vals.iter().sum::<f64>();
        soa_n += vals.len();
        curve.push((
            t as u32 * setting.soa_every.max(1),
            vals.iter().sum::<f64>() / vals.len() as f64,
            vals.len(),
        ));
    }
    Summary {
        captors: setting.captors.to_string(),
        captors_learner: captors_learner(&setting.captors),
        captors_sha256: captors_weights(&setting.captors),
        target: setting.target.to_string(),
        num_captors: setting.num_captors,
        speed_ratio: setting.speed_ratio,
        maps: maps_label.to_string(),
        protocol: training_protocol(setting),
        episodes: records.len(),
        episode_length: setting.episode_length,
        seed: setting.seed,
        capture_rule: setting.capture_rule,
        soa_every: setting.soa_every,
        time: records.iter().map(|r| r.steps as f64).sum::<f64>() / n,
        sr: 100.0 * captures as f64 / n,
        sr_low: 100.0 * lo,
        sr_high: 100.0 * hi,
        path_len: records.iter().map(|r| r.captor_path_len).sum::<f64>() / n,
        mean_soa_m2: (soa_n > 0).then(|| soa_sum / soa_n as f64),
        target_departure: departure_share(records),
        target_departure_places: departure_places(records),
        soa_curve: curve,
    }
}

/// Markdown table header matching `Summary::table_row`.
pub const TABLE_HEADER: &str = "| captors | target | K:1 | v_p:v_e | maps | protocol | episodes | Time (steps) | SR % [95% CI] | Path Len (m) | mean SoA (m^2) |\n|---|---|---|---|---|---|---|---|---|---|---|";

impl Summary {
    pub fn table_row(&self) -> String {
        format!(
            "| {} | {} | {}:1 | 1.0:{} | {}{} | {} | {} | {:.1} | {:.1} [{:.1}, {:.1}] | {:.2} | {} |",
            self.captors,
            self.target,
            self.num_captors,
            ratio_label(self.speed_ratio),
            self.maps,
            match self.capture_rule {
                CaptureRule::Fast => "",
                CaptureRule::Strict => " (strict capture)",
            },
            self.protocol,
            self.episodes,
            self.time,
            self.sr,
            self.sr_low,
            self.sr_high,
            self.path_len,
            self.mean_soa_m2
                .map(|s| format!("{s:.2}"))
                .unwrap_or_else(|| "-".into()),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wilson_interval_matches_known_values() {
        // 71 of 100: [0.615, 0.790] (standard tables).
        let (lo, hi) = wilson_interval(71, 100);
        assert!(
            (lo - 0.6146).abs() < 1e-3 && (hi - 0.7898).abs() < 1e-3,
            "{lo} {hi}"
        );
        let (lo, hi) = wilson_interval(0, 50);
        assert!(lo.abs() < 1e-12);
        assert!((hi - 0.0714).abs() < 1e-3);
        let (lo, hi) = wilson_interval(50, 50);
        assert!((lo - 0.9286).abs() < 1e-3 && (hi - 1.0).abs() < 1e-12);
        // The interval holds the observed rate exactly, at every n.
        for n in 1..300 {
            for k in [0, n] {
                let (lo, hi) = wilson_interval(k, n);
                let p = k as f64 / n as f64;
                assert!(lo <= p && p <= hi, "{k}/{n}: [{lo}, {hi}]");
            }
        }
    }

    #[test]
    fn summary_counts_failures_as_full_length_and_averages_soa_over_running_episodes() {
        let setting = EvalSetting {
            episode_length: 10,
            soa_every: 1,
            ..EvalSetting::default()
        };
        let rec = |captured, steps, soa: Vec<f64>| EpisodeRecord {
            episode: 0,
            seed: 0,
            map: "m".into(),
            steps,
            captured,
            captor_path_len: 2.0,
            soa_m2: soa,
            target_departures: None,
            target_departure_places: None,
        };
        let records = vec![
            rec(true, 2, vec![4.0, 2.0, 0.0]),
            rec(false, 10, vec![8.0; 11]),
        ];
        let s = summarise(&setting, "m", &records);
        assert_eq!(s.time, 6.0);
        assert_eq!(s.sr, 50.0);
        assert_eq!(s.soa_curve[0], (0, 6.0, 2));
        assert_eq!(s.soa_curve[5], (5, 8.0, 1));
        assert!((s.mean_soa_m2.unwrap() - (6.0 + 88.0) / 14.0).abs() < 1e-12);
    }
}
