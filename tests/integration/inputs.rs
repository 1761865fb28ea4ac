//! Bad inputs and faults a new user meets in `maps`, `eval`, `table`,
//! `render` and the league verbs: contradictory class lists, table cells
//! given twice, an edited checkpoint sidecar, a render killed while writing,
//! negative list values, a league folder not given, `--watch 5s`.
//! Each test failed before its fix: the tool picked one input silently,
//! relabelled results, lost a previous file or gave clap's error instead of
//! ours.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;
use t2e::cli::table::TableArgs;
use t2e_core::env::CaptureRule;
use t2e_core::map::catalog;
use t2e_core::map::SizeClass;
use t2e_learners::controllers::ControllerSpec;
use t2e_learners::eval::{EvalSetting, SettingIdentity, Summary};
use t2e_learners::learn::train::Trainer;

const BIN: &str = env!("CARGO_BIN_EXE_t2e-league");

/// A folder with copies of two shipped maps (a.png small, b.png large) and
/// the given class lists.
fn map_folder(lists: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (name, shipped) in [("a", "gen-small-1"), ("b", "gen-large-1")] {
        std::fs::copy(
            catalog::shipped_dir().join(format!("{shipped}.png")),
            dir.path().join(format!("{name}.png")),
        )
        .unwrap();
    }
    for (file, text) in lists {
        std::fs::write(dir.path().join(file), text).unwrap();
    }
    dir
}

fn err_of<T: std::fmt::Debug, E: Into<anyhow::Error>>(r: Result<T, E>) -> String {
    format!("{:#}", r.map_err(Into::into).unwrap_err())
}

#[test]
fn a_map_listed_with_two_classes_is_refused_naming_the_file_map_classes_and_lines() {
    // Twice in one splits.csv, with other classes: today the last row won.
    let dir = map_folder(&[("splits.csv", "map,split\na,small\nb,large\na,medium\n")]);
    let spec = dir.path().display().to_string();
    let err = err_of(catalog::resolve(&spec));
    assert!(
        err.contains("splits.csv: map 'a' is listed as small and as medium")
            && err.contains("splits.csv line 2 and")
            && err.contains("splits.csv line 4"),
        "{err}"
    );
    assert!(err_of(catalog::resolve(&format!("{spec}:small")))
        .contains("listed as small and as medium"));
    // `maps list` and loading for training refuse it too.
    assert!(catalog::load_prepared(&spec).is_err());

    // Twice with the same class: nothing contradicts, accepted.
    let dir = map_folder(&[("splits.csv", "map,split\na,small\nb,large\na,small\n")]);
    let entries = catalog::list_dir(dir.path()).unwrap();
    assert_eq!(entries[0].listed_class, Some(SizeClass::Small));
    assert_eq!(
        catalog::resolve(&format!("{}:small", dir.path().display()))
            .unwrap()
            .len(),
        1
    );

    // splits.csv and manifest.csv of one folder disagreeing: both named.
    let dir = map_folder(&[
        ("splits.csv", "map,split\na,small\n"),
        (
            "manifest.csv",
            "map,split,area_m2,seed\nb,large,70,1\na,large,30,1\n",
        ),
    ]);
    let err = err_of(catalog::list_dir(dir.path()));
    assert!(
        err.contains("map 'a' is listed as small and as large")
            && err.contains("splits.csv line 2")
            && err.contains("manifest.csv line 3"),
        "{err}"
    );

    // A class names a map whose file is missing: the set would silently
    // be smaller than the list says.
    let dir = map_folder(&[("splits.csv", "map,split\na,small\nb,large\nc,small\n")]);
    let err = err_of(catalog::resolve(&format!("{}:small", dir.path().display())));
    assert!(
        err.contains("splits.csv line 4 lists the small map 'c'") && err.contains("no c.png"),
        "{err}"
    );
    // The other class and the whole folder are unaffected.
    assert_eq!(
        catalog::resolve(&format!("{}:large", dir.path().display()))
            .unwrap()
            .len(),
        1
    );

    // A map file in capitals is a map of the folder too (it was skipped),
    // and two files of one name are refused.
    let dir = map_folder(&[]);
    std::fs::copy(dir.path().join("a.png"), dir.path().join("C.PNG")).unwrap();
    let names: Vec<String> = catalog::list_dir(dir.path())
        .unwrap()
        .into_iter()
        .map(|e| e.name)
        .collect();
    assert_eq!(names, ["C", "a", "b"]);
    std::fs::copy(dir.path().join("a.png"), dir.path().join("a.PNG")).unwrap();
    let err = err_of(catalog::list_dir(dir.path()));
    assert!(err.contains("are both map 'a'"), "{err}");

    // `maps generate` merges into a manifest: a contradictory one is
    // refused before any map is written.
    let dir = map_folder(&[("manifest.csv", "map,split\nx,small\nx,large\n")]);
    let err = err_of(t2e::cli::maps::generate_maps(
        SizeClass::Small,
        900,
        1,
        dir.path(),
    ));
    assert!(
        err.contains("manifest.csv: map 'x' is listed as small (line 2) and as large (line 3)"),
        "{err}"
    );
    assert!(!dir.path().join("gen-small-900.png").exists());
}

#[test]
fn maps_commands_do_not_overwrite_what_they_read() {
    let dir = map_folder(&[]);
    let map = dir.path().join("a.png");
    let before = std::fs::read(&map).unwrap();
    // `maps show` onto its own map would replace the map with a picture.
    let out = Command::new(BIN)
        .args([
            "maps",
            "show",
            map.to_str().unwrap(),
            "--out",
            map.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("the picture would replace the map"),
        "{stderr}"
    );
    assert_eq!(std::fs::read(&map).unwrap(), before);
    let out = Command::new(BIN)
        .args(["maps", "show", map.to_str().unwrap(), "--out"])
        .arg(dir.path().join("pic.jpg"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("must end in .png"), "{stderr}");
    // Generated maps written into a test set would join its classes.
    let test_set = map_folder(&[("splits.csv", "map,split\na,small\nb,large\n")]);
    let err = err_of(t2e::cli::maps::generate_maps(
        SizeClass::Small,
        1,
        1,
        test_set.path(),
    ));
    assert!(err.contains("holds a splits.csv"), "{err}");
    assert!(!test_set.path().join("manifest.csv").exists());
}

fn summary(maps: &str, episodes: usize, episode_length: u32, sr: f64) -> Summary {
    Summary {
        captors: "ckpt:runs/mappo".into(),
        captors_learner: "MAPPO".into(),
        captors_sha256: None,
        target: "heuristic".into(),
        num_captors: 3,
        speed_ratio: 1.0,
        maps: maps.into(),
        protocol: "held-out".into(),
        episodes,
        episode_length,
        seed: 0,
        capture_rule: CaptureRule::Fast,
        soa_every: 0,
        time: 200.0,
        sr,
        sr_low: sr - 3.0,
        sr_high: (sr + 3.0).min(100.0),
        path_len: 20.0,
        mean_soa_m2: None,
        target_departure: None,
        target_departure_places: None,
        soa_curve: Vec::new(),
    }
}

/// An eval --out folder holding these summaries.
fn eval_folder(root: &Path, name: &str, summaries: &[Summary]) -> PathBuf {
    let dir = root.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("summary.json"),
        serde_json::to_string_pretty(summaries).unwrap(),
    )
    .unwrap();
    dir
}

fn table(evals: Vec<PathBuf>, out: Option<PathBuf>) -> anyhow::Result<()> {
    t2e::cli::table::run(TableArgs {
        evals,
        out,
        latex: None,
        cross: false,
    })
}

#[test]
fn table_refuses_two_results_for_one_cell_and_rows_of_mixed_settings() {
    let root = tempfile::tempdir().unwrap();
    let first = eval_folder(
        root.path(),
        "first",
        &[
            summary("small", 500, 500, 90.0),
            summary("medium", 500, 500, 80.0),
        ],
    );
    // The same cell again, from a shorter evaluation: today the later one
    // silently replaced the first.
    let second = eval_folder(root.path(), "second", &[summary("small", 100, 500, 70.0)]);
    let err = err_of(table(vec![first.clone(), second.clone()], None));
    assert!(
        err.contains("two results for one table cell")
            && err.contains(&first.join("summary.json").display().to_string())
            && err.contains(&second.join("summary.json").display().to_string())
            && err.contains("episodes 500 vs 100"),
        "{err}"
    );
    // Another class of the row at another episode length: today merged
    // into one row.
    let longer = eval_folder(root.path(), "longer", &[summary("large", 500, 1000, 60.0)]);
    let err = err_of(table(vec![first.clone(), longer.clone()], None));
    assert!(
        err.contains("one table row")
            && err.contains("episode_length 500 vs 1000")
            && err.contains("longer"),
        "{err}"
    );
    // The same folder twice is one result; --out is written.
    let md = root.path().join("t.md");
    table(
        vec![first.clone(), first.join("summary.json")],
        Some(md.clone()),
    )
    .unwrap();
    let text = std::fs::read_to_string(&md).unwrap();
    assert_eq!(text.matches("| 90.0 [").count(), 1, "{text}");
    assert!(text.contains("| 500 x 500 steps |"), "{text}");
    // An output that is an input is refused before it is overwritten.
    let before = std::fs::read(first.join("summary.json")).unwrap();
    let err = err_of(table(vec![first.clone()], Some(first.join("summary.json"))));
    assert!(
        err.contains("--out") && err.contains("would overwrite it"),
        "{err}"
    );
    assert_eq!(std::fs::read(first.join("summary.json")).unwrap(), before);
    // A setting folder's own summary (one object) reads too; an empty
    // list or nothing for the tables is an error, not an empty table.
    let setting = root.path().join("setting");
    std::fs::create_dir(&setting).unwrap();
    std::fs::write(
        setting.join("summary.json"),
        serde_json::to_string(&summary("large", 500, 500, 50.0)).unwrap(),
    )
    .unwrap();
    table(vec![first.clone(), setting], None).unwrap();
    let empty = eval_folder(root.path(), "empty", &[]);
    assert!(err_of(table(vec![empty], None)).contains("holds no summary"));
    let mut other = summary("shipped", 500, 500, 50.0);
    other.target = "random".into();
    let other = eval_folder(root.path(), "other", &[other]);
    let err = err_of(table(vec![other.clone()], None));
    assert!(
        err.contains("belongs in the paper's tables") && err.contains("--cross"),
        "{err}"
    );
    // Against a learned target, --cross lays out Table V: refused on maps
    // other than the classes, and never as LaTeX (it is Markdown only).
    let cross = |evals: Vec<PathBuf>, out: Option<PathBuf>, latex: Option<PathBuf>| {
        t2e::cli::table::run(TableArgs {
            evals,
            out,
            latex,
            cross: true,
        })
    };
    assert!(err_of(cross(vec![other], None, None)).contains("none of the 1 summaries"));
    let mut learned = summary("medium", 500, 500, 40.0);
    learned.target = "ckpt:runs/league/target".into();
    let learned = eval_folder(root.path(), "learned", &[learned]);
    let md = root.path().join("v.md");
    let err = err_of(cross(
        vec![learned.clone()],
        None,
        Some(root.path().join("v.tex")),
    ));
    assert!(err.contains("Markdown only"), "{err}");
    assert!(!root.path().join("v.tex").exists());
    cross(vec![first, learned], Some(md.clone()), None).unwrap();
    let text = std::fs::read_to_string(&md).unwrap();
    assert!(
        text.contains("| vs rule-based | vs ckpt:runs/league/target |"),
        "{text}"
    );
    // The rule-based column pools small (90.0) and medium (80.0): 85.0.
    assert!(
        text.contains(" | 85.0 [") && text.contains(" | 40.0 ["),
        "{text}"
    );
}

fn tiny_run(dir: &Path) -> PathBuf {
    tch::set_num_threads(1);
    let cfg = common::tiny_train_config("inputs", t2e_core::protocol::Protocol::HeldOut, "shipped");
    let maps = catalog::load_prepared("shipped:small").unwrap();
    let mut t = Trainer::new(cfg, maps).unwrap();
    t.iterate().unwrap();
    t.save(dir).unwrap().remove(0)
}

#[test]
fn an_edited_meta_json_of_a_training_checkpoint_is_refused_by_its_manifest() {
    let run = tempfile::tempdir().unwrap();
    let ckpt = tiny_run(run.path());
    let spec = || -> ControllerSpec { format!("ckpt:{}", ckpt.display()).parse().unwrap() };
    let maps = catalog::load_prepared("shipped:small").unwrap();
    let setting = |captors| EvalSetting {
        captors,
        num_captors: 2,
        episodes: 2,
        episode_length: 20,
        soa_every: 0,
        ..EvalSetting::default()
    };
    SettingIdentity::of(&setting(spec()), "shipped:small", &maps).unwrap();
    assert!(
        ckpt.join("SHA256SUMS").is_file(),
        "a training checkpoint carries a manifest"
    );

    // Relabel the protocol by hand: the weights are untouched, so their
    // hashes in meta.json still match, but the rows it labels would lie.
    let meta = ckpt.join("meta.json");
    let text = std::fs::read_to_string(&meta).unwrap();
    assert!(text.contains("\"held-out\""));
    std::fs::write(&meta, text.replace("\"held-out\"", "\"paper\"")).unwrap();
    let err = SettingIdentity::of(&setting(spec()), "shipped:small", &maps)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("meta.json") && err.contains("SHA256SUMS"),
        "{err}"
    );

    // Without the manifest it is refused too, and `seal` names the way.
    std::fs::write(&meta, &text).unwrap();
    std::fs::remove_file(ckpt.join("SHA256SUMS")).unwrap();
    let err = SettingIdentity::of(&setting(spec()), "shipped:small", &maps)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("SHA256SUMS: missing") && err.contains("t2e-league seal"),
        "{err}"
    );
    let o = Command::new(BIN).arg("seal").arg(&ckpt).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    SettingIdentity::of(&setting(spec()), "shipped:small", &maps).unwrap();
}

/// `eval --resume` with another --episodes plays the setting again, in a
/// folder of its own, and says why, naming the old folder and the field.
#[test]
fn eval_resume_says_why_it_plays_a_setting_again() {
    let out = tempfile::tempdir().unwrap();
    let eval = |episodes: &str| {
        Command::new(BIN)
            .args([
                "eval",
                "--captors",
                "heuristic",
                "--target",
                "heuristic",
                "--k",
                "2",
            ])
            .args([
                "--maps",
                "shipped:small",
                "--episodes",
                episodes,
                "--episode-length",
                "20",
            ])
            .args(["--soa-every", "0", "--quiet", "--resume", "--out"])
            .arg(out.path())
            .output()
            .unwrap()
    };
    let first = eval("2");
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    assert!(!String::from_utf8_lossy(&first.stderr).contains("starts again"));
    let again = eval("2");
    assert!(!String::from_utf8_lossy(&again.stderr).contains("starts again"));
    let changed = eval("3");
    let err = String::from_utf8_lossy(&changed.stderr);
    assert!(changed.status.success(), "{err}");
    assert!(
        err.contains("starts again") && err.contains("episodes 2 -> 3"),
        "{err}"
    );
    let old: Vec<_> = std::fs::read_dir(out.path())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    assert_eq!(old.len(), 2, "{old:?}");
    assert!(
        old.iter().any(|p| err.contains(&p.display().to_string())),
        "{err}"
    );
    // A FIFO in place of a finished setting's files is named, never read.
    let newest = old
        .iter()
        .find(|p| !err.contains(&p.display().to_string()))
        .unwrap();
    std::fs::remove_file(newest.join("summary.json")).unwrap();
    assert!(Command::new("mkfifo")
        .arg(newest.join("summary.json"))
        .status()
        .unwrap()
        .success());
    let child = Command::new(BIN)
        .args([
            "eval",
            "--captors",
            "heuristic",
            "--target",
            "heuristic",
            "--k",
            "2",
        ])
        .args([
            "--maps",
            "shipped:small",
            "--episodes",
            "3",
            "--episode-length",
            "20",
        ])
        .args(["--soa-every", "0", "--quiet", "--resume", "--out"])
        .arg(out.path())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let o = common::output_within(child, 60, "eval --resume with a FIFO in a setting folder");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("summary.json is not a regular file"), "{err}");
}

#[test]
fn a_render_killed_while_writing_leaves_the_previous_gif() {
    let dir = tempfile::tempdir().unwrap();
    let gif = dir.path().join("episode.gif");
    let previous = b"GIF89a: the previous render".to_vec();
    std::fs::write(&gif, &previous).unwrap();
    let render = |limit: Option<u32>| {
        let mut cmd = Command::new("sh");
        let ulimit = limit.map_or(String::new(), |kb| format!("ulimit -f {kb}; "));
        cmd.arg("-c")
            .arg(format!("{ulimit}exec \"$0\" \"$@\""))
            .arg(BIN)
            .args(["render", "--maps"])
            .arg(catalog::shipped_dir().join("gen-small-1.png"))
            .args(["--episode-length", "15", "--out"])
            .arg(&gif);
        cmd.output().unwrap()
    };
    // The file-size limit kills the process (SIGXFSZ) while it writes the
    // GIF, as a kill or a full disk would: today the old file was truncated
    // and half of the new one written in its place.
    let out = render(Some(4));
    assert!(!out.status.success(), "{out:?}");
    assert_eq!(
        std::fs::read(&gif).unwrap(),
        previous,
        "the previous GIF was destroyed"
    );
    // The next render replaces it whole and removes the dead temporary.
    let out = render(None);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&gif).unwrap();
    assert!(bytes.starts_with(b"GIF89a") && bytes.ends_with(b";") && bytes.len() > 4096);
    let left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["episode.gif"]);
}

#[test]
fn negative_list_values_reach_our_own_checks() {
    let run = |args: &[&str]| {
        let out = Command::new(BIN).args(args).output().unwrap();
        assert!(!out.status.success(), "{args:?} succeeded");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    for args in [
        &["eval", "--k", "-1"][..],
        &["eval", "--k", "3,-1"],
        &["eval", "--k=-1"],
    ] {
        let err = run(args);
        assert!(
            err.contains("K = -1: the number of captors must be at least 1")
                && !err.contains("unexpected argument"),
            "{args:?}: {err}"
        );
    }
    let err = run(&["eval", "--k", "0"]);
    assert!(
        err.contains("K = 0: the number of captors must be at least 1"),
        "{err}"
    );
    let err = run(&["eval", "--speed-ratio", "-1.2"]);
    assert!(
        err.contains("--speed-ratio -1.2: must be a number in (0, 10]"),
        "{err}"
    );
    let err = run(&["eval", "--maps", "-nowhere"]);
    assert!(err.contains("--maps '-nowhere': not found"), "{err}");
    let err = run(&["render", "--speed-ratio", "-1", "--out", "x.gif"]);
    assert!(
        err.contains("--speed-ratio -1: must be a number in (0, 10]"),
        "{err}"
    );
    let err = run(&["render", "--k", "-2", "--out", "x.gif"]);
    assert!(
        err.contains("-2") && !err.contains("unexpected argument"),
        "{err}"
    );
}

/// `train --for` stops at a wall-clock budget with a final checkpoint, and
/// `--eval-every` evaluates checkpoints in the background into eval.csv and
/// eval.png, the final checkpoint included; bad durations name the option.
#[test]
fn train_for_a_wall_clock_budget_with_periodic_evaluation() {
    let dir = tempfile::tempdir().unwrap();
    let mut cfg =
        common::tiny_train_config("budget", t2e_core::protocol::Protocol::HeldOut, "shipped");
    cfg.total_env_steps = 100_000_000;
    let config = dir.path().join("config.toml");
    std::fs::write(&config, toml::to_string(&cfg).unwrap()).unwrap();
    let run = dir.path().join("run");
    let train = |extra: &[&str]| {
        Command::new(BIN)
            .args(["train", "--config"])
            .arg(&config)
            .arg("--out")
            .arg(&run)
            .args(["--quiet", "--eval-maps", "shipped", "--eval-episodes", "4"])
            .args(["--eval-episode-length", "30"])
            .args(extra)
            .env("RAYON_NUM_THREADS", "1")
            .env("OMP_NUM_THREADS", "1")
            .output()
            .unwrap()
    };
    for (option, value) in [
        ("--for", "0"),
        ("--for", "-5m"),
        ("--for", "soon"),
        ("--eval-every", "0"),
    ] {
        let out = train(&[option, value]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(option) && err.contains(value),
            "{option} {value}: {err}"
        );
        assert!(
            !run.join("state.json").exists(),
            "{option} {value}: refused before training"
        );
    }
    let out = train(&["--for", "6s", "--eval-every", "2s"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("out of time (--for)"), "{stdout}");
    let state: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("state.json")).unwrap()).unwrap();
    let final_steps = state["env_steps"].as_u64().unwrap();
    assert!(final_steps > 0 && final_steps < cfg.total_env_steps);
    let mut reader = csv::Reader::from_path(run.join("eval.csv")).unwrap();
    let rows: Vec<t2e_learners::learn::train::periodic_eval::EvalRow> =
        reader.deserialize().collect::<Result<_, _>>().unwrap();
    assert!(rows.len() >= 2, "{rows:?}");
    for pair in rows.windows(2) {
        assert!(pair[0].env_steps < pair[1].env_steps && pair[0].wall_s <= pair[1].wall_s);
    }
    for r in &rows {
        assert_eq!(
            (
                r.side.as_str(),
                r.maps.as_str(),
                r.episodes,
                r.episode_length
            ),
            ("captors", "shipped", 4, 30)
        );
        assert!(
            0.0 <= r.sr_low && r.sr_low <= r.sr && r.sr <= r.sr_high && r.sr_high <= 100.0,
            "{r:?}"
        );
        assert!(
            r.wall_s > 0.0 && r.wall_s < 7.0 && (0.0..=30.0).contains(&r.time),
            "{r:?}"
        );
    }
    assert_eq!(
        rows.last().unwrap().env_steps,
        final_steps,
        "the final checkpoint is evaluated too"
    );
    assert!(run.join("eval.png").exists());
}

// ---- The league verbs: where the league is, --pool, --watch ----------------

/// The tiny league's config, as a league stores it.
fn stored_config() -> String {
    let cfg = league::rules::config::LeagueConfig::parse(common::league::TINY_LEAGUE).unwrap();
    toml::to_string_pretty(&cfg).unwrap()
}

/// A league store made by hand (the tiny league's config and an identity,
/// no players): enough for `status`, and far cheaper than running one.
fn league_store(store: &league::store::StoreUrl) {
    let s = league::store::Store::open(store).unwrap();
    s.config_once(&stored_config()).unwrap();
    s.set_league_id_once("0123456789abcdef").unwrap();
}

/// A league folder at `root/rel`, as `run` leaves one (league.db and
/// config.toml in it).
fn league_folder(root: &Path, rel: &str) -> PathBuf {
    let dir = root.join(rel);
    std::fs::create_dir_all(&dir).unwrap();
    league_store(&league::store::StoreUrl::in_dir(&dir));
    std::fs::write(dir.join("config.toml"), stored_config()).unwrap();
    dir
}

/// `t2e-league ARGS` run in `cwd`: (success, stdout, stderr).
fn t2e_in(cwd: &Path, args: &[&str]) -> (bool, String, String) {
    let out = Command::new(BIN)
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn without_dir_the_league_verbs_find_the_only_league_under_runs_league() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    league_folder(root, "runs/league/kill-test");
    // A folder without a league beside it is not a candidate.
    std::fs::create_dir_all(root.join("runs/league/notes")).unwrap();
    let (ok, out, err) = t2e_in(root, &["status", "--json"]);
    assert!(ok, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(json["league"], "kill-test");
    assert_eq!(json["dir"], "runs/league/kill-test");
    assert!(
        err.contains("league folder: runs/league/kill-test"),
        "{err}"
    );
    // export and exploit look in the same place: they get as far as the player.
    for args in [
        &["export", "nobody", "--out", "x"][..],
        &["exploit", "nobody", "--budget", "1000"],
    ] {
        let (ok, _, err) = t2e_in(root, args);
        assert!(!ok, "{args:?} succeeded");
        assert!(
            err.contains("league folder: runs/league/kill-test")
                && err.contains("nobody")
                && !err.contains("holds no league"),
            "{args:?}: {err}"
        );
    }
    // An explicit --dir wins, and says nothing of the search.
    let (ok, _, err) = t2e_in(root, &["status", "--dir", "runs/league/kill-test"]);
    assert!(ok && !err.contains("league folder:"), "{err}");
}

#[test]
fn without_dir_several_leagues_or_none_are_listed_and_dir_asked_for() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let (ok, _, err) = t2e_in(root, &["status"]);
    assert!(
        !ok && err.contains("no runs/league/ folder") && err.contains("--dir"),
        "{err}"
    );
    std::fs::create_dir_all(root.join("runs/league/notes")).unwrap();
    let (ok, _, err) = t2e_in(root, &["status"]);
    assert!(
        !ok && err.contains("found only: runs/league/notes") && err.contains("--dir"),
        "{err}"
    );
    league_folder(root, "runs/league/a");
    league_folder(root, "runs/league/b");
    for args in [
        &["status"][..],
        &["export", "captors-main", "--out", "x"],
        &["exploit", "target-main", "--budget", "1000"],
    ] {
        let (ok, _, err) = t2e_in(root, args);
        assert!(
            !ok && err.contains("holds 2 league folders: runs/league/a, runs/league/b")
                && err.contains("--dir"),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn status_watch_takes_a_duration_as_for_does() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let tmp = tempfile::tempdir().unwrap();
    let dir = league_folder(tmp.path(), "league");
    let d = dir.to_str().unwrap();
    let mut child = Command::new(BIN)
        .args(["status", "--dir", d, "--watch", "5s"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The first report comes at once; the next one 5 s later.
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines().map_while(Result::ok) {
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    let mut seen = false;
    while let Ok(line) = rx.recv_timeout(std::time::Duration::from_secs(60)) {
        if line.contains("league kill-test") {
            seen = true;
            break;
        }
    }
    let still_running = child.try_wait().unwrap().is_none();
    child.kill().ok();
    let out = child.wait_with_output().unwrap();
    assert!(
        seen && still_running,
        "status --watch 5s: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    for (watch, says) in [
        ("0.2s", "--watch 0.2s: must be at least 0.5s"),
        ("5x", "--watch 5x: unknown unit 'x'"),
        ("soon", "--watch soon: expected a duration"),
    ] {
        let (ok, _, err) = t2e_in(tmp.path(), &["status", "--dir", d, "--watch", watch]);
        assert!(!ok && err.contains(says), "--watch {watch}: {err}");
    }
}

#[test]
fn with_store_status_takes_the_shared_pool_as_pool_like_export() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    // A store that is not league.db in a league folder: a SQLite file.
    let db = root.join("shared.db");
    league_store(&league::store::StoreUrl::Sqlite(db.clone()));
    let pool = root.join("pool");
    std::fs::create_dir_all(&pool).unwrap();
    let (db, pool) = (db.to_str().unwrap(), pool.to_str().unwrap());
    let (ok, out, err) = t2e_in(root, &["status", "--store", db, "--pool", pool, "--json"]);
    assert!(ok, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(json["league"], "kill-test");
    assert_eq!(json["dir"], pool);
    // Without --pool the report comes from the store alone.
    let (ok, _, err) = t2e_in(root, &["status", "--store", db]);
    assert!(ok, "{err}");
    // --dir is the league folder, never the pool.
    let (ok, _, err) = t2e_in(root, &["status", "--store", db, "--dir", pool]);
    assert!(!ok && err.contains("--pool DIR"), "{err}");
    // exploit and export need the pool, as --pool.
    for args in [
        &["exploit", "target-main", "--store", db, "--budget", "1000"][..],
        &["export", "target-main", "--store", db, "--out", "x"],
    ] {
        let (ok, _, err) = t2e_in(root, args);
        assert!(!ok && err.contains("give --pool DIR"), "{args:?}: {err}");
    }
    // --pool goes with --store.
    let (ok, _, err) = t2e_in(root, &["status", "--pool", pool]);
    assert!(!ok && err.contains("--pool goes with --store"), "{err}");
}

#[test]
fn a_file_as_pool_and_seats_out_of_range_are_named() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    let file = root.join("not-a-folder");
    std::fs::write(&file, "x").unwrap();
    let f = file.to_str().unwrap();
    let db = root.join("s.db");
    let db = db.to_str().unwrap();
    let config = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/league-default.toml");
    let (ok, _, err) = t2e_in(
        root,
        &[
            "run",
            "--config",
            config.to_str().unwrap(),
            "--store",
            db,
            "--pool",
            f,
        ],
    );
    assert!(
        !ok && err.contains("a file, not a folder") && err.contains(f),
        "{err}"
    );
    let (ok, _, err) = t2e_in(root, &["worker", "--store", db, "--pool", f, "--dir", "w"]);
    assert!(!ok && err.contains("a file, not a folder"), "{err}");
    for (seats, says) in [
        ("-1", "--seats -1: a worker runs 1 to 256"),
        ("0", "--seats 0: a worker runs"),
        ("257", "--seats 257: a worker runs"),
        ("two", "--seats two: not a whole number of seats"),
    ] {
        let (ok, _, err) = t2e_in(
            root,
            &[
                "worker", "--store", db, "--pool", "p", "--dir", "w", "--seats", seats,
            ],
        );
        assert!(!ok && err.contains(says), "--seats {seats}: {err}");
    }
    assert!(
        !root.join("w").exists() && !root.join("p").exists(),
        "nothing created"
    );
    assert!(!Path::new(db).exists(), "no store created");
}

#[test]
fn log_lines_are_plain_text_or_one_json_object_each() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path();
    // Text: the message as it reads, an error marked as one.
    let (ok, _, err) = t2e_in(root, &["train", "--config", "missing.toml"]);
    assert!(!ok);
    assert!(
        err.starts_with("error: missing.toml: cannot read") && err.lines().count() == 1,
        "{err}"
    );
    // JSON, by flag or inherited through T2E_LOG_FORMAT as a league's
    // processes inherit it: every line one object with a level and a message.
    let eval = [
        "eval",
        "--maps",
        "shipped",
        "--episodes",
        "2",
        "--episode-length",
        "20",
        "--quiet",
        "--out",
        "out",
    ];
    let by_flag: Vec<&str> = ["--log-format", "json"].into_iter().chain(eval).collect();
    let (ok, _, err) = t2e_in(root, &by_flag);
    assert!(ok, "{err}");
    let inherited = Command::new(BIN)
        .args(["train", "--config", "missing.toml"])
        .env("T2E_LOG_FORMAT", "json")
        .current_dir(root)
        .output()
        .unwrap();
    assert!(!inherited.status.success());
    let inherited = String::from_utf8_lossy(&inherited.stderr).into_owned();
    let mut levels = Vec::new();
    for line in err.lines().chain(inherited.lines()) {
        let v: serde_json::Value =
            serde_json::from_str(line).unwrap_or_else(|e| panic!("not JSON ({e}): {line}"));
        levels.push((
            v["level"].as_str().unwrap().to_string(),
            v["fields"]["message"].as_str().unwrap().to_string(),
        ));
    }
    assert!(
        levels.contains(&("INFO".into(), "wrote out".into())),
        "{levels:?}"
    );
    assert!(
        levels
            .iter()
            .any(|(l, m)| l == "ERROR" && m.starts_with("missing.toml: cannot read")),
        "{levels:?}"
    );
    let (ok, _, err) = t2e_in(root, &["--log-format", "xml", "status"]);
    assert!(
        !ok && err.contains("'xml'") && err.contains("text, json"),
        "{err}"
    );
}
