//! `t2e-league maps`: list map sets, draw one map, generate floor plans.

use anyhow::{bail, Context, Result};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use t2e_core::map::catalog::{gibson_dir, resolve, shipped_dir};
use t2e_core::map::generate::{generate, GeneratorConfig};
use t2e_core::map::{load_png, save_png, Grid, PreparedMap, SizeClass};
use t2e_core::render::map_image::map_image_prepared;

#[derive(clap::Args, Debug)]
pub struct MapsArgs {
    #[command(subcommand)]
    pub command: MapsCommand,
}

#[derive(clap::Subcommand, Debug)]
pub enum MapsCommand {
    /// Print a table of maps with their area and size class.
    ///
    /// Columns: side (cells), free cells, traversable area, the class computed
    /// from the area and the class listed in the folder's splits.csv or
    /// manifest.csv; rows marked '*' disagree with their list.
    List {
        /// Which maps: small | medium | large (Gibson classes), gibson,
        /// shipped, a folder, FOLDER:CLASS, or a single .png file.
        #[arg(long, default_value = "shipped", value_name = "SPEC")]
        maps: String,
    },
    /// Draw one map to a PNG.
    ///
    /// Free space is light, obstacles dark, cells where robots may be placed
    /// (more than 0.4 m from obstacles) tinted blue; a 1 m grid and a scale bar.
    Show {
        /// A .png path, or the name of a shipped or Gibson map
        /// (e.g. gen-small-1, Graceville_floor_trav_0_v3).
        map: String,
        /// Output PNG file.
        #[arg(long, value_name = "FILE.png")]
        out: PathBuf,
        /// Pixels per 0.05 m cell.
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=16))]
        scale: u32,
    },
    /// Generate floor plans of one size class as PNG maps.
    ///
    /// Maps are written as DIR/gen-CLASS-SEED.png (0.01 m per pixel, 255 free)
    /// and recorded in DIR/manifest.csv (map, split, area_m2, seed).
    Generate {
        /// Size class to generate: small (<40 m^2), medium (40-60), large (>60).
        #[arg(long)]
        class: SizeClass,
        /// Seed of the first map; the others use seed+1, seed+2, ...
        #[arg(long)]
        seed: u64,
        /// How many maps to generate.
        #[arg(long, default_value_t = 1)]
        count: u64,
        /// Output folder (created if missing); existing manifest rows of
        /// other maps are kept.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
    },
    /// Fetch the 26 Gibson test maps from the paper's public repository.
    ///
    /// Clones https://github.com/Dr-Xiaogaren/T2E (with git) at the pinned
    /// commit, checks every map of scene/val/{easy,middle,hard}/ against the
    /// content hashes and classes the binary embeds, and writes the PNGs and
    /// a splits.csv (small / medium / large) to DIR. Point T2E_GIBSON_DIR at
    /// DIR, or use ../shared/maps/gibson as DIR.
    FetchGibson {
        /// Output folder; created whole (an interrupted fetch leaves none).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Read the maps from this checkout of the reference repository
        /// instead of cloning it (no network needed).
        #[arg(long, value_name = "CHECKOUT")]
        from: Option<PathBuf>,
    },
}

pub fn run(args: MapsArgs) -> Result<()> {
    match args.command {
        MapsCommand::List { maps } => list(&maps),
        MapsCommand::Show { map, out, scale } => show(&map, &out, scale),
        MapsCommand::Generate {
            class,
            seed,
            count,
            out,
        } => generate_maps(class, seed, count, &out),
        MapsCommand::FetchGibson { out, from } => fetch_gibson(&out, from.as_deref()),
    }
}

fn list(spec: &str) -> Result<()> {
    let entries = resolve(spec)?;
    // Decoding a 1600 px PNG takes a while: load in parallel, report in order.
    let loaded: Vec<Result<Grid>> = entries.par_iter().map(|e| Ok(e.load()?)).collect();
    let name_w = entries
        .iter()
        .map(|e| e.name.len())
        .max()
        .unwrap_or(0)
        .max(4);
    println!(
        "{:<name_w$}  {:>5}  {:>10}  {:>9}  {:<8}  listed",
        "map", "side", "free cells", "area m^2", "class"
    );
    let mut failed = Vec::new();
    let mut mismatches = 0;
    let mut areas = Vec::new();
    for (entry, grid) in entries.iter().zip(loaded) {
        let grid = match grid {
            Ok(g) => g,
            Err(e) => {
                println!("{:<name_w$}  error: {e:#}", entry.name);
                failed.push(entry.name.clone());
                continue;
            }
        };
        let class = grid.size_class();
        let listed = entry
            .listed_class
            .map_or("-".to_string(), |c| c.to_string());
        let mark = match entry.listed_class {
            Some(c) if c != class => {
                mismatches += 1;
                " *"
            }
            _ => "",
        };
        areas.push(grid.area_m2());
        let row = format!(
            "{:<name_w$}  {:>5}  {:>10}  {:>9.2}  {:<8}  {:<8}{mark}",
            entry.name,
            grid.side(),
            grid.free_cells(),
            grid.area_m2(),
            class.name(),
            listed
        );
        println!("{}", row.trim_end());
    }
    if !areas.is_empty() {
        let mean = areas.iter().sum::<f64>() / areas.len() as f64;
        println!("{} maps, mean area {mean:.2} m^2", areas.len());
    }
    if mismatches > 0 {
        println!("* {mismatches} map(s) whose computed class differs from the listed one");
    }
    if !failed.is_empty() {
        bail!(
            "{} of {} maps could not be loaded: {}",
            failed.len(),
            entries.len(),
            failed.join(", ")
        );
    }
    Ok(())
}

fn fetch_gibson(out: &Path, from: Option<&Path>) -> Result<()> {
    use t2e_core::map::gibson_source::{import_checkout, REFERENCE_COMMIT, REFERENCE_REPOSITORY};
    let clone;
    let checkout = match from {
        Some(dir) => dir.to_path_buf(),
        None => {
            clone = tempfile_dir()?;
            let dir = clone.join("T2E");
            eprintln!("cloning {REFERENCE_REPOSITORY} at {REFERENCE_COMMIT} ...");
            let cloned = run_git(&[
                "clone",
                "--quiet",
                REFERENCE_REPOSITORY,
                &dir.to_string_lossy(),
            ])
            .and_then(|()| {
                run_git(&[
                    "-C",
                    &dir.to_string_lossy(),
                    "checkout",
                    "--quiet",
                    REFERENCE_COMMIT,
                ])
            });
            if let Err(e) = cloned {
                let _ = std::fs::remove_dir_all(&clone);
                return Err(e);
            }
            dir
        }
    };
    let result = import_checkout(&checkout, out);
    if from.is_none() {
        let _ = std::fs::remove_dir_all(checkout.parent().unwrap_or(&checkout));
    }
    let maps = result?;
    for class in SizeClass::ALL {
        let n = maps.iter().filter(|m| m.class == class).count();
        println!("{class}: {n} maps");
    }
    println!(
        "{} maps checked against the embedded content hashes -> {} (set T2E_GIBSON_DIR={})",
        maps.len(),
        out.display(),
        out.canonicalize()
            .unwrap_or_else(|_| out.to_path_buf())
            .display()
    );
    Ok(())
}

/// A fresh folder for the clone, beside the system's temporary files.
fn tempfile_dir() -> Result<PathBuf> {
    let dir = std::env::temp_dir().join(format!("t2e-fetch-gibson-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    Ok(dir)
}

fn run_git(args: &[&str]) -> Result<()> {
    let status = std::process::Command::new("git")
        .args(args)
        .status()
        .context("cannot run git (needed to fetch the maps; or clone the repository yourself and pass --from CHECKOUT)")?;
    if !status.success() {
        bail!(
            "git {} failed ({status}); without network, clone the repository elsewhere and pass --from CHECKOUT",
            args.join(" ")
        );
    }
    Ok(())
}

/// A map argument: an existing file, else `NAME[.png]` in the shipped or Gibson folder.
fn find_map(map: &str) -> Result<PathBuf> {
    let as_path = PathBuf::from(map);
    if as_path.is_file() {
        return Ok(as_path);
    }
    let file = if map.ends_with(".png") {
        map.to_string()
    } else {
        format!("{map}.png")
    };
    let mut folders = vec![shipped_dir()];
    folders.extend(gibson_dir());
    for dir in &folders {
        let candidate = dir.join(&file);
        if candidate.is_file() {
            return Ok(candidate);
        }
    }
    let searched: Vec<String> = folders.iter().map(|d| d.display().to_string()).collect();
    bail!(
        "map '{map}' not found: not a file, and no {file} in {}",
        searched.join(" or ")
    )
}

fn show(map: &str, out: &Path, scale: u32) -> Result<()> {
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !ext.eq_ignore_ascii_case("png") {
        bail!(
            "--out {}: show writes a PNG picture, so the file must end in .png",
            out.display()
        );
    }
    let path = find_map(map)?;
    if let (Ok(a), Ok(b)) = (path.canonicalize(), out.canonicalize()) {
        if a == b {
            bail!(
                "--out {}: is the map {map} itself; the picture would replace the map",
                out.display()
            );
        }
    }
    let grid = load_png(&path)?;
    let prepared = PreparedMap::new(grid);
    let img = map_image_prepared(&prepared, scale);
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create folder {}", dir.display()))?;
    }
    // Written whole and renamed into place (a killed run leaves the old file).
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .with_context(|| format!("cannot encode {}", out.display()))?;
    t2e_core::fs::write_file_atomically(out, bytes.get_ref())
        .with_context(|| format!("cannot write {}", out.display()))?;
    let g = &prepared.grid;
    println!(
        "{}: {} ({}x{} px): {:.2} m^2, {}, {} spawn cells",
        g.name,
        out.display(),
        img.width(),
        img.height(),
        g.area_m2(),
        g.size_class(),
        prepared.spawn_cells.len()
    );
    Ok(())
}

/// One row of a generated folder's manifest.csv.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ManifestRow {
    pub map: String,
    pub split: SizeClass,
    /// Missing in hand-written manifests.
    #[serde(default)]
    pub area_m2: Option<f64>,
    #[serde(default)]
    pub seed: Option<u64>,
}

/// Reads a manifest; a missing file is an empty manifest.
pub fn read_manifest(path: &Path) -> Result<Vec<ManifestRow>> {
    if !path.exists() {
        return Ok(Vec::new());
    }
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_path(path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let headers = reader
        .headers()
        .with_context(|| format!("{}: cannot read its header", path.display()))?
        .clone();
    let mut rows: Vec<ManifestRow> = Vec::new();
    let mut lines: BTreeMap<String, u64> = BTreeMap::new();
    for (i, rec) in reader.records().enumerate() {
        // Row 1 is the header.
        let rec = rec.with_context(|| format!("{}: row {}", path.display(), i + 2))?;
        let line = rec.position().map_or(i as u64 + 2, |p| p.line());
        let row: ManifestRow = rec
            .deserialize(Some(&headers))
            .with_context(|| format!("{}: row {} (line {line})", path.display(), i + 2))?;
        // The same map twice with other classes: refused, as the catalog
        // refuses it (`map::catalog::class_lists`); keeping either row
        // would silently move the map to another class.
        if let Some(&before) = lines.get(&row.map) {
            let first = rows.iter().find(|r| r.map == row.map).unwrap();
            if first.split != row.split {
                bail!(
                    "{}: map '{}' is listed as {} (line {before}) and as {} (line {line}); remove one of the rows",
                    path.display(),
                    row.map,
                    first.split,
                    row.split
                );
            }
            continue;
        }
        lines.insert(row.map.clone(), line);
        rows.push(row);
    }
    Ok(rows)
}

/// Merges `new` into the manifest at `path` by map name (new rows win) and
/// writes it back sorted by name, areas with two decimals.
pub fn update_manifest(path: &Path, new: &[ManifestRow]) -> Result<()> {
    let mut by_name: BTreeMap<String, ManifestRow> = read_manifest(path)?
        .into_iter()
        .map(|r| (r.map.clone(), r))
        .collect();
    for row in new {
        by_name.insert(row.map.clone(), row.clone());
    }
    // Written whole and renamed into place: a killed run leaves the old
    // manifest or the new one, never half of one.
    let mut writer = csv::Writer::from_writer(Vec::new());
    writer.write_record(["map", "split", "area_m2", "seed"])?;
    for row in by_name.values() {
        let area = row.area_m2.map_or(String::new(), |a| format!("{a:.2}"));
        let seed = row.seed.map_or(String::new(), |s| s.to_string());
        writer.write_record([row.map.as_str(), row.split.name(), &area, &seed])?;
    }
    let bytes = writer
        .into_inner()
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    Ok(t2e_core::fs::write_file_atomically(path, &bytes)?)
}

/// Most maps one `maps generate` writes (about 20 KB each).
pub const MAX_GENERATE: u64 = 1000;

/// Generates `count` maps of `class` from seeds `seed..`, writes them to
/// `out` and merges them into `out/manifest.csv`.
pub fn generate_maps(class: SizeClass, seed: u64, count: u64, out: &Path) -> Result<()> {
    if count == 0 || count > MAX_GENERATE {
        bail!("--count {count}: must be between 1 and {MAX_GENERATE}");
    }
    let last = seed.checked_add(count - 1).with_context(|| {
        format!("--seed {seed} with --count {count} runs past the largest seed")
    })?;
    // A folder with a splits.csv is a test set (the Gibson maps): the
    // manifest would add generated maps to its classes.
    if out.join("splits.csv").is_file() {
        bail!(
            "--out {}: holds a splits.csv (a map set such as the Gibson test maps); generated maps and their manifest.csv would join its classes: write them to a folder of their own",
            out.display()
        );
    }
    // A manifest that cannot be merged is refused before any map is written.
    read_manifest(&out.join("manifest.csv"))?;
    std::fs::create_dir_all(out)
        .with_context(|| format!("cannot create folder {}", out.display()))?;
    let cfg = GeneratorConfig::default();
    let mut rows = Vec::new();
    for s in seed..=last {
        let grid = generate(s, class, &cfg);
        let path = out.join(format!("{}.png", grid.name));
        save_png(&grid, &path)?;
        println!(
            "{}: {:.2} m^2, {}, {} free cells -> {}",
            grid.name,
            grid.area_m2(),
            grid.size_class(),
            grid.free_cells(),
            path.display()
        );
        rows.push(ManifestRow {
            map: grid.name.clone(),
            split: grid.size_class(),
            area_m2: Some(grid.area_m2()),
            seed: Some(s),
        });
        // Recorded as soon as it is written: an interrupted run loses no map.
        update_manifest(&out.join("manifest.csv"), &rows[rows.len() - 1..])?;
    }
    let manifest = out.join("manifest.csv");
    println!("{} map(s) recorded in {}", rows.len(), manifest.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(clap::Parser, Debug)]
    struct TestCli {
        #[command(subcommand)]
        command: MapsCommand,
    }

    #[test]
    fn arguments_parse() {
        let cli = TestCli::try_parse_from([
            "maps", "generate", "--class", "large", "--seed", "5", "--count", "2", "--out", "x",
        ])
        .unwrap();
        assert!(matches!(
            cli.command,
            MapsCommand::Generate {
                class: SizeClass::Large,
                seed: 5,
                count: 2,
                ..
            }
        ));
        let cli = TestCli::try_parse_from(["maps", "list"]).unwrap();
        assert!(matches!(cli.command, MapsCommand::List { ref maps } if maps == "shipped"));
        let err = TestCli::try_parse_from([
            "maps", "generate", "--class", "huge", "--seed", "1", "--out", "x",
        ])
        .unwrap_err();
        assert!(err.to_string().contains("huge"), "{err}");
        assert!(
            TestCli::try_parse_from(["maps", "show", "m", "--out", "a.png", "--scale", "0"])
                .is_err()
        );
    }

    #[test]
    fn generate_writes_maps_and_merges_the_manifest() {
        let dir = tempfile::tempdir().unwrap();
        let manifest = dir.path().join("manifest.csv");
        std::fs::write(
            &manifest,
            "map,split\nzz-hand-made,large\ngen-small-4,medium\n",
        )
        .unwrap();
        generate_maps(SizeClass::Small, 3, 2, dir.path()).unwrap();
        let rows = read_manifest(&manifest).unwrap();
        let names: Vec<&str> = rows.iter().map(|r| r.map.as_str()).collect();
        assert_eq!(names, ["gen-small-3", "gen-small-4", "zz-hand-made"]);
        assert_eq!(rows[1].split, SizeClass::Small); // replaced
        assert_eq!(rows[2].area_m2, None); // kept as it was
        for row in &rows[..2] {
            let g = load_png(&dir.path().join(format!("{}.png", row.map))).unwrap();
            assert_eq!(
                format!("{:.2}", g.area_m2()),
                format!("{:.2}", row.area_m2.unwrap())
            );
            assert_eq!(g.size_class(), row.split);
        }
        // The catalog reads the manifest's classes.
        let entries = t2e_core::map::catalog::list_dir(dir.path()).unwrap();
        assert_eq!(entries.len(), 2);
        assert!(entries
            .iter()
            .all(|e| e.listed_class == Some(SizeClass::Small)));
    }

    #[test]
    fn bad_input_names_the_culprit() {
        let dir = tempfile::tempdir().unwrap();
        let manifest = dir.path().join("manifest.csv");
        std::fs::write(&manifest, "map,split,area_m2,seed\na,tiny,1.0,3\n").unwrap();
        let e = format!("{:#}", read_manifest(&manifest).unwrap_err());
        assert!(e.contains("manifest.csv") && e.contains("row 2"), "{e}");
        let e = format!("{:#}", find_map("no-such-map").unwrap_err());
        assert!(e.contains("no-such-map.png"), "{e}");
        let out = dir.path().join("m.png");
        let e = format!("{:#}", show("/nonexistent/x.png", &out, 2).unwrap_err());
        assert!(e.contains("x.png"), "{e}");
    }

    #[test]
    fn show_draws_a_generated_map() {
        let dir = tempfile::tempdir().unwrap();
        let map = dir.path().join("m.png");
        save_png(
            &generate(1, SizeClass::Small, &GeneratorConfig::default()),
            &map,
        )
        .unwrap();
        let out = dir.path().join("sub/shown.png");
        show(map.to_str().unwrap(), &out, 1).unwrap();
        let img = image::open(&out).unwrap();
        assert_eq!((img.width(), img.height()), (320, 320));
    }
}
