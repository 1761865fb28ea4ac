//! The two protocols (paper: train and test on Gibson; held-out: train on
//! other maps, test on Gibson): a config must name one, the training maps
//! must fit it, and the protocol travels with the checkpoint into every eval
//! table, so no figure can be read under the wrong one.

use std::sync::Arc;
use t2e::controllers::ControllerSpec;
use t2e::env::EnvConfig;
use t2e::eval::{self, EvalSetting};
use t2e::learn::train::{SideConfig, TrainConfig, Trainer};
use t2e::map::catalog;
use t2e::nn::checkpoint::read_meta;
use t2e::nn::NetConfig;
use t2e::protocol::Protocol;

fn tiny(protocol: Protocol, maps: &str) -> TrainConfig {
    TrainConfig {
        name: "protocol".into(),
        seed: 1,
        num_envs: 2,
        rollout_steps: 10,
        total_env_steps: 20,
        device: "cpu".into(),
        protocol,
        maps: maps.into(),
        env: EnvConfig {
            num_captors: 2,
            episode_length: 20,
            ..EnvConfig::default()
        },
        captors: SideConfig {
            play: "mappo".into(),
            net: NetConfig {
                hidden: 8,
                conv_channels: [2, 2],
                patch_pool: 4,
            },
            ..SideConfig::default()
        },
        target: SideConfig {
            play: "heuristic".into(),
            ..SideConfig::default()
        },
        ..TrainConfig::default()
    }
}

#[test]
fn the_protocol_decides_the_training_maps_and_travels_into_the_tables() {
    tch::set_num_threads(1);
    let Some(_) = catalog::gibson_dir() else {
        assert!(
            std::env::var_os("CI").is_none(),
            "Gibson maps missing in CI"
        );
        return;
    };
    let gibson = catalog::load_prepared("gibson").unwrap();
    let shipped = catalog::load_prepared("shipped").unwrap();
    assert_eq!(gibson.len(), 26);

    // Held-out refuses the test maps; paper refuses anything else.
    let err = Trainer::new(tiny(Protocol::HeldOut, "gibson"), gibson.clone())
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("test set") && err.contains("protocol = \"paper\""),
        "{err}"
    );
    let err = Trainer::new(tiny(Protocol::Paper, "shipped"), shipped.clone())
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("not one of the 26 Gibson maps"), "{err}");
    let mixed: Vec<_> = gibson.iter().chain(shipped.iter()).cloned().collect();
    assert!(Trainer::new(tiny(Protocol::Paper, "mixed"), Arc::new(mixed)).is_err());

    // Each trains where it may, and its checkpoint says under which protocol.
    let runs = tempfile::tempdir().unwrap();
    let mut dirs = Vec::new();
    for (protocol, maps, spec) in [
        (Protocol::Paper, gibson.clone(), "gibson"),
        (Protocol::HeldOut, shipped.clone(), "shipped"),
    ] {
        let mut t = Trainer::new(tiny(protocol, spec), maps).unwrap();
        t.iterate().unwrap();
        let dir = t
            .save(&runs.path().join(protocol.name()))
            .unwrap()
            .remove(0);
        assert_eq!(read_meta(&dir).unwrap().protocol, protocol);
        dirs.push(dir);
    }

    // Eval tables carry it: one learned side, both, or none.
    let small = catalog::load_prepared("gibson:small").unwrap();
    let ckpt = |d: &std::path::Path| {
        format!("ckpt:{}", d.display())
            .parse::<ControllerSpec>()
            .unwrap()
    };
    let setting = |captors: ControllerSpec| EvalSetting {
        captors,
        num_captors: 2,
        episodes: 2,
        episode_length: 30,
        soa_every: 0,
        ..EvalSetting::default()
    };
    let (paper, _) = eval::run(&setting(ckpt(&dirs[0])), &small, "small", false).unwrap();
    assert_eq!(paper.protocol, "paper");
    assert!(
        paper.table_row().contains("| paper |"),
        "{}",
        paper.table_row()
    );
    assert!(eval::TABLE_HEADER.contains("| protocol |"));
    let (held_out, _) = eval::run(&setting(ckpt(&dirs[1])), &small, "small", false).unwrap();
    assert_eq!(held_out.protocol, "held-out");
    let (none, _) = eval::run(&setting(ControllerSpec::Heuristic), &small, "small", false).unwrap();
    assert_eq!(none.protocol, "-", "heuristics are trained on no maps");
}

#[test]
fn a_config_file_must_name_its_protocol() {
    let dir = tempfile::tempdir().unwrap();
    let train = dir.path().join("train.toml");
    std::fs::write(&train, "name = \"x\"\nmaps = \"shipped\"\n").unwrap();
    let err = format!("{:#}", TrainConfig::load(&train).unwrap_err());
    assert!(
        err.contains("train.toml") && err.contains("protocol: missing"),
        "{err}"
    );
    std::fs::write(
        &train,
        "name = \"x\"\nprotocol = \"paper\"\nmaps = \"gibson\"\n",
    )
    .unwrap();
    assert_eq!(TrainConfig::load(&train).unwrap().protocol, Protocol::Paper);
    std::fs::write(&train, "name = \"x\"\nprotocol = \"heldout\"\n").unwrap();
    let err = format!("{:#}", TrainConfig::load(&train).unwrap_err());
    assert!(
        err.contains("train.toml") && err.contains("heldout"),
        "{err}"
    );

    // A run folder's own config.toml from before the field reads as held-out.
    std::fs::write(&train, "name = \"x\"\nmaps = \"shipped\"\n").unwrap();
    assert_eq!(
        TrainConfig::load_stored(&train).unwrap().protocol,
        Protocol::HeldOut
    );

    let league = dir.path().join("league.toml");
    std::fs::write(&league, "name = \"l\"\nmaps = \"shipped\"\n").unwrap();
    let err = format!(
        "{:#}",
        t2e::league::config::LeagueConfig::load(&league).unwrap_err()
    );
    assert!(
        err.contains("league.toml") && err.contains("protocol: missing"),
        "{err}"
    );
    let stored = t2e::league::config::LeagueConfig::load_stored(&league).unwrap();
    assert_eq!(stored.protocol, Protocol::HeldOut);
}
