//! The map facts of spec §1 on the real Gibson test maps (kept outside the
//! project, in ../shared/maps/gibson), and the maps the project ships in maps/.

use std::collections::BTreeMap;
use std::path::PathBuf;
use t2e::map::catalog::{gibson_dir, list_dir, shipped_dir};
use t2e::map::{Grid, SizeClass};

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
            t2e::map::testset::gibson_name(grid),
            Some(name.as_str()),
            "{name} is not recognised as a test map; the table should read:\n{listed}"
        );
    }
    // A generated map is not a test map.
    let generated = t2e::map::generate::generate(
        1,
        SizeClass::Medium,
        &t2e::map::generate::GeneratorConfig::default(),
    );
    assert_eq!(t2e::map::testset::gibson_name(&generated), None);
}

/// The fingerprints of the Gibson folder, as `map::testset` embeds them.
fn fingerprint_file(dir: &std::path::Path) -> Vec<u8> {
    use t2e::map::fingerprint::{encode, Fingerprint};
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
        file == t2e::map::testset::FINGERPRINTS_FILE,
        "crates/core/src/map/gibson_fingerprints.bin is not the fingerprint of {}: regenerate it with cargo test --release --test integration -- --ignored gibson_maps::write_test_map_fingerprints",
        dir.display()
    );
    let probes = t2e::map::testset::test_probes();
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
