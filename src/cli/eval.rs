//! `t2e-league eval`: the paper's protocol over one or more settings.

use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use t2e_core::env::{CaptureRule, EnvConfig, Side};
use t2e_core::map::{self, PreparedMap};
use t2e_learners::controllers::ControllerSpec;
use t2e_learners::eval::{self, ratio_label, EvalSetting, SettingIdentity, Summary, TABLE_HEADER};
use t2e_learners::plots::line::{self, Series};

#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// Captor controller: heuristic (expert captors), greedy (ASZ-greedy),
    /// greedy:K (ASZ-greedy on K-cell squares, K from 1 to 8: greedy:2
    /// marches on 0.10 m cells; K here is not --k), random, still, ckpt:PATH
    /// (a trained policy, its most likely action, the paper's evaluation) or
    /// sample:PATH (the same policy, sampling its actions).
    #[arg(long, default_value = "heuristic")]
    pub captors: ControllerSpec,
    /// Target controller: heuristic (rule-based target), greedy or greedy:K
    /// (ASZ-greedy's mirror: the move that leaves the target the largest
    /// ASZ; K as for --captors), lookahead:H or lookahead:H:CAPTORS (each
    /// move played H steps ahead against a model of the captors, the expert
    /// ones unless CAPTORS names another team; the best future kept),
    /// robust:H:M1+M2+... (the same against every team M1, M2, ...; the
    /// rule-based move unless some team catches it and another move is
    /// free under all), random, still, ckpt:PATH (a trained policy, its most likely action)
    /// or sample:PATH (the same policy, sampling its actions).
    #[arg(long, default_value = "heuristic")]
    pub target: ControllerSpec,
    /// Map sets, comma-separated: small, medium, large (Gibson classes), gibson,
    /// shipped, a folder, FOLDER:CLASS, or a .png file. One table row per set.
    #[arg(
        long,
        default_value = "shipped",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub maps: Vec<String>,
    /// Numbers of captors K, comma-separated (3,4 for the paper's 3:1 and 4:1).
    // The list options take values that start with '-', so that `--k -1`
    // reaches our own check (which says what K must be) instead of clap's
    // "unexpected argument".
    #[arg(long, default_value = "3", value_delimiter = ',', allow_hyphen_values = true, value_parser = parse_k)]
    pub k: Vec<usize>,
    /// Target speed over captor speed, comma-separated (1.0,1.2,1.4 in the paper).
    #[arg(
        long,
        default_value = "1.0",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub speed_ratio: Vec<f64>,
    /// Test episodes per setting (500, the paper's protocol).
    #[arg(long, default_value_t = 500)]
    pub episodes: usize,
    /// Steps before an episode counts as failed.
    #[arg(long, default_value_t = 500)]
    pub episode_length: u32,
    /// Seed of the episode seeds; the same seed gives the same starts to every controller.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Capture rule: fast (12 probes, the paper's tables) or strict (|ASZ| threshold).
    #[arg(long, value_enum, default_value = "fast")]
    pub capture_rule: CaptureRule,
    /// Measure |ASZ| every n-th step for SoA (0 = never; 1 = every step, as the paper).
    #[arg(long, default_value_t = 1)]
    pub soa_every: u32,
    /// Output folder: table.md, summary.json, and per setting episodes.csv, soa.csv, soa.png, departures.csv.
    #[arg(long, default_value = "runs/eval")]
    pub out: PathBuf,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
    /// Keep the settings a previous (killed) run of the same command already
    /// finished in --out, and run only the rest. Each setting is written as
    /// soon as it finishes.
    #[arg(long)]
    pub resume: bool,
}

/// One value of `--k`: a number of captors, 1 to `MAX_CAPTORS`.
fn parse_k(text: &str) -> Result<usize, String> {
    let k: i64 = text.trim().parse().map_err(|_| {
        format!("K = '{text}': not a whole number (K is the number of captors, e.g. --k 3,4)")
    })?;
    let max = t2e_core::env::MAX_CAPTORS as i64;
    if !(1..=max).contains(&k) {
        return Err(format!(
            "K = {k}: the number of captors must be at least 1 and at most {max}"
        ));
    }
    Ok(k as usize)
}

/// Loads and prepares the maps of every spec once.
fn load_map_sets(specs: &[String]) -> Result<BTreeMap<String, Arc<Vec<Arc<PreparedMap>>>>> {
    let mut sets = BTreeMap::new();
    for spec in specs {
        sets.insert(spec.clone(), map::catalog::load_prepared(spec)?);
    }
    Ok(sets)
}

/// The folder of one setting: readable parts (sanitised, so no name can
/// leave `out`) and the identity's hash, so two settings that differ in
/// anything that changes their numbers never share a folder.
fn setting_dir(out: &Path, s: &EvalSetting, maps: &str, identity: &SettingIdentity) -> PathBuf {
    let part = |text: &str| t2e_core::util::safe_component(text, 40);
    out.join(format!(
        "{}-vs-{}_k{}_r{}_{}_{}",
        part(&s.captors.to_string()),
        part(&s.target.to_string()),
        s.num_captors,
        part(&ratio_label(s.speed_ratio).replace('.', "p")),
        part(maps),
        identity.short_hash()
    ))
}

/// A file of a setting folder, read only if it is a regular file: a FIFO
/// in its place would block the read for ever.
fn read_regular(path: &Path) -> Result<String, String> {
    match std::fs::symlink_metadata(path).and_then(|_| std::fs::metadata(path)) {
        Err(_) => return Err(format!("{} is missing", path.display())),
        Ok(m) if !m.is_file() => return Err(format!("{} is not a regular file", path.display())),
        Ok(_) => {}
    }
    std::fs::read_to_string(path).map_err(|e| format!("{} cannot be read ({e})", path.display()))
}

/// The summary a previous run left for this setting, if every part of its
/// identity (`setting.json`) matches; else why not, or None where the
/// folder holds no run at all.
fn finished_setting(dir: &Path, identity: &SettingIdentity) -> Result<Summary, Option<String>> {
    let identity_file = dir.join("setting.json");
    if std::fs::symlink_metadata(&identity_file).is_err() {
        // Written last: without it the folder was never finished.
        return Err(dir
            .is_dir()
            .then(|| format!("{} was left unfinished (no setting.json)", dir.display())));
    }
    let text = read_regular(&identity_file)?;
    let written: SettingIdentity = serde_json::from_str(&text).map_err(|e| {
        format!(
            "{} is not a setting's identity ({e})",
            identity_file.display()
        )
    })?;
    if &written != identity {
        return Err(Some(format!(
            "{} records another setting",
            identity_file.display()
        )));
    }
    let summary_file = dir.join("summary.json");
    let summary: Summary = serde_json::from_str(&read_regular(&summary_file)?)
        .map_err(|e| format!("{} is not a summary ({e})", summary_file.display()))?;
    // The per-episode file must hold every episode the summary counts.
    let episodes_file = dir.join("episodes.csv");
    let text = read_regular(&episodes_file)?;
    let rows = csv::Reader::from_reader(text.as_bytes())
        .records()
        .filter(|r| r.is_ok())
        .count();
    if rows != summary.episodes {
        return Err(Some(format!(
            "{} holds {rows} episodes, its summary.json counts {}",
            episodes_file.display(),
            summary.episodes
        )));
    }
    Ok(summary)
}

/// Why `--resume` plays a setting again: what is wrong with `dir` itself
/// (`finished`), else the folders in `out` of the same setting name
/// (captors, target, K, ratio, maps) whose recorded identity differs,
/// each with the fields that changed. None where nothing of this setting
/// is there.
fn why_not_resumed(
    out: &Path,
    dir: &Path,
    identity: &SettingIdentity,
    finished: Option<String>,
) -> Option<String> {
    if let Some(why) = finished {
        return Some(format!("{why}; playing it again"));
    }
    let name = dir.file_name()?.to_string_lossy().into_owned();
    let stem = name.rsplit_once('_')?.0.to_string();
    let now = serde_json::to_value(identity).ok()?;
    let mut reasons = Vec::new();
    let mut others: Vec<PathBuf> = std::fs::read_dir(out)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .and_then(|n| n.rsplit_once('_'))
                .is_some_and(|(s, _)| s == stem)
                && *p != dir
        })
        .collect();
    others.sort();
    for other in others {
        let Ok(text) = read_regular(&other.join("setting.json")) else {
            continue;
        };
        let Ok(then) = serde_json::from_str::<serde_json::Value>(&text) else {
            continue;
        };
        let (Some(then), Some(now)) = (then.as_object(), now.as_object()) else {
            continue;
        };
        let changed: Vec<String> = now
            .iter()
            .filter(|(k, v)| then.get(*k) != Some(*v))
            .map(|(k, v)| match (then.get(k), v) {
                (Some(a), b) if !a.is_object() && !a.is_array() && !b.is_array() => {
                    format!("{k} {a} -> {b}")
                }
                _ => format!("{k} changed"),
            })
            .collect();
        reasons.push(format!(
            "{} was played with other settings ({}); it is left as it is",
            other.display(),
            changed.join(", ")
        ));
    }
    (!reasons.is_empty()).then(|| reasons.join("; "))
}

fn write_setting(
    dir: &Path,
    identity: &SettingIdentity,
    summary: &Summary,
    records: &[eval::EpisodeRecord],
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    // The identity goes last: a folder without it is never taken as finished.
    let _ = std::fs::remove_file(dir.join("setting.json"));
    // Opening a FIFO left in a file's place to write would block.
    for name in [
        "summary.json",
        "episodes.csv",
        "soa.csv",
        "soa.png",
        "departures.csv",
    ] {
        let path = dir.join(name);
        if std::fs::symlink_metadata(&path).is_ok_and(|m| !m.is_file()) {
            std::fs::remove_file(&path).with_context(|| {
                format!(
                    "{}: not a regular file, and cannot be removed",
                    path.display()
                )
            })?;
        }
    }
    let episodes = dir.join("episodes.csv");
    let mut w = csv::Writer::from_path(&episodes)
        .with_context(|| format!("cannot write {}", episodes.display()))?;
    w.write_record([
        "episode",
        "seed",
        "map",
        "steps",
        "captured",
        "captor_path_len_m",
        "mean_soa_m2",
        "target_departure_rate",
    ])?;
    for r in records {
        let soa = if r.soa_m2.is_empty() {
            String::new()
        } else {
            format!(
                "{:.4}",
                r.soa_m2.iter().sum::<f64>() / r.soa_m2.len() as f64
            )
        };
        w.write_record([
            r.episode.to_string(),
            r.seed.to_string(),
            r.map.clone(),
            r.steps.to_string(),
            r.captured.to_string(),
            format!("{:.4}", r.captor_path_len),
            soa,
            r.target_departures
                .map(|(d, n)| format!("{:.4}", d as f64 / n.max(1) as f64))
                .unwrap_or_default(),
        ])?;
    }
    w.flush()?;
    std::fs::write(
        dir.join("summary.json"),
        serde_json::to_string_pretty(summary)?,
    )
    .with_context(|| format!("cannot write {}", dir.join("summary.json").display()))?;
    if !summary.soa_curve.is_empty() {
        let mut w = csv::Writer::from_path(dir.join("soa.csv"))?;
        w.write_record(["step", "mean_asz_m2", "episodes_running"])?;
        for (t, m, n) in &summary.soa_curve {
            w.write_record([t.to_string(), format!("{m:.4}"), n.to_string()])?;
        }
        w.flush()?;
    }
    if let Some(places) = &summary.target_departure_places {
        let path = dir.join("departures.csv");
        let mut w = csv::Writer::from_path(&path)
            .with_context(|| format!("cannot write {}", path.display()))?;
        w.write_record(["by", "bin", "decisions", "departures", "departure_pct"])?;
        for (by, bin, tally) in places.rows() {
            w.write_record([
                by.to_string(),
                bin,
                tally.decisions.to_string(),
                tally.departures.to_string(),
                eval::departures::share(tally)
                    .map(|s| format!("{s:.3}"))
                    .unwrap_or_default(),
            ])?;
        }
        w.flush()?;
    }
    t2e_core::fs::write_file_atomically(
        &dir.join("setting.json"),
        serde_json::to_string_pretty(identity)?.as_bytes(),
    )?;
    Ok(())
}

/// Refuses a list that names the same value twice.
fn no_repeats<T: PartialEq + std::fmt::Display>(option: &str, values: &[T]) -> Result<()> {
    for (i, v) in values.iter().enumerate() {
        if values[..i].contains(v) {
            anyhow::bail!("{option} lists {v} twice");
        }
    }
    Ok(())
}

/// Refuses the arguments before any map is loaded: repeats, settings out of
/// range, and players that cannot play a K asked for.
fn check_args(args: &EvalArgs) -> Result<()> {
    no_repeats("--k", &args.k)?;
    no_repeats("--speed-ratio", &args.speed_ratio)?;
    no_repeats("--maps", &args.maps)?;
    for &k in &args.k {
        for &ratio in &args.speed_ratio {
            EvalSetting {
                num_captors: k,
                speed_ratio: ratio,
                episodes: args.episodes,
                episode_length: args.episode_length,
                ..EvalSetting::default()
            }
            .validate()
            .map_err(anyhow::Error::msg)?;
        }
    }
    for k in &args.k {
        let cfg = EnvConfig {
            num_captors: *k,
            ..EnvConfig::default()
        };
        args.captors
            .check(Side::Captors, &cfg)
            .map_err(|e| anyhow::anyhow!("--captors: {e}"))?;
        args.target
            .check(Side::Target, &cfg)
            .map_err(|e| anyhow::anyhow!("--target: {e}"))?;
    }
    Ok(())
}

/// One setting's summary: the finished one under `--resume`, else played and
/// written; apart from `run` so the resume rule reads on its own.
fn setting_summary(
    args: &EvalArgs,
    setting: &EvalSetting,
    spec: &str,
    maps: &Arc<Vec<Arc<PreparedMap>>>,
) -> Result<(Summary, PathBuf)> {
    let identity = SettingIdentity::of(setting, spec, maps).map_err(anyhow::Error::msg)?;
    let dir = setting_dir(&args.out, setting, spec, &identity);
    let finished = if args.resume {
        finished_setting(&dir, &identity)
    } else {
        Err(None)
    };
    let summary = match finished {
        Ok(done) => done,
        Err(finished) => {
            if args.resume {
                if let Some(why) = why_not_resumed(&args.out, &dir, &identity, finished) {
                    eprintln!(
                        "--resume: {spec}, K = {}, ratio {}: starts again: {why}",
                        setting.num_captors, setting.speed_ratio
                    );
                }
            }
            let (summary, records) = eval::run(setting, maps, spec, !args.quiet)?;
            write_setting(&dir, &identity, &summary, &records)?;
            summary
        }
    };
    Ok((summary, dir))
}

/// A setting's mean-|ASZ| curve as a series, its own plot written to `dir`;
/// apart from `run` because only settings with a curve have one.
fn setting_curve(
    args: &EvalArgs,
    summary: &Summary,
    (k, ratio, spec): (usize, f64, &str),
    dir: &Path,
    color: [u8; 3],
) -> Result<Series> {
    let points: Vec<(f64, f64)> = summary
        .soa_curve
        .iter()
        .map(|&(t, m, _)| (t as f64, m))
        .collect();
    let label = format!("{}:1 x{} {}", k, ratio_label(ratio), spec);
    let series = Series {
        label: label.clone(),
        points,
        color,
    };
    let title = format!(
        "mean |ASZ| over time: {} vs {}, {label}",
        args.captors, args.target
    );
    line::save_png(
        &line::line_plot(
            std::slice::from_ref(&series),
            &title,
            "step",
            "|ASZ| (m^2)",
            800,
            500,
        ),
        dir.join("soa.png"),
    )?;
    Ok(series)
}

/// The run's table, summaries and (with several curves) their joint plot;
/// apart from `run` because it is written once, after every setting.
fn write_outputs(args: &EvalArgs, summaries: &[Summary], curves: &[Series]) -> Result<()> {
    let mut table = format!("{TABLE_HEADER}\n");
    for s in summaries {
        table.push_str(&s.table_row());
        table.push('\n');
    }
    for (name, bytes) in [
        ("table.md", table.into_bytes()),
        (
            "summary.json",
            serde_json::to_string_pretty(&summaries)?.into_bytes(),
        ),
    ] {
        t2e_core::fs::write_file_atomically(&args.out.join(name), &bytes)
            .with_context(|| format!("cannot write {}", args.out.join(name).display()))?;
    }
    if curves.len() > 1 {
        let title = format!("mean |ASZ| over time: {} vs {}", args.captors, args.target);
        line::save_png(
            &line::line_plot(curves, &title, "step", "|ASZ| (m^2)", 1000, 600),
            args.out.join("soa.png"),
        )?;
    }
    Ok(())
}

pub fn run(args: EvalArgs) -> Result<()> {
    if args.captors.is_checkpoint() || args.target.is_checkpoint() {
        tch::set_num_threads(1);
    }
    check_args(&args)?;
    let sets = load_map_sets(&args.maps)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let mut summaries = Vec::new();
    let mut curves = Vec::new();
    println!("{TABLE_HEADER}");
    for &k in &args.k {
        for &ratio in &args.speed_ratio {
            for spec in &args.maps {
                let setting = EvalSetting {
                    captors: args.captors.clone(),
                    target: args.target.clone(),
                    num_captors: k,
                    speed_ratio: ratio,
                    episodes: args.episodes,
                    episode_length: args.episode_length,
                    seed: args.seed,
                    capture_rule: args.capture_rule,
                    soa_every: args.soa_every,
                };
                let (summary, dir) = setting_summary(&args, &setting, spec, &sets[spec])?;
                println!("{}", summary.table_row());
                if !summary.soa_curve.is_empty() {
                    let color = line::palette(curves.len());
                    let at = (k, ratio, spec.as_str());
                    curves.push(setting_curve(&args, &summary, at, &dir, color)?);
                }
                summaries.push(summary);
            }
        }
    }
    write_outputs(&args, &summaries, &curves)?;
    tracing::info!("wrote {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity(setting: &EvalSetting) -> SettingIdentity {
        let grid = t2e_core::map::Grid::with_free_rects("m", 320, &[(100..200, 100..200)]);
        let maps = vec![Arc::new(PreparedMap::new(grid))];
        SettingIdentity::of(setting, "m", &maps).unwrap()
    }

    #[test]
    fn resume_reuses_only_a_setting_identical_in_every_number() {
        let out = tempfile::tempdir().unwrap();
        let setting = EvalSetting {
            episodes: 3,
            episode_length: 20,
            soa_every: 0,
            ..EvalSetting::default()
        };
        let record = |captured| eval::EpisodeRecord {
            episode: 0,
            seed: 1,
            map: "m".into(),
            steps: 20,
            captured,
            captor_path_len: 1.0,
            soa_m2: vec![],
            target_departures: None,
            target_departure_places: None,
        };
        let records = vec![record(true), record(false), record(false)];
        let summary = eval::summarise(&setting, "m", &records);
        let id = identity(&setting);
        let dir = setting_dir(out.path(), &setting, "m", &id);
        assert!(finished_setting(&dir, &id).is_err(), "nothing written yet");
        write_setting(&dir, &id, &summary, &records).unwrap();
        assert_eq!(finished_setting(&dir, &id), Ok(summary));
        // Each of these changes the numbers: none may reuse the result or share its folder.
        let variants = [
            EvalSetting {
                episodes: 500,
                ..setting.clone()
            },
            EvalSetting {
                soa_every: 1,
                ..setting.clone()
            },
            EvalSetting {
                speed_ratio: 1.04,
                ..setting.clone()
            },
            EvalSetting {
                capture_rule: CaptureRule::Strict,
                ..setting.clone()
            },
            EvalSetting {
                seed: 1,
                ..setting.clone()
            },
            EvalSetting {
                episode_length: 21,
                ..setting.clone()
            },
            EvalSetting {
                target: ControllerSpec::Random,
                ..setting.clone()
            },
        ];
        let mut dirs = vec![dir.clone()];
        for v in &variants {
            let vid = identity(v);
            assert!(finished_setting(&dir, &vid).is_err(), "{v:?} reused");
            let vdir = setting_dir(out.path(), v, "m", &vid);
            assert!(!dirs.contains(&vdir), "{v:?} shares {}", vdir.display());
            dirs.push(vdir);
        }
        // Other maps under the same name: another identity.
        let grid = t2e_core::map::Grid::with_free_rects("m", 320, &[(100..200, 100..201)]);
        let other =
            SettingIdentity::of(&setting, "m", &[Arc::new(PreparedMap::new(grid))]).unwrap();
        assert!(finished_setting(&dir, &other).is_err());
        // A folder name never leaves --out, whatever the controller's path says.
        let sneaky = EvalSetting {
            captors: "ckpt:../../../etc".parse().unwrap(),
            ..setting.clone()
        };
        let d = setting_dir(out.path(), &sneaky, "../x", &id);
        assert_eq!(d.parent().unwrap(), out.path());
        assert!(d
            .file_name()
            .unwrap()
            .to_str()
            .unwrap()
            .starts_with("ckpt_etc-vs-heuristic_k3_r1p0_x_"));
    }

    #[test]
    fn ratios_keep_every_digit_in_labels() {
        assert_eq!(ratio_label(1.0), "1.0");
        assert_eq!(ratio_label(1.04), "1.04");
        assert_eq!(ratio_label(1.2), "1.2");
    }
}
