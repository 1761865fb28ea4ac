//! Trustworthy results: each test here pins a way the tool once gave a
//! silently wrong number or lost data (eval settings mixed up on resume, a
//! checkpoint deleted before its replacement, NaN training "successfully",
//! weights loaded without a check, degenerate options giving results, test
//! maps trained on, paths leaving their folder, unclear errors).

use crate::common;

use common::{maps, room};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use t2e::cli::bench::BenchArgs;
use t2e::cli::eval::EvalArgs;
use t2e_core::env::{CaptureRule, Side};
use t2e_core::fs::{clean_stale_temporaries, write_dir_atomically, Written};
use t2e_learners::eval::Summary;
use t2e_learners::learn::ppo::{PpoConfig, PpoLearner};
use t2e_learners::learn::rollout::Rollout;
use t2e_learners::learn::train::{TrainConfig, Trainer};
use t2e_learners::nn::checkpoint::read_meta;
use t2e_learners::nn::{NetConfig, PolicySnapshot};

fn eval_args(out: &Path) -> EvalArgs {
    EvalArgs {
        captors: "heuristic".parse().unwrap(),
        target: "heuristic".parse().unwrap(),
        maps: vec!["shipped".into()],
        k: vec![3],
        speed_ratio: vec![1.0],
        episodes: 12,
        episode_length: 150,
        seed: 0,
        capture_rule: CaptureRule::Fast,
        soa_every: 0,
        out: out.to_path_buf(),
        quiet: true,
        resume: false,
    }
}

fn summaries(out: &Path) -> Vec<Summary> {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// Folders of settings under an eval output folder.
fn setting_dirs(out: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(out)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    v.sort();
    v
}

#[test]
fn eval_never_mixes_up_settings() {
    let out = tempfile::tempdir().unwrap();
    let base = eval_args(out.path());
    t2e::cli::eval::run(eval_args(out.path())).unwrap();
    let fast = summaries(out.path())[0].clone();

    // Another exact speed ratio, resumed: a new result, not the 1.0 one.
    let mut args = eval_args(out.path());
    args.speed_ratio = vec![1.04];
    args.resume = true;
    t2e::cli::eval::run(args).unwrap();
    let r104 = summaries(out.path())[0].clone();
    assert_eq!(r104.speed_ratio, 1.04);
    assert!(
        r104.table_row().contains("1.0:1.04"),
        "{}",
        r104.table_row()
    );
    assert_eq!(
        setting_dirs(out.path()).len(),
        2,
        "1.04 got a folder of its own"
    );

    // The strict rule, resumed: its own result.
    let mut args = eval_args(out.path());
    args.capture_rule = CaptureRule::Strict;
    args.resume = true;
    t2e::cli::eval::run(args).unwrap();
    let strict = summaries(out.path())[0].clone();
    assert_eq!(strict.capture_rule, CaptureRule::Strict);
    assert_eq!(setting_dirs(out.path()).len(), 3);
    assert_ne!(
        (strict.sr, strict.time),
        (fast.sr, fast.time),
        "the strict rule must be played, not read back from the fast one"
    );

    // The same setting resumed is reused as it was.
    let mut args = eval_args(out.path());
    args.resume = true;
    t2e::cli::eval::run(args).unwrap();
    assert_eq!(summaries(out.path())[0], fast);

    // Two ratios in one grid: two rows, two folders, each with its own ratio.
    let grid = tempfile::tempdir().unwrap();
    let mut args = eval_args(grid.path());
    args.speed_ratio = vec![1.0, 1.04];
    t2e::cli::eval::run(args).unwrap();
    let rows = summaries(grid.path());
    assert_eq!(
        rows.iter().map(|s| s.speed_ratio).collect::<Vec<_>>(),
        [1.0, 1.04]
    );
    assert_eq!(setting_dirs(grid.path()).len(), 2);
    let table = std::fs::read_to_string(grid.path().join("table.md")).unwrap();
    assert!(
        table.contains("1.0:1.0 |") && table.contains("1.0:1.04 |"),
        "{table}"
    );
    drop(base);
}

#[test]
fn degenerate_options_are_refused() {
    let out = tempfile::tempdir().unwrap();
    let mut args = eval_args(out.path());
    args.episodes = 0;
    let err = t2e::cli::eval::run(args).unwrap_err().to_string();
    assert!(err.contains("--episodes 0"), "{err}");
    assert!(
        !out.path().join("table.md").exists(),
        "no table for no episodes"
    );
    let mut args = eval_args(out.path());
    args.speed_ratio = vec![f64::NAN];
    assert!(t2e::cli::eval::run(args).is_err());
    let mut args = eval_args(out.path());
    args.speed_ratio = vec![1.0, 1.0];
    assert!(t2e::cli::eval::run(args)
        .unwrap_err()
        .to_string()
        .contains("twice"));

    let bench_args = |seconds: f64, planner_model: Option<&str>| BenchArgs {
        maps: Some("shipped".into()),
        seconds,
        envs: 4,
        train: Vec::new(),
        iterations: 1,
        device: None,
        opponents: false,
        store: None,
        threads: 1,
        planner_model: planner_model.map(String::from),
        writers: vec![1],
    };
    for seconds in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = t2e::cli::bench::run(bench_args(seconds, None))
            .unwrap_err()
            .to_string();
        assert!(err.contains("--seconds"), "{seconds}: {err}");
    }
    // A planner model that is not there, or not a captor team, is refused
    // before any table is timed, by the flag's name.
    for (team, why) in [("ckpt:/no/such/run", "no/such/run"), ("lookahead:5", "")] {
        let args = bench_args(0.05, Some(team));
        let err = format!("{:#}", t2e::cli::bench::run(args).unwrap_err());
        assert!(
            err.contains("--planner-model") && err.contains(why),
            "{team}: {err}"
        );
    }

    let cfg = TrainConfig {
        total_env_steps: 0,
        ..TrainConfig::default()
    };
    assert!(cfg
        .validate()
        .unwrap_err()
        .to_string()
        .contains("total_env_steps = 0"));
}

#[test]
fn nan_in_a_config_is_an_error_naming_the_field() {
    let dir = tempfile::tempdir().unwrap();
    for (field, text) in [
        (
            "captors.ppo.entropy_coef",
            "[captors]\nplay = \"mappo\"\n[captors.ppo]\nentropy_coef = nan\n",
        ),
        (
            "captors.ppo.huber_delta",
            "[captors]\nplay = \"mappo\"\n[captors.ppo]\nhuber_delta = nan\n",
        ),
        (
            "captors.ppo.lr",
            "[captors]\nplay = \"mappo\"\n[captors.ppo]\nlr = inf\n",
        ),
        (
            "captors.ppo.max_grad_norm",
            "[captors]\nplay = \"mappo\"\n[captors.ppo]\nmax_grad_norm = -1.0\n",
        ),
        (
            "captors.ppo.adam_eps",
            "[captors]\nplay = \"mappo\"\n[captors.ppo]\nadam_eps = nan\n",
        ),
        ("env.target_speed", "[env]\ntarget_speed = nan\n"),
    ] {
        let path = dir.path().join("c.toml");
        std::fs::write(&path, format!("protocol = \"held-out\"\n{text}")).unwrap();
        let err = format!("{:#}", TrainConfig::load(&path).unwrap_err());
        assert!(
            err.contains("c.toml") && err.contains(field),
            "{field}: {err}"
        );
    }
}

/// A small learner and a rollout of random but finite data.
fn learner_and_rollout() -> (PpoLearner, Rollout) {
    use rand::{Rng, SeedableRng};
    let _seed = t2e_learners::nn::seed_torch(0);
    let net = NetConfig {
        hidden: 16,
        conv_channels: [2, 4],
        patch_pool: 4,
        ..Default::default()
    };
    let cfg = PpoConfig {
        epochs: 2,
        ..PpoConfig::default()
    };
    let (steps, rows, vl) = (10, 4, 10);
    let learner = PpoLearner::new(
        &t2e_learners::learn::mappo::KIND,
        cfg,
        net.clone(),
        vl,
        1,
        tch::Device::Cpu,
    );
    let mut ro = Rollout::new(steps, rows, vl, &net, 10);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    for x in ro.vectors.iter_mut() {
        *x = rng.gen_range(-1.0..1.0);
    }
    for x in ro.patches.iter_mut() {
        *x = rng.gen_range(0..2);
    }
    for x in ro.rewards.iter_mut() {
        *x = rng.gen_range(-1.0..1.0);
    }
    for (a, l) in ro.actions.iter_mut().zip(ro.logp.iter_mut()) {
        *a = rng.gen_range(0..5);
        *l = (0.2f32).ln();
    }
    (learner, ro)
}

fn weights(l: &PpoLearner) -> Vec<Vec<f32>> {
    t2e_learners::nn::checkpoint::named_cpu_tensors(&l.actor_vs)
        .into_iter()
        .chain(t2e_learners::nn::checkpoint::named_cpu_tensors(
            &l.critic_vs,
        ))
        .map(|(_, t)| {
            let t = t.flatten(0, -1);
            let mut v = vec![0f32; t.numel()];
            t.copy_data(&mut v, t.numel());
            v
        })
        .collect()
}

#[test]
fn a_non_finite_update_is_undone() {
    use rand::SeedableRng;
    let (mut learner, mut ro) = learner_and_rollout();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2);
    let before = weights(&learner);
    let norm_before = learner.value_norm.clone();
    let steps_before = learner.actor_adam.steps;
    ro.rewards[7] = f32::NAN; // the injected fault
    let err = learner.update(&ro, &mut rng).unwrap_err();
    assert!(err.to_string().contains("non-finite"), "{err}");
    assert_eq!(weights(&learner), before, "weights restored");
    assert_eq!(
        learner.value_norm, norm_before,
        "return statistics restored"
    );
    assert_eq!(learner.actor_adam.steps, steps_before, "Adam restored");
    // Clean data again: the update goes through and changes the weights.
    ro.rewards[7] = 0.5;
    learner.update(&ro, &mut rng).unwrap();
    assert_ne!(weights(&learner), before);
    assert!(weights(&learner).iter().flatten().all(|x| x.is_finite()));
}

fn tiny_config() -> TrainConfig {
    let mut cfg = common::one_captor_against_still("trust", 3);
    cfg.num_envs = 4;
    cfg.rollout_steps = 20;
    cfg.env.episode_length = 30;
    cfg.captors.net = NetConfig {
        hidden: 16,
        conv_channels: [2, 4],
        patch_pool: 4,
        ..Default::default()
    };
    cfg
}

fn tiny_maps() -> Arc<Vec<Arc<t2e_core::map::PreparedMap>>> {
    maps(room(100, 160, 100, 160))
}

#[test]
fn checkpoints_are_never_lost_and_never_silently_replaced() {
    tch::set_num_threads(1);
    let run = tempfile::tempdir().unwrap();
    let mut t = Trainer::new(tiny_config(), tiny_maps()).unwrap();
    t.iterate().unwrap();
    let first = t.save(run.path()).unwrap().remove(0);
    // Re-saving the same state (the end of a finished run, or its resume)
    // leaves the complete checkpoint alone.
    let inode = |p: &Path| std::os::unix::fs::MetadataExt::ino(&std::fs::metadata(p).unwrap());
    let before = inode(&first.join("actor.safetensors"));
    t.save(run.path()).unwrap();
    assert_eq!(
        inode(&first.join("actor.safetensors")),
        before,
        "identical checkpoint rewritten"
    );

    // Replacing a folder with other content swaps it in one step.
    let dir = run.path().join("swap");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(dir.join("a"), "old").unwrap();
    let w = write_dir_atomically(&dir, |tmp| {
        std::fs::write(tmp.join("a"), "new").map_err(anyhow::Error::from)
    })
    .unwrap();
    assert_eq!(w, Written::Replaced);
    assert_eq!(std::fs::read_to_string(dir.join("a")).unwrap(), "new");
    let w = write_dir_atomically(&dir, |tmp| {
        std::fs::write(tmp.join("a"), "new").map_err(anyhow::Error::from)
    })
    .unwrap();
    assert_eq!(w, Written::Unchanged);

    // What a killed process leaves behind is cleaned up; a folder moved
    // aside whose replacement never came is put back.
    let ckpts = run.path().join("checkpoints");
    let dead = 999_999_999u32;
    std::fs::create_dir(ckpts.join(format!(".captors-000000000160.tmp-{dead}"))).unwrap();
    std::fs::write(run.path().join(format!(".state.json.tmp-{dead}")), "{").unwrap();
    let name = first.file_name().unwrap().to_string_lossy().into_owned();
    let aside = ckpts.join(format!(".{name}.old-{dead}"));
    std::fs::rename(&first, &aside).unwrap();
    let mut touched = clean_stale_temporaries(&ckpts).unwrap();
    touched.extend(clean_stale_temporaries(run.path()).unwrap());
    assert_eq!(touched.len(), 3, "{touched:?}");
    assert!(
        first.join("meta.json").is_file(),
        "moved-aside checkpoint restored"
    );
    let left: Vec<_> = std::fs::read_dir(&ckpts)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, std::slice::from_ref(&name));

    // ckpt:RUN plays the checkpoint state.json names, and fails rather than
    // falling back to an older one when that one is gone.
    t.iterate().unwrap();
    let second = t.save(run.path()).unwrap().remove(0);
    let snap = PolicySnapshot::load(run.path(), Side::Captors).unwrap();
    assert_eq!(snap.dir, second);
    std::fs::remove_dir_all(&second).unwrap();
    let err = format!(
        "{:#}",
        PolicySnapshot::load(run.path(), Side::Captors).unwrap_err()
    );
    assert!(
        err.contains("state.json") && err.contains("missing"),
        "{err}"
    );
    let err = format!(
        "{:#}",
        Trainer::resume(tiny_config(), tiny_maps(), run.path())
            .err()
            .unwrap()
    );
    assert!(err.contains("missing"), "{err}");
}

/// A copy of the files of folder `from` in a new folder `to`.
fn copy_folder(from: &Path, to: &Path) -> PathBuf {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
    }
    to.to_path_buf()
}

/// Rewrites `meta.json` of a checkpoint through `edit`, and its manifest
/// after it, as a forger would: what is checked then is what lies past
/// the manifest.
fn edit_meta(dir: &Path, edit: impl FnOnce(&mut serde_json::Value)) {
    let path = dir.join("meta.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut v);
    std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    t2e_learners::nn::checkpoint::write_manifest(dir).unwrap();
}

#[test]
fn weights_are_integrity_checked() {
    tch::set_num_threads(1);
    let run = tempfile::tempdir().unwrap();
    let mut t = Trainer::new(tiny_config(), tiny_maps()).unwrap();
    t.iterate().unwrap();
    let ckpt = t.save(run.path()).unwrap().remove(0);
    let meta = read_meta(&ckpt).unwrap();
    assert_eq!(meta.files.len(), 3, "{:?}", meta.files);
    PolicySnapshot::load(&ckpt, Side::Captors).unwrap();

    // One flipped byte in the middle of the weights.
    let copy = |name: &str| copy_folder(&ckpt, &run.path().join(name));
    let flipped = copy("flipped");
    let file = flipped.join("actor.safetensors");
    let mut bytes = std::fs::read(&file).unwrap();
    let mid = bytes.len() - 40;
    bytes[mid] ^= 0x10;
    std::fs::write(&file, &bytes).unwrap();
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&flipped, Side::Captors).unwrap_err()
    );
    assert!(
        (err.contains("sha256") || err.contains("SHA-256")) && err.contains("actor.safetensors"),
        "{err}"
    );

    // A NaN written into a weight, with the hash updated to match: still refused.
    let poisoned = copy("poisoned");
    let file = poisoned.join("actor.safetensors");
    let tensors = tch::Tensor::read_safetensors(&file).unwrap();
    let _ = tensors[0].1.view(-1).get(0).fill_(f64::NAN);
    tch::Tensor::write_safetensors(&tensors, &file).unwrap();
    let hash = t2e_core::util::sha256_file(&file).unwrap();
    edit_meta(&poisoned, |v| v["files"]["actor.safetensors"] = hash.into());
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&poisoned, Side::Captors).unwrap_err()
    );
    assert!(err.contains("NaN or infinite"), "{err}");

    // An algorithm this build does not know.
    let unknown = copy("unknown");
    edit_meta(&unknown, |v| v["algorithm"] = "dqn".into());
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&unknown, Side::Captors).unwrap_err()
    );
    assert!(err.contains("dqn"), "{err}");

    // A resumed run checks the critic and optimizer files too.
    let critic = ckpt.join("critic.safetensors");
    let mut bytes = std::fs::read(&critic).unwrap();
    let mid = bytes.len() - 8;
    bytes[mid] ^= 1;
    std::fs::write(&critic, &bytes).unwrap();
    let err = format!(
        "{:#}",
        Trainer::resume(tiny_config(), tiny_maps(), run.path())
            .err()
            .unwrap()
    );
    assert!(
        (err.contains("sha256") || err.contains("SHA-256")) && err.contains("critic.safetensors"),
        "{err}"
    );

    // A folder without meta.json says so.
    let bare = run.path().join("bare");
    std::fs::create_dir(&bare).unwrap();
    std::fs::copy(
        ckpt.join("actor.safetensors"),
        bare.join("actor.safetensors"),
    )
    .unwrap();
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&bare, Side::Captors).unwrap_err()
    );
    assert!(err.contains("meta.json"), "{err}");
}

#[test]
fn test_maps_are_recognised_by_content_wherever_they_sit() {
    let Some(gibson) = t2e_core::map::catalog::gibson_dir() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "Gibson maps missing in CI"
        );
        return;
    };
    let copy = tempfile::tempdir().unwrap();
    let src = gibson.join("Kettle_floor_trav_0_v3.png");
    let renamed = copy.path().join("my-own-map.png");
    std::fs::copy(&src, &renamed).unwrap();
    let maps = t2e_core::map::catalog::load_prepared(&renamed.display().to_string()).unwrap();
    let err = Trainer::new(tiny_config(), maps).err().unwrap().to_string();
    assert!(
        err.contains("Kettle_floor_trav_0_v3") && err.contains("test set"),
        "{err}"
    );
}

#[test]
fn extra_maps_are_held_to_the_held_out_rule_and_mixed_by_share() {
    // A copy of a test map is refused as an extra map, whatever it is called.
    if let Some(gibson) = t2e_core::map::catalog::gibson_dir() {
        let copy = tempfile::tempdir().unwrap();
        std::fs::copy(
            gibson.join("Kettle_floor_trav_0_v3.png"),
            copy.path().join("extra.png"),
        )
        .unwrap();
        let mut cfg = tiny_config();
        cfg.extra_maps.maps = copy.path().join("extra.png").display().to_string();
        let err = Trainer::new(cfg, tiny_maps()).err().unwrap().to_string();
        assert!(
            err.starts_with("extra_maps.maps")
                && err.contains("Kettle_floor_trav_0_v3")
                && err.contains("never test maps"),
            "{err}"
        );
    } else {
        assert!(
            std::env::var_os("CI").is_none(),
            "Gibson maps missing in CI"
        );
    }
    // Generated extra maps at a quarter of the episodes: over many episodes
    // about a quarter of the worlds play a map that is not the tiny room.
    let mut cfg = tiny_config();
    cfg.extra_maps.maps = "generated:1:small".into();
    cfg.extra_maps.share = 0.25;
    let own = tiny_maps();
    let own_name = own[0].grid.name.clone();
    let t = Trainer::new(cfg.clone(), own.clone()).unwrap();
    let maps = t.maps();
    let extra = maps.iter().filter(|m| m.grid.name != own_name).count();
    assert_eq!(
        (maps.len(), extra),
        (4, 1),
        "1 own map 3 times, 1 extra once"
    );
    // Off, the list is the protocol's own maps.
    cfg.extra_maps = Default::default();
    assert_eq!(Trainer::new(cfg, own).unwrap().maps().len(), 1);
}

#[test]
fn inputs_that_once_misbehaved_give_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    // A PNG header claiming 20000 x 20000 pixels is refused before decoding.
    let mut png = b"\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR".to_vec();
    png.extend(20000u32.to_be_bytes());
    png.extend(20000u32.to_be_bytes());
    png.extend([8, 0, 0, 0, 0, 0, 0, 0, 0]);
    let huge = dir.path().join("huge.png");
    std::fs::write(&huge, &png).unwrap();
    let err = t2e_core::map::load_png(&huge).unwrap_err().to_string();
    assert!(
        err.contains("huge.png") && err.contains("20000x20000"),
        "{err}"
    );

    // Missing files and folders say "not found".
    for spec in ["nowhere.png", "no-such-folder:small"] {
        let err = format!("{:#}", t2e_core::map::resolve(spec).unwrap_err());
        assert!(err.contains("not found"), "{spec}: {err}");
    }
    let err = format!("{:#}", t2e_core::map::resolve("maps:huge").unwrap_err());
    assert!(err.contains("'huge' is not a size class"), "{err}");

    // A class list that is not UTF-8 is named.
    let bad = dir.path().join("bad");
    std::fs::create_dir(&bad).unwrap();
    std::fs::copy(
        t2e_core::map::catalog::shipped_dir().join("gen-small-1.png"),
        bad.join("a.png"),
    )
    .unwrap();
    std::fs::write(bad.join("manifest.csv"), b"map,split\na,sm\xffall\n").unwrap();
    let err = format!(
        "{:#}",
        t2e_core::map::resolve(&bad.display().to_string()).unwrap_err()
    );
    assert!(
        err.contains("manifest.csv") && err.contains("UTF-8"),
        "{err}"
    );

    // A run name cannot leave runs/.
    let cfg = TrainConfig {
        name: "../elsewhere".into(),
        ..TrainConfig::default()
    };
    assert!(cfg
        .validate()
        .unwrap_err()
        .to_string()
        .starts_with("name = "));

    // render writes GIF data, so the file must be a .gif.
    use clap::Parser;
    let cli = t2e::cli::Cli::parse_from(["t2e-league", "render", "--out", "ep.png"]);
    let t2e::cli::Command::Render(args) = cli.command else {
        unreachable!()
    };
    let err = t2e::cli::render::run(args).unwrap_err().to_string();
    assert!(err.contains(".gif"), "{err}");
}

#[test]
fn defects_an_adversarial_pass_found_are_fixed() {
    // A huge or overflowing number of worlds is refused, not allocated.
    for (envs, steps) in [(100_000_000usize, 10usize), (1_844_674_407_370_955_162, 10)] {
        let cfg = TrainConfig {
            num_envs: envs,
            rollout_steps: steps,
            total_env_steps: 80,
            ..tiny_config()
        };
        assert!(
            cfg.validate()
                .unwrap_err()
                .to_string()
                .starts_with("num_envs"),
            "{envs}"
        );
    }
    let cfg = TrainConfig {
        num_envs: 4096,
        rollout_steps: 100_000,
        ..tiny_config()
    };
    assert!(cfg
        .validate()
        .unwrap_err()
        .to_string()
        .contains("does not fit"));

    // A 1x1 map says it is smaller than a cell.
    let dir = tempfile::tempdir().unwrap();
    let one = dir.path().join("one.png");
    image::GrayImage::from_pixel(1, 1, image::Luma([255]))
        .save(&one)
        .unwrap();
    let err = t2e_core::map::load_png(&one).unwrap_err().to_string();
    assert!(err.contains("smaller than one 0.05 m cell"), "{err}");

    // eval names the file it cannot write.
    let out = dir.path().join("out");
    std::fs::create_dir_all(out.join("table.md")).unwrap();
    let err = format!("{:#}", t2e::cli::eval::run(eval_args(&out)).unwrap_err());
    assert!(err.contains("table.md"), "{err}");

    // eval --resume does not trust a summary whose episodes.csv lost rows.
    let out = dir.path().join("again");
    t2e::cli::eval::run(eval_args(&out)).unwrap();
    let setting = setting_dirs(&out).remove(0);
    let csv = setting.join("episodes.csv");
    let text = std::fs::read_to_string(&csv).unwrap();
    let cut: Vec<&str> = text.lines().take(4).collect();
    std::fs::write(&csv, cut.join("\n") + "\n").unwrap();
    let mut args = eval_args(&out);
    args.resume = true;
    t2e::cli::eval::run(args).unwrap();
    let rows = std::fs::read_to_string(&csv).unwrap().lines().count();
    assert_eq!(
        rows, 13,
        "the setting was played again: header + 12 episodes"
    );

    // maps generate records each map as it goes, and caps --count.
    let gen = dir.path().join("gen");
    t2e::cli::maps::generate_maps(t2e_core::map::SizeClass::Small, 1, 2, &gen).unwrap();
    let manifest = std::fs::read_to_string(gen.join("manifest.csv")).unwrap();
    assert_eq!(manifest.lines().count(), 3, "{manifest}");
    assert!(
        t2e::cli::maps::generate_maps(t2e_core::map::SizeClass::Small, 1, 1_000_000_000, &gen)
            .unwrap_err()
            .to_string()
            .contains("--count")
    );

    // A state.json edited to disagree with its checkpoint is refused.
    tch::set_num_threads(1);
    let run = dir.path().join("run");
    let mut t = Trainer::new(tiny_config(), tiny_maps()).unwrap();
    t.iterate().unwrap();
    t.iterate().unwrap();
    t.save(&run).unwrap();
    let state_path = run.join("state.json");
    let mut state: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&state_path).unwrap()).unwrap();
    state["iteration"] = 1.into();
    state["env_steps"] = 80.into();
    std::fs::write(&state_path, state.to_string()).unwrap();
    let err = format!(
        "{:#}",
        Trainer::resume(tiny_config(), tiny_maps(), &run)
            .err()
            .unwrap()
    );
    assert!(err.contains("changed by hand"), "{err}");
}

#[test]
fn a_reset_learner_is_back_to_its_initial_weights() {
    tch::set_num_threads(1);
    let tmp = tempfile::tempdir().unwrap();
    let mut t = Trainer::new(tiny_config(), tiny_maps()).unwrap();
    let (initial, later, reset) = (
        tmp.path().join("initial"),
        tmp.path().join("later"),
        tmp.path().join("reset"),
    );
    t.side(Side::Captors).unwrap().save(&initial).unwrap();
    t.iterate().unwrap();
    t.side(Side::Captors).unwrap().save(&later).unwrap();
    t.side(Side::Captors).unwrap().reset_to(&initial).unwrap();
    t.side(Side::Captors).unwrap().save(&reset).unwrap();
    let files = |d: &Path| read_meta(d).unwrap().files;
    for f in [
        "actor.safetensors",
        "critic.safetensors",
        "optimizer.safetensors",
    ] {
        assert_ne!(
            files(&initial)[f],
            files(&later)[f],
            "{f}: training changed nothing"
        );
        assert_eq!(files(&initial)[f], files(&reset)[f], "{f}: not restored");
    }
    let steps = read_meta(&reset).unwrap().env_steps;
    assert_eq!(
        steps,
        read_meta(&later).unwrap().env_steps,
        "the step count goes on"
    );
    // Training goes on from there.
    t.iterate().unwrap();
}

/// Every checkpoint folder is verified as an export is: its manifest covers
/// meta.json, an export's player.json names meta.json's side, a folder
/// without a manifest is refused (whether it was a training checkpoint or
/// an export stripped of its marks), and a network reading wall rays must
/// record the rays' range.
#[test]
fn every_checkpoint_is_verified_by_its_manifest_and_its_sides_agree() {
    tch::set_num_threads(1);
    let run = tempfile::tempdir().unwrap();
    let mut t = Trainer::new(tiny_config(), tiny_maps()).unwrap();
    t.iterate().unwrap();
    let ckpt = t.save(run.path()).unwrap().remove(0);
    let manifest = std::fs::read_to_string(ckpt.join("SHA256SUMS")).unwrap();
    for file in ["meta.json", "actor.safetensors", "critic.safetensors"] {
        assert!(manifest.contains(&format!("  {file}\n")), "{manifest}");
    }
    // An export's shape: player.json and the league's config beside the
    // checkpoint's files, all in the manifest.
    let export = copy_folder(&ckpt, &run.path().join("export"));
    std::fs::write(
        export.join("player.json"),
        r#"{"player": "captors-main", "side": "captors"}"#,
    )
    .unwrap();
    std::fs::write(export.join("league-config.toml"), "").unwrap();
    t2e_learners::nn::checkpoint::write_manifest(&export).unwrap();
    PolicySnapshot::load(&export, Side::Captors).unwrap();
    let eval_target = |dir: &Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_t2e-league"))
            .args([
                "eval",
                "--captors",
                "heuristic",
                "--k",
                "2",
                "--maps",
                "shipped:small",
            ])
            .args([
                "--episodes",
                "1",
                "--episode-length",
                "10",
                "--quiet",
                "--out",
            ])
            .arg(run.path().join("eval"))
            .arg("--target")
            .arg(format!("ckpt:{}", dir.display()))
            .output()
            .unwrap()
    };

    // meta.json's side turned to the target, the manifest made again.
    edit_meta(&export, |v| v["side"] = "target".into());
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&export, Side::Target).unwrap_err()
    );
    assert!(
        err.contains("player.json") && err.contains("\"captors\""),
        "{err}"
    );
    let o = eval_target(&export);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("player.json"),
        "{stderr}"
    );

    // The export stripped of its manifest and its marks.
    edit_meta(&export, |v| v["side"] = "captors".into());
    for mark in ["SHA256SUMS", "player.json", "league-config.toml"] {
        std::fs::remove_file(export.join(mark)).unwrap();
    }
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&export, Side::Captors).unwrap_err()
    );
    assert!(err.contains("SHA256SUMS: missing"), "{err}");

    // A training checkpoint's meta.json edited without its manifest.
    let meta = ckpt.join("meta.json");
    let text = std::fs::read_to_string(&meta).unwrap();
    std::fs::write(
        &meta,
        text.replace("\"env_steps\"", "\"env_steps\" ").replacen(
            "\"iteration\": 1",
            "\"iteration\": 7",
            1,
        ),
    )
    .unwrap();
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&ckpt, Side::Captors).unwrap_err()
    );
    assert!(
        err.contains("meta.json") && err.contains("SHA256SUMS"),
        "{err}"
    );
    std::fs::write(&meta, &text).unwrap();
    PolicySnapshot::load(&ckpt, Side::Captors).unwrap();

    // Rays without their range: written when a ray was divided by each
    // map's extent.
    edit_meta(&ckpt, |v| {
        v["net"]["sight"] = serde_json::json!({"wall_rays": 12})
    });
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&ckpt, Side::Captors).unwrap_err()
    );
    assert!(
        err.contains("wall_ray_range_m") && err.contains("16 m"),
        "{err}"
    );
    edit_meta(&ckpt, |v| v["wall_ray_range_m"] = 24.0.into());
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&ckpt, Side::Captors).unwrap_err()
    );
    assert!(err.contains("wall_ray_range_m = 24"), "{err}");
}

/// Faults an adversarial pass found in the manifest's writer and `seal`:
/// a link in the manifest's place is replaced, not written through; a
/// name a manifest line cannot hold is refused; an export's player.json
/// left out of its manifest is refused; a FIFO in a weight's place is
/// called what it is.
#[test]
fn the_manifest_is_written_whole_in_place_and_covers_an_exports_own_files() {
    tch::set_num_threads(1);
    let run = tempfile::tempdir().unwrap();
    let mut t = Trainer::new(tiny_config(), tiny_maps()).unwrap();
    t.iterate().unwrap();
    let ckpt = t.save(run.path()).unwrap().remove(0);
    let copy = |name: &str| copy_folder(&ckpt, &run.path().join(name));
    // A dangling link where the manifest goes: seal refuses, and nothing
    // is written outside the folder.
    let linked = copy("linked");
    std::fs::remove_file(linked.join("SHA256SUMS")).unwrap();
    let outside = run.path().join("outside");
    std::os::unix::fs::symlink(&outside, linked.join("SHA256SUMS")).unwrap();
    let err = t2e_learners::nn::checkpoint::seal(&linked)
        .unwrap_err()
        .to_string();
    assert!(err.contains("not a regular file"), "{err}");
    t2e_learners::nn::checkpoint::write_manifest(&linked).unwrap();
    assert!(
        !outside.exists(),
        "the manifest was written through the link"
    );
    assert!(std::fs::symlink_metadata(linked.join("SHA256SUMS"))
        .unwrap()
        .is_file());
    PolicySnapshot::load(&linked, Side::Captors).unwrap();
    // A name with a line break.
    std::fs::write(linked.join("evil\nname"), b"x").unwrap();
    let err = t2e_learners::nn::checkpoint::write_manifest(&linked)
        .unwrap_err()
        .to_string();
    assert!(err.contains("line break"), "{err}");
    // An export whose player.json is not in its manifest.
    let export = copy("export");
    std::fs::write(export.join("player.json"), r#"{"side": "captors"}"#).unwrap();
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&export, Side::Captors).unwrap_err()
    );
    assert!(
        err.contains("player.json") && err.contains("not listed"),
        "{err}"
    );
    t2e_learners::nn::checkpoint::write_manifest(&export).unwrap();
    PolicySnapshot::load(&export, Side::Captors).unwrap();
    std::fs::write(export.join("player.json"), r#"{"player": 7}"#).unwrap();
    let err = format!(
        "{:#}",
        PolicySnapshot::load(&export, Side::Captors).unwrap_err()
    );
    assert!(err.contains("no string `side`"), "{err}");
    // A FIFO in a weight's place, sealed: named as such, never opened.
    let fifo = copy("fifo");
    std::fs::remove_file(fifo.join("SHA256SUMS")).unwrap();
    std::fs::remove_file(fifo.join("critic.safetensors")).unwrap();
    assert!(std::process::Command::new("mkfifo")
        .arg(fifo.join("critic.safetensors"))
        .status()
        .unwrap()
        .success());
    let err = t2e_learners::nn::checkpoint::seal(&fifo)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("critic.safetensors") && err.contains("not a regular file"),
        "{err}"
    );
    assert!(!fifo.join("SHA256SUMS").exists());
}
