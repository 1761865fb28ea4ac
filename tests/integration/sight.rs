//! Sight (`net.sight`: wall rays and a coarse map of the whole map
//! appended to each robot's vector, not in the paper): the env writes them
//! after the spec's numbers, a network
//! reads them, a checkpoint carries them in meta.json and sees with them
//! in any env, and whatever would feed a network other inputs than it was
//! trained on is refused by name.

use crate::common;

use std::path::{Path, PathBuf};
use t2e_core::env::{Action, EnvConfig, Side, Sight, TrapEnv, PATCH_LEN};
use t2e_core::map::catalog;
use t2e_learners::controllers::ControllerSpec;
use t2e_learners::learn::train::{SideConfig, Trainer};

const RAYS: Sight = Sight::rays(8);
const RAYS_AND_MAP: Sight = Sight {
    wall_rays: 4,
    map_cells: 8,
};

/// A tiny captor team trained one iteration with 8 wall rays.
fn sighted_run(dir: &Path) -> PathBuf {
    sighted_run_with(dir, RAYS)
}

/// A tiny captor team trained one iteration with `sight`.
fn sighted_run_with(dir: &Path, sight: Sight) -> PathBuf {
    tch::set_num_threads(1);
    let mut cfg =
        common::tiny_train_config("sighted", t2e_core::protocol::Protocol::HeldOut, "shipped");
    cfg.captors.net.sight = sight;
    cfg.captors.net.vector_input = t2e_learners::nn::VectorInput::Egocentric;
    let maps = catalog::load_prepared("shipped:small").unwrap();
    let mut t = Trainer::new(cfg, maps).unwrap();
    t.iterate().unwrap();
    t.save(dir).unwrap().remove(0)
}

#[test]
fn rays_follow_the_spec_vector_and_leave_it_as_it_was() {
    let maps = catalog::load_prepared("shipped:small").unwrap();
    let plain_cfg = EnvConfig {
        num_captors: 2,
        ..EnvConfig::default()
    };
    let seen_cfg = EnvConfig {
        sight: RAYS,
        ..plain_cfg.clone()
    };
    assert_eq!(seen_cfg.vector_len(), plain_cfg.vector_len() + 8);
    let mut plain = TrapEnv::new(plain_cfg, maps.clone()).unwrap();
    let mut seen = TrapEnv::new(seen_cfg, maps).unwrap();
    let a = plain.reset(7).unwrap();
    let b = seen.reset(7).unwrap();
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.vector[..], y.vector[..15]);
        assert_eq!(x.patch, y.patch);
        assert!(y.vector[15..].iter().all(|&r| r > 0.0 && r <= 1.0), "{y:?}");
    }
    // The robots differ in place and heading, so do their rays.
    assert_ne!(b[0].vector[15..], b[2].vector[15..]);
    // Written with another sight than the env's, the spec part is the same.
    let mut v = vec![0f32; 15 + 4];
    let mut p = vec![0u8; PATCH_LEN];
    plain.write_observation_with(Sight::rays(4), 0, &mut v, &mut p);
    assert_eq!(v[..15], a[0].vector[..]);
    // Ray 0 is straight ahead: 8 rays' first and 4 rays' first agree.
    assert_eq!(v[15], b[0].vector[15]);
}

#[test]
fn the_coarse_map_follows_the_rays_and_shows_every_robot() {
    let maps = catalog::load_prepared("shipped:small").unwrap();
    let cfg = EnvConfig {
        num_captors: 2,
        sight: RAYS_AND_MAP,
        ..EnvConfig::default()
    };
    assert_eq!(cfg.vector_len(), 15 + 4 + 4 * 64);
    let mut env = TrapEnv::new(cfg, maps).unwrap();
    let obs = env.reset(7).unwrap();
    let cells = 64;
    for (i, o) in obs.iter().enumerate() {
        let map = &o.vector[19..];
        let (walls, rest) = map.split_at(cells);
        let (captors, rest) = rest.split_at(cells);
        let (target, me) = rest.split_at(cells);
        // Every robot stands in a cell that is not all wall.
        assert_eq!(captors.iter().sum::<f32>(), 2.0);
        assert_eq!(target.iter().sum::<f32>(), 1.0);
        assert_eq!(me.iter().sum::<f32>(), 1.0);
        let mine = me.iter().position(|&x| x == 1.0).unwrap();
        assert!(walls[mine] < 1.0, "robot {i} in a solid cell");
        if i == 2 {
            assert_eq!(target[mine], 1.0);
        } else {
            assert!(captors[mine] >= 1.0);
        }
        // Walls and robots are shared; only "self" differs between robots.
        assert_eq!(
            obs[0].vector[19..19 + 3 * cells],
            o.vector[19..19 + 3 * cells]
        );
    }
}

#[test]
fn a_checkpoint_with_a_map_records_it_and_is_refused_where_the_env_lacks_it() {
    let run = tempfile::tempdir().unwrap();
    let ckpt = sighted_run_with(run.path(), RAYS_AND_MAP);
    let meta = t2e_learners::nn::checkpoint::read_meta(&ckpt).unwrap();
    assert_eq!(meta.net.sight, RAYS_AND_MAP);
    assert_eq!(meta.vector_len(), 15 + 4 + 256);
    let text = std::fs::read_to_string(ckpt.join("meta.json")).unwrap();
    assert!(text.contains("\"map_cells\": 8"), "{text}");
    let rays_only = EnvConfig {
        num_captors: 2,
        sight: Sight::rays(4),
        ..EnvConfig::default()
    };
    let err = meta
        .check_reads(Side::Captors, &rays_only)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("rays4+map8") && err.contains("net.sight") && err.contains("rays4"),
        "{err}"
    );
    // As a controller it writes its own inputs, map included, in an env
    // that has none.
    let spec: ControllerSpec = format!("ckpt:{}", ckpt.display()).parse().unwrap();
    let plain = EnvConfig {
        num_captors: 2,
        ..EnvConfig::default()
    };
    spec.check(Side::Captors, &plain).unwrap();
    let maps = catalog::load_prepared("shipped:small").unwrap();
    let mut env = TrapEnv::new(plain, maps).unwrap();
    env.reset(3).unwrap();
    let mut c = spec.build(Side::Captors).unwrap();
    c.reset(&env, 3);
    let mut out = [Action::Stop; 2];
    c.act(&env, Side::Captors, &mut out);
}

#[test]
fn a_sighted_checkpoint_records_its_rays_and_sees_with_them_in_any_env() {
    let run = tempfile::tempdir().unwrap();
    let ckpt = sighted_run(run.path());
    let meta = t2e_learners::nn::checkpoint::read_meta(&ckpt).unwrap();
    assert_eq!(meta.net.sight, RAYS);
    assert_eq!(meta.vector_len(), 15 + 8);
    let text = std::fs::read_to_string(ckpt.join("meta.json")).unwrap();
    assert!(text.contains("\"wall_rays\": 8"), "{text}");

    // As a controller it writes its own inputs: it plays in an env without
    // sight, and its actions there are those it takes in an env with it.
    let spec: ControllerSpec = format!("ckpt:{}", ckpt.display()).parse().unwrap();
    let maps = catalog::load_prepared("shipped:small").unwrap();
    let plain_cfg = EnvConfig {
        num_captors: 2,
        ..EnvConfig::default()
    };
    spec.check(Side::Captors, &plain_cfg).unwrap();
    let play = |cfg: EnvConfig| -> Vec<Action> {
        let mut env = TrapEnv::new(cfg, maps.clone()).unwrap();
        env.reset(3).unwrap();
        let mut c = spec.build(Side::Captors).unwrap();
        c.reset(&env, 3);
        let mut all = Vec::new();
        for _ in 0..20 {
            let mut out = [Action::Stop; 2];
            c.act(&env, Side::Captors, &mut out);
            all.extend(out);
            let mut acts = out.to_vec();
            acts.push(Action::Stop);
            env.step(&acts);
        }
        all
    };
    let sighted_cfg = EnvConfig {
        sight: RAYS,
        ..plain_cfg.clone()
    };
    assert_eq!(play(plain_cfg.clone()), play(sighted_cfg.clone()));

    // Fed an env's vectors as they are (a league opponent), it needs the
    // env's sight to be its own.
    meta.check_reads(Side::Captors, &sighted_cfg).unwrap();
    let err = meta
        .check_reads(Side::Captors, &plain_cfg)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("sight rays8") && err.contains("net.sight") && err.contains("spec"),
        "{err}"
    );
}

#[test]
fn two_learners_or_a_league_with_different_sight_are_refused_by_name() {
    let mut cfg =
        common::tiny_train_config("two", t2e_core::protocol::Protocol::HeldOut, "shipped");
    cfg.captors.net.sight = RAYS;
    cfg.target = SideConfig {
        play: "mappo".parse().unwrap(),
        net: cfg.captors.net.clone(),
        ..SideConfig::default()
    };
    cfg.validate().unwrap();
    assert_eq!(cfg.learning_env().sight, RAYS);
    cfg.target.net.sight = Sight::OFF;
    let err = cfg.validate().unwrap_err().to_string();
    assert!(
        err.contains("captors.net.sight") && err.contains("rays8 against spec"),
        "{err}"
    );

    let league = league::rules::config::LeagueConfig::parse(
        "[captors.net.sight]\nwall_rays = 12\n[target.net.sight]\nwall_rays = 12\n",
    )
    .unwrap();
    assert_eq!(
        league.train_config(Side::Target).learning_env().sight,
        Sight::rays(12)
    );
    let err = league::rules::config::LeagueConfig::parse("[captors.net.sight]\nwall_rays = 12\n")
        .unwrap_err()
        .to_string();
    assert!(err.contains("target.net.sight"), "{err}");
    let err = league::rules::config::LeagueConfig::parse(
        "[captors.net.sight]\nwall_rays = 2\n[target.net.sight]\nwall_rays = 2\n",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("sight.wall_rays"), "{err}");
    let err = league::rules::config::LeagueConfig::parse(
        "[captors.net.sight]\nmap_cells = 64\n[target.net.sight]\nmap_cells = 64\n",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("sight.map_cells"), "{err}");
}

#[test]
fn a_league_with_sight_trains_snapshots_that_carry_it_and_meet_each_other() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = league::run::folder::layout::LeagueDir::new(tmp.path().join("league"));
    let config = tmp.path().join("league.toml");
    let text = common::league::TINY_LEAGUE
        .replace(
            "env_steps_per_learner = 9_600",
            "env_steps_per_learner = 3_200",
        )
        .replace(
            "[target.net]\n",
            "[captors.net.sight]\nwall_rays = 8\n[target.net]\n",
        )
        .replace(
            "[snapshots]\n",
            "[target.net.sight]\nwall_rays = 8\n[snapshots]\n",
        );
    std::fs::write(&config, text).unwrap();
    common::league::run_to_the_end(&dir.root, &config);
    let (matches, _) = common::league::check(&dir);
    assert!(matches > 0, "no match was played");
    let store = league::store::Store::open(&dir.store).unwrap();
    let mut snapshots = 0;
    for p in store.players().unwrap() {
        if let Some((rel, _)) = &p.checkpoint {
            let meta = t2e_learners::nn::checkpoint::read_meta(&dir.root.join(rel)).unwrap();
            assert_eq!(meta.net.sight, RAYS, "{}", p.name);
            snapshots += 1;
        }
    }
    assert!(snapshots >= 2, "{snapshots} snapshots");
}
