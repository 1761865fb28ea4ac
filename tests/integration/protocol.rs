//! The two protocols (paper: train and test on Gibson; held-out: train on
//! other maps, test on Gibson): a config must name one, the training maps
//! must fit it, and the protocol travels with the checkpoint into every eval
//! table, so no figure can be read under the wrong one.

use crate::common;

use std::sync::Arc;
use t2e_learners::controllers::ControllerSpec;

use t2e_core::map::catalog;
use t2e_learners::eval::{self, EvalSetting};
use t2e_learners::learn::train::{TrainConfig, Trainer};
use t2e_learners::nn::checkpoint::read_meta;

use t2e_core::protocol::Protocol;

fn tiny(protocol: Protocol, maps: &str) -> TrainConfig {
    common::tiny_train_config("protocol", protocol, maps)
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
        league::rules::config::LeagueConfig::load(&league).unwrap_err()
    );
    assert!(
        err.contains("league.toml") && err.contains("protocol: missing"),
        "{err}"
    );
    let stored = league::rules::config::LeagueConfig::load_stored(&league).unwrap();
    assert_eq!(stored.protocol, Protocol::HeldOut);
}

/// The Gibson folder, or None (after a note) when it is absent outside CI.
fn gibson_or_skip() -> Option<std::path::PathBuf> {
    match catalog::gibson_dir() {
        Some(dir) => Some(dir),
        None => {
            assert!(
                std::env::var_os("CI").is_none(),
                "Gibson maps missing in CI"
            );
            eprintln!("note: Gibson maps not found (../shared/maps/gibson or $T2E_GIBSON_DIR); test skipped");
            None
        }
    }
}

/// Edited copies of a test map's image, as a user might make them: (name,
/// image). Every one keeps the map square, and each has another content
/// hash than the original.
fn edited_copies(img: &image::GrayImage) -> Vec<(&'static str, image::GrayImage)> {
    use image::imageops;
    let pad = |img: &image::GrayImage, left: u32, top: u32, extra: u32| {
        let mut out = image::GrayImage::new(img.width() + extra, img.height() + extra);
        imageops::replace(&mut out, img, left as i64, top as i64);
        out
    };
    // A free pixel that the loader samples, near the middle of the free space.
    let free_sampled = |img: &image::GrayImage| {
        let (w, h) = img.dimensions();
        let (cx, cy) = (w / 2, h / 2);
        (0..w / 5)
            .flat_map(|i| (0..h / 5).map(move |j| (5 * i + 2, 5 * j + 2)))
            .filter(|&(x, y)| x < w && y < h && img.get_pixel(x, y).0[0] == 255)
            .min_by_key(|&(x, y)| (x as i64 - cx as i64).pow(2) + (y as i64 - cy as i64).pow(2))
            .unwrap()
    };
    let mut one_pixel = img.clone();
    let (x, y) = free_sampled(img);
    one_pixel.put_pixel(x, y, image::Luma([0]));
    // One sampled pixel freed in a far corner: an island that moves any
    // bounding box of the free cells to the corner.
    let mut far_pixel = img.clone();
    far_pixel.put_pixel(2, 2, image::Luma([255]));
    let mut combined = pad(
        &imageops::rotate90(&imageops::flip_horizontal(img)),
        43,
        17,
        60,
    );
    let (x, y) = free_sampled(&combined);
    combined.put_pixel(x, y, image::Luma([0]));
    vec![
        ("mirror", imageops::flip_horizontal(img)),
        ("flip", imageops::flip_vertical(img)),
        ("rot90", imageops::rotate90(img)),
        ("rot180", imageops::rotate180(img)),
        ("rot270", imageops::rotate270(img)),
        (
            "transpose",
            imageops::flip_horizontal(&imageops::rotate90(img)),
        ),
        ("pad40", pad(img, 40, 40, 80)),
        ("shift3", pad(img, 3, 3, 3)),
        ("one-pixel", one_pixel),
        ("far-pixel", far_pixel),
        ("combined", combined),
    ]
}

#[test]
fn near_copies_of_a_test_map_are_refused_under_both_protocols() {
    let Some(gibson) = gibson_or_skip() else {
        return;
    };
    let name = "Avonia_floor_trav_0_v3";
    let img = image::open(gibson.join(format!("{name}.png")))
        .unwrap()
        .to_luma8();
    let dir = tempfile::tempdir().unwrap();
    let original =
        catalog::load_prepared(gibson.join(format!("{name}.png")).to_str().unwrap()).unwrap();
    for (edit, copy) in edited_copies(&img) {
        let path = dir.path().join(format!("my-{edit}.png"));
        copy.save(&path).unwrap();
        let maps = catalog::load_prepared(path.to_str().unwrap()).unwrap();
        assert_ne!(
            maps[0].grid.content_hash(),
            original[0].grid.content_hash(),
            "{edit}"
        );
        let err = Protocol::HeldOut
            .check_training_maps("mine", &maps)
            .expect_err(edit)
            .to_string();
        assert!(
            err.contains(&format!("map 'my-{edit}' is a near-copy of the Gibson test map {name} (medium) at similarity "))
                && err.contains("maps = \"mine\""),
            "{edit}: {err}"
        );
        // Paper trains on the 26 maps unmodified, so no edited copy either.
        let err = Protocol::Paper
            .check_training_maps("mine", &maps)
            .expect_err(edit)
            .to_string();
        assert!(
            err.contains("not one of the 26 Gibson maps but a near-copy of the Gibson test map Avonia_floor_trav_0_v3"),
            "{edit}: {err}"
        );
    }
    // The map itself under another name: the test set by its hash; paper takes it.
    let renamed = dir.path().join("renamed.png");
    std::fs::copy(gibson.join(format!("{name}.png")), &renamed).unwrap();
    let maps = catalog::load_prepared(renamed.to_str().unwrap()).unwrap();
    let err = Protocol::HeldOut
        .check_training_maps("r", &maps)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("is the Gibson test map Avonia_floor_trav_0_v3 (medium"),
        "{err}"
    );
    Protocol::Paper.check_training_maps("r", &maps).unwrap();
    // A folder mixing good maps and a copy: refused, naming the copy.
    let mixed = tempfile::tempdir().unwrap();
    for f in ["gen-small-1.png", "gen-large-2.png"] {
        std::fs::copy(catalog::shipped_dir().join(f), mixed.path().join(f)).unwrap();
    }
    edited_copies(&img)[2]
        .1
        .save(mixed.path().join("zz-rot.png"))
        .unwrap();
    let maps = catalog::load_prepared(mixed.path().to_str().unwrap()).unwrap();
    let err = Protocol::HeldOut
        .check_training_maps("mixed", &maps)
        .unwrap_err()
        .to_string();
    assert!(err.contains("map 'zz-rot' is a near-copy"), "{err}");
}

#[test]
fn shipped_and_generated_maps_train_held_out() {
    let shipped = catalog::load_prepared("shipped").unwrap();
    Protocol::HeldOut
        .check_training_maps("shipped", &shipped)
        .unwrap();
    let generated = catalog::load_prepared("generated:20").unwrap();
    // Its speed is a `bench` row, not asserted here: a bound of 1 s
    // failed at 1.17 s with other runs on the cores.
    Protocol::HeldOut
        .check_training_maps("generated:20", &generated)
        .unwrap();
    let err = Protocol::Paper
        .check_training_maps("generated:20", &generated)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("not one of the 26 Gibson maps") && err.contains("and 59 more"),
        "{err}"
    );
}

/// The measurements behind `NEAR_COPY_THRESHOLD`: every edited copy of every
/// Gibson map scores well above it, every shipped and generated:40 map well
/// below it. Prints the numbers (`-- --nocapture`).
#[test]
fn near_copy_margins() {
    use t2e_core::map::testset::{resembled_test_map, NEAR_COPY_THRESHOLD};
    let Some(gibson) = gibson_or_skip() else {
        return;
    };
    let mut lowest: std::collections::BTreeMap<&str, (f64, String)> = Default::default();
    for entry in catalog::list_dir(&gibson).unwrap() {
        let img = image::open(&entry.path).unwrap().to_luma8();
        for (edit, copy) in edited_copies(&img) {
            let grid = t2e_core::map::load::grid_from_pixels("copy", &copy).unwrap();
            let r = resembled_test_map(&grid, 0.0).unwrap();
            assert_eq!(r.name, entry.name, "{edit} of {}: {r}", entry.name);
            let low = lowest.entry(edit).or_insert((f64::MAX, String::new()));
            if r.similarity < low.0 {
                *low = (r.similarity, format!("{}: {r}", entry.name));
            }
        }
    }
    let mut others = (0.0, String::new(), String::new());
    let mut highest_iou = (0.0, String::new());
    let generated = catalog::load_prepared("generated:40").unwrap();
    let shipped = catalog::load_prepared("shipped").unwrap();
    for m in generated.iter().chain(shipped.iter()) {
        if let Some(r) = resembled_test_map(&m.grid, 0.0) {
            if r.similarity > others.0 {
                others = (r.similarity, m.grid.name.clone(), r.to_string());
            }
            if r.free_iou > highest_iou.0 {
                highest_iou = (r.free_iou, format!("{}: {r}", m.grid.name));
            }
        }
    }
    for (edit, (s, map)) in &lowest {
        eprintln!("lowest similarity of {edit:>9} copies: {s:.3} ({map})");
    }
    eprintln!(
        "highest similarity of a shipped or generated:40 map: {:.3} ({} to {})",
        others.0, others.1, others.2
    );
    eprintln!(
        "highest free space IoU of those: {:.3} ({})",
        highest_iou.0, highest_iou.1
    );
    let copies_min = lowest.values().map(|v| v.0).fold(f64::MAX, f64::min);
    assert!(copies_min >= NEAR_COPY_THRESHOLD + 0.1, "{copies_min}");
    assert!(others.0 <= NEAR_COPY_THRESHOLD - 0.1, "{others:?}");
}
