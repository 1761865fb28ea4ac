//! `t2e-league eval`: the paper's protocol over one or more settings.

use crate::env::{CaptureRule, EnvConfig, Side};
use crate::eval::{self, EvalSetting, Summary, TABLE_HEADER};
use crate::heuristics::ControllerSpec;
use crate::map::{self, PreparedMap};
use crate::render::plot::{self, Series};
use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;

#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// Captor controller: heuristic (expert captors), greedy (ASZ-greedy), random, still.
    #[arg(long, default_value = "heuristic")]
    pub captors: ControllerSpec,
    /// Target controller: heuristic (rule-based target), random, still.
    #[arg(long, default_value = "heuristic")]
    pub target: ControllerSpec,
    /// Map sets, comma-separated: small, medium, large (Gibson classes), gibson,
    /// shipped, a folder, FOLDER:CLASS, or a .png file. One table row per set.
    #[arg(long, default_value = "shipped", value_delimiter = ',')]
    pub maps: Vec<String>,
    /// Numbers of captors K, comma-separated (3,4 for the paper's 3:1 and 4:1).
    #[arg(long, default_value = "3", value_delimiter = ',')]
    pub k: Vec<usize>,
    /// Target speed over captor speed, comma-separated (1.0,1.2,1.4 in the paper).
    #[arg(long, default_value = "1.0", value_delimiter = ',')]
    pub speed_ratio: Vec<f64>,
    /// Test episodes per setting.
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
    /// Output folder: table.md, summary.json, and per setting episodes.csv, soa.csv, soa.png.
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

/// Loads and prepares the maps of every spec once.
fn load_map_sets(specs: &[String]) -> Result<BTreeMap<String, Arc<Vec<Arc<PreparedMap>>>>> {
    let mut sets = BTreeMap::new();
    for spec in specs {
        sets.insert(spec.clone(), map::catalog::load_prepared(spec)?);
    }
    Ok(sets)
}

fn setting_dir(out: &Path, s: &EvalSetting, maps: &str) -> PathBuf {
    let maps = maps.replace(['/', ':', '.'], "_");
    out.join(format!(
        "{}-vs-{}_k{}_r{:.1}_{}",
        s.captors,
        s.target,
        s.num_captors,
        s.speed_ratio,
        maps.trim_matches('_')
    ))
}

/// The summary a previous run left for this setting, if it matches.
fn finished_setting(dir: &Path, setting: &EvalSetting) -> Option<Summary> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    let s: Summary = serde_json::from_str(&text).ok()?;
    let same = s.episodes == setting.episodes
        && s.episode_length == setting.episode_length
        && s.seed == setting.seed
        && s.mean_soa_m2.is_some() == (setting.soa_every > 0);
    same.then_some(s)
}

fn write_setting(dir: &Path, summary: &Summary, records: &[eval::EpisodeRecord]) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let mut w = csv::Writer::from_path(dir.join("episodes.csv"))?;
    w.write_record([
        "episode",
        "seed",
        "map",
        "steps",
        "captured",
        "captor_path_len_m",
        "mean_soa_m2",
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
        ])?;
    }
    w.flush()?;
    std::fs::write(
        dir.join("summary.json"),
        serde_json::to_string_pretty(summary)?,
    )?;
    if !summary.soa_curve.is_empty() {
        let mut w = csv::Writer::from_path(dir.join("soa.csv"))?;
        w.write_record(["step", "mean_asz_m2", "episodes_running"])?;
        for (t, m, n) in &summary.soa_curve {
            w.write_record([t.to_string(), format!("{m:.4}"), n.to_string()])?;
        }
        w.flush()?;
    }
    Ok(())
}

pub fn run(args: EvalArgs) -> Result<()> {
    if args.captors.is_checkpoint() || args.target.is_checkpoint() {
        tch::set_num_threads(1);
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
                let dir = setting_dir(&args.out, &setting, spec);
                let summary = match finished_setting(&dir, &setting).filter(|_| args.resume) {
                    Some(done) => done,
                    None => {
                        let (summary, records) =
                            eval::run(&setting, &sets[spec], spec, !args.quiet)?;
                        write_setting(&dir, &summary, &records)?;
                        summary
                    }
                };
                println!("{}", summary.table_row());
                if !summary.soa_curve.is_empty() {
                    let points: Vec<(f64, f64)> = summary
                        .soa_curve
                        .iter()
                        .map(|&(t, m, _)| (t as f64, m))
                        .collect();
                    let label = format!("{}:1 x{:.1} {}", k, ratio, spec);
                    let series = Series {
                        label: label.clone(),
                        points,
                        color: plot::palette(curves.len()),
                    };
                    let title = format!(
                        "mean |ASZ| over time: {} vs {}, {label}",
                        args.captors, args.target
                    );
                    plot::save_png(
                        &plot::line_plot(
                            std::slice::from_ref(&series),
                            &title,
                            "step",
                            "|ASZ| (m^2)",
                            800,
                            500,
                        ),
                        dir.join("soa.png"),
                    )?;
                    curves.push(series);
                }
                summaries.push(summary);
            }
        }
    }
    let mut table = std::fs::File::create(args.out.join("table.md"))?;
    writeln!(table, "{TABLE_HEADER}")?;
    for s in &summaries {
        writeln!(table, "{}", s.table_row())?;
    }
    std::fs::write(
        args.out.join("summary.json"),
        serde_json::to_string_pretty(&summaries)?,
    )?;
    if curves.len() > 1 {
        let title = format!("mean |ASZ| over time: {} vs {}", args.captors, args.target);
        plot::save_png(
            &plot::line_plot(&curves, &title, "step", "|ASZ| (m^2)", 1000, 600),
            args.out.join("soa.png"),
        )?;
    }
    eprintln!("wrote {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resume_reuses_only_a_matching_finished_setting() {
        let dir = tempfile::tempdir().unwrap();
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
        };
        let records = vec![record(true), record(false), record(false)];
        let summary = eval::summarise(&setting, "m", &records);
        assert!(
            finished_setting(dir.path(), &setting).is_none(),
            "nothing written yet"
        );
        write_setting(dir.path(), &summary, &records).unwrap();
        assert_eq!(finished_setting(dir.path(), &setting), Some(summary));
        let longer = EvalSetting {
            episodes: 500,
            ..setting.clone()
        };
        assert!(finished_setting(dir.path(), &longer).is_none());
        let with_soa = EvalSetting {
            soa_every: 1,
            ..setting
        };
        assert!(finished_setting(dir.path(), &with_soa).is_none());
    }
}
