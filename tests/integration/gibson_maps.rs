//! The map facts of spec §1 on the real Gibson test maps (kept outside the
//! project, in ../shared/maps/gibson), and the maps the project ships in maps/.

use std::collections::BTreeMap;
use std::path::PathBuf;
use t2e_core::map::catalog::{gibson_dir, list_dir, shipped_dir};
use t2e_core::map::{Grid, SizeClass};

/// The Gibson folder, or None (after a note) when it is absent outside CI.
fn gibson_or_skip() -> Option<PathBuf> {
    match gibson_dir() {
        Some(dir) => Some(dir),
        None if std::env::var_os("CI").is_some() => {
            panic!("the Gibson maps were not found (../shared/maps/gibson or $T2E_GIBSON_DIR) and CI is set")
        }
        None => {
            eprintln!("note: Gibson maps not found (../shared/maps/gibson or $T2E_GIBSON_DIR); test skipped");
            None
        }
    }
}

fn load_gibson() -> Option<BTreeMap<String, (Grid, Option<SizeClass>)>> {
    let dir = gibson_or_skip()?;
    let entries = list_dir(&dir).unwrap();
    Some(
        entries
            .iter()
            .map(|e| (e.name.clone(), (e.load().unwrap(), e.listed_class)))
            .collect(),
    )
}

fn area_of(maps: &BTreeMap<String, (Grid, Option<SizeClass>)>, name: &str) -> f64 {
    maps.get(name)
        .unwrap_or_else(|| panic!("{name} missing"))
        .0
        .area_m2()
}

#[test]
fn all_26_gibson_maps_load_in_their_listed_class() {
    let Some(maps) = load_gibson() else { return };
    assert_eq!(maps.len(), 26);
    for (name, (grid, listed)) in &maps {
        let listed = listed.unwrap_or_else(|| panic!("{name} is not in splits.csv"));
        assert_eq!(
            grid.size_class(),
            listed,
            "{name}: {:.2} m^2",
            grid.area_m2()
        );
    }
    // One map is 1800 px: a 360x360 grid; the others are padded to 320.
    assert_eq!(maps.values().filter(|(g, _)| g.side() == 360).count(), 1);
}

#[test]
fn gibson_areas_match_the_paper() {
    let Some(maps) = load_gibson() else { return };
    let mean = maps.values().map(|(g, _)| g.area_m2()).sum::<f64>() / maps.len() as f64;
    assert!((mean - 42.52).abs() <= 0.01, "mean area {mean:.4} m^2");
    let kettle = area_of(&maps, "Kettle_floor_trav_0_v3");
    assert!((kettle - 15.7).abs() < 0.05, "Kettle {kettle:.3}");
    let grace = area_of(&maps, "Graceville_floor_trav_0_v3");
    assert!((grace - 74.1).abs() < 0.05, "Graceville {grace:.3}");
    assert_eq!(maps["Graceville_floor_trav_0_v3"].0.free_cells(), 29_649);
    // They are the extremes of the set.
    let (min, max) = maps.values().fold((f64::MAX, 0f64), |(lo, hi), (g, _)| {
        (lo.min(g.area_m2()), hi.max(g.area_m2()))
    });
    assert_eq!((min, max), (kettle, grace));
}

#[derive(serde::Deserialize)]
struct ManifestRow {
    map: String,
    split: SizeClass,
    area_m2: f64,
}

#[test]
fn shipped_maps_match_their_manifest_and_are_connected() {
    let dir = shipped_dir();
    let manifest = dir.join("manifest.csv");
    let mut reader =
        csv::Reader::from_path(&manifest).unwrap_or_else(|e| panic!("{}: {e}", manifest.display()));
    let rows: Vec<ManifestRow> = reader.deserialize().map(|r| r.unwrap()).collect();
    let entries = list_dir(&dir).unwrap();
    assert_eq!(
        entries.len(),
        rows.len(),
        "PNG files and manifest rows differ"
    );
    for class in SizeClass::ALL {
        assert!(
            rows.iter().filter(|r| r.split == class).count() >= 3,
            "fewer than 3 {class} maps shipped"
        );
    }
    for row in &rows {
        let entry = entries
            .iter()
            .find(|e| e.name == row.map)
            .unwrap_or_else(|| panic!("{}.png missing", row.map));
        let mut grid = entry.load().unwrap();
        assert_eq!(
            grid.size_class(),
            row.split,
            "{}: {:.2} m^2",
            row.map,
            grid.area_m2()
        );
        assert_eq!(entry.listed_class, Some(row.split));
        assert!(
            (grid.area_m2() - row.area_m2).abs() < 0.006,
            "{}: {:.3} vs manifest {}",
            row.map,
            grid.area_m2(),
            row.area_m2
        );
        assert_eq!(
            grid.keep_largest_component(),
            0,
            "{}: more than one free component",
            row.map
        );
    }
}

#[test]
fn the_test_set_is_recognised_by_content() {
    let Some(maps) = load_gibson() else { return };
    let mut listed = String::new();
    for (name, (grid, _)) in &maps {
        listed.push_str(&format!("    (\"{name}\", \"{}\"),\n", grid.content_hash()));
    }
    for (name, (grid, _)) in &maps {
        assert_eq!(
            t2e_core::map::testset::gibson_name(grid),
            Some(name.as_str()),
            "{name} is not recognised as a test map; the table should read:\n{listed}"
        );
    }
    // A generated map is not a test map.
    let generated = t2e_core::map::generate::generate(
        1,
        SizeClass::Medium,
        &t2e_core::map::generate::GeneratorConfig::default(),
    );
    assert_eq!(t2e_core::map::testset::gibson_name(&generated), None);
}

/// The fingerprints of the Gibson folder, as `map::testset` embeds them.
fn fingerprint_file(dir: &std::path::Path) -> Vec<u8> {
    use t2e_core::map::fingerprint::{encode, Fingerprint};
    let maps: Vec<_> = list_dir(dir)
        .unwrap()
        .iter()
        .map(|e| (Fingerprint::of(&e.load().unwrap()), e.listed_class))
        .collect();
    encode(&maps)
}

#[test]
fn the_embedded_fingerprints_are_those_of_the_test_maps() {
    let Some(dir) = gibson_or_skip() else { return };
    let file = fingerprint_file(&dir);
    assert!(
        file == t2e_core::map::testset::FINGERPRINTS_FILE,
        "crates/core/src/map/gibson_fingerprints.bin is not the fingerprint of {}: regenerate it with cargo test --release --test integration -- --ignored gibson_maps::write_test_map_fingerprints",
        dir.display()
    );
    let probes = t2e_core::map::testset::test_probes();
    assert_eq!(probes.len(), 26);
    assert!(probes.iter().all(|(_, class)| class.is_some()));
}

/// Writes crates/core/src/map/gibson_fingerprints.bin from the Gibson folder.
#[test]
#[ignore]
fn write_test_map_fingerprints() {
    let dir = gibson_or_skip().expect("the Gibson maps are needed");
    let out = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("crates/core/src/map/gibson_fingerprints.bin");
    let bytes = fingerprint_file(&dir);
    std::fs::write(&out, &bytes).unwrap();
    eprintln!("wrote {} ({} bytes)", out.display(), bytes.len());
}

/// `maps fetch-gibson --from` on a folder laid out as the reference
/// repository (`scene/val/{easy,middle,hard}/`, built here from the Gibson
/// folder by its splits.csv) writes the same 26 maps, byte for byte, with
/// the same classes; a changed map, a map in the wrong class folder and a
/// missing one are refused by name, and nothing is written.
#[test]
fn fetch_gibson_extracts_the_reference_layout() {
    use std::process::Command;
    use t2e_core::map::gibson_source::{read_flat, CLASS_FOLDERS};
    let Some(gibson) = gibson_or_skip() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let checkout = tmp.path().join("T2E");
    let entries = list_dir(&gibson).unwrap();
    assert_eq!(entries.len(), 26);
    let folder_of = |class: SizeClass| CLASS_FOLDERS.iter().find(|(_, c)| *c == class).unwrap().0;
    for e in &entries {
        let dir = checkout
            .join("scene/val")
            .join(folder_of(e.listed_class.unwrap()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::copy(&e.path, dir.join(format!("{}.png", e.name))).unwrap();
    }
    let fetch = |from: &std::path::Path, out: &std::path::Path| {
        Command::new(env!("CARGO_BIN_EXE_t2e-league"))
            .args(["maps", "fetch-gibson", "--from"])
            .arg(from)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap()
    };
    let out = tmp.path().join("maps/gibson");
    let o = fetch(&checkout, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let written = read_flat(&out).unwrap();
    let original = read_flat(&gibson).unwrap();
    assert_eq!(written, original);
    for e in &entries {
        let a = std::fs::read(&e.path).unwrap();
        let b = std::fs::read(out.join(format!("{}.png", e.name))).unwrap();
        assert!(a == b, "{} differs from its source", e.name);
    }
    // A second fetch into the finished folder is a no-op, not an error.
    assert!(fetch(&checkout, &out).status.success());

    // A map moved to another class folder.
    let moved_from = checkout.join("scene/val/hard/Delton_floor_trav_0_v3.png");
    let moved_to = checkout.join("scene/val/easy/Delton_floor_trav_0_v3.png");
    std::fs::rename(&moved_from, &moved_to).unwrap();
    let bad_out = tmp.path().join("bad");
    let o = fetch(&checkout, &bad_out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("Delton_floor_trav_0_v3.png") && err.contains("large"),
        "{err}"
    );
    assert!(!bad_out.exists());
    // Missing.
    std::fs::remove_file(&moved_to).unwrap();
    let o = fetch(&checkout, &bad_out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("Delton_floor_trav_0_v3"),
        "{err}"
    );
    // Changed content: one free pixel of another map painted black.
    let victim = checkout.join("scene/val/middle/Churchton_floor_trav_0_v3.png");
    let mut img = image::open(&victim).unwrap().to_luma8();
    let (w, h) = img.dimensions();
    // A 5 x 5 block inside open floor: it holds one sampled pixel whatever the padding.
    let free = |x: u32, y: u32| img.get_pixel(x, y).0[0] == 255;
    let spot = (10..h - 10)
        .step_by(7)
        .flat_map(|y| (10..w - 10).step_by(7).map(move |x| (x, y)))
        .find(|&(x, y)| (x - 8..=x + 8).all(|i| (y - 8..=y + 8).all(|j| free(i, j))));
    let (sx, sy) = spot.expect("open floor on Churchton");
    for i in sx - 2..=sx + 2 {
        for j in sy - 2..=sy + 2 {
            img.put_pixel(i, j, image::Luma([0]));
        }
    }
    let changed = true;
    assert!(changed);
    img.save(&victim).unwrap();
    std::fs::copy(gibson.join("Delton_floor_trav_0_v3.png"), &moved_from).unwrap();
    let o = fetch(&checkout, &bad_out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && err.contains("Churchton_floor_trav_0_v3.png")
            && err.contains("SHA-256"),
        "{err}"
    );
    assert!(!bad_out.exists());
}

/// Where `maps fetch-gibson` cannot write, or reads something that is no
/// map file, it says so once, names the folder the user gave, and leaves
/// nothing behind (no hidden `.NAME.partial-<pid>/`); a FIFO in a map's
/// place is refused without being opened, so the command cannot block.
#[test]
fn fetch_gibson_refuses_bad_folders_and_fifos_by_name_and_leaves_nothing() {
    use std::process::Command;
    use t2e_core::map::gibson_source::CLASS_FOLDERS;
    let Some(gibson) = gibson_or_skip() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let checkout = tmp.path().join("T2E");
    let folder_of = |class: SizeClass| CLASS_FOLDERS.iter().find(|(_, c)| *c == class).unwrap().0;
    for e in &list_dir(&gibson).unwrap() {
        let dir = checkout
            .join("scene/val")
            .join(folder_of(e.listed_class.unwrap()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::copy(&e.path, dir.join(format!("{}.png", e.name))).unwrap();
    }
    let fetch = |out: &std::path::Path| {
        let o = Command::new(env!("CARGO_BIN_EXE_t2e-league"))
            .args(["maps", "fetch-gibson", "--from"])
            .arg(&checkout)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap();
        assert!(!o.status.success(), "{} was accepted", out.display());
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let leftovers = |dir: &std::path::Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains("partial"))
            .collect()
    };
    let once = |err: &str, text: &str| {
        assert_eq!(
            err.matches(text).count(),
            1,
            "{text:?} not said exactly once: {err}"
        );
    };
    // A dangling symbolic link.
    let link = tmp.path().join("LINK");
    std::os::unix::fs::symlink(tmp.path().join("nowhere"), &link).unwrap();
    let err = fetch(&link);
    assert!(
        err.contains("LINK") && err.contains("does not exist"),
        "{err}"
    );
    assert_eq!(leftovers(tmp.path()), Vec::<String>::new());
    // Under a file.
    let file = tmp.path().join("a-file");
    std::fs::write(&file, b"x").unwrap();
    let err = fetch(&file.join("gibson"));
    assert!(err.contains("a-file is a file"), "{err}");
    assert!(!err.contains("os error 17"), "{err}");
    // An empty folder that exists.
    let empty = tmp.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let err = fetch(&empty);
    once(&err, "an empty folder");
    // Where nothing can be created: the message names the folder given,
    // not the program's staging folder.
    let err = fetch(std::path::Path::new("/proc/t2e-no-such/gibson"));
    assert!(
        err.contains("/proc/t2e-no-such/gibson") && !err.contains("partial"),
        "{err}"
    );
    // A FIFO in a map's place, under a time limit: a blocked open fails
    // the test instead of hanging it.
    let victim = checkout.join("scene/val/easy").join(
        list_dir(&gibson)
            .unwrap()
            .iter()
            .find(|e| e.listed_class == Some(SizeClass::Small))
            .map(|e| format!("{}.png", e.name))
            .unwrap(),
    );
    std::fs::remove_file(&victim).unwrap();
    assert!(Command::new("mkfifo")
        .arg(&victim)
        .status()
        .unwrap()
        .success());
    let child = Command::new(env!("CARGO_BIN_EXE_t2e-league"))
        .args(["maps", "fetch-gibson", "--from"])
        .arg(&checkout)
        .arg("--out")
        .arg(tmp.path().join("fifo-out"))
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let o = crate::common::output_within(child, 60, "fetch-gibson with a FIFO in a map's place");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("not a regular file"),
        "{err}"
    );
    assert!(!tmp.path().join("fifo-out").exists());
}
