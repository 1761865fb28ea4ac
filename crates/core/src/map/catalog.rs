//! Sets of maps on disk: a folder of PNGs with an optional class list
//! (`splits.csv` as in the Gibson set, or the generator's `manifest.csv`),
//! and the names users give them on the command line.

use super::grid::{Grid, SizeClass};
use super::load::{load_png, MapError};
use super::prepared::PreparedMap;
use crate::error::Chain;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Why a map set cannot be resolved or loaded; each message names the
/// selection, the folder or the file.
#[derive(Debug, thiserror::Error)]
pub enum MapLoadError {
    /// A selection (`--maps`, a config's `maps`) that names no usable set.
    #[error("--maps '{spec}': {reason}")]
    Spec { spec: String, reason: String },
    /// A Gibson selection (`gibson`, `small`, ...) without the Gibson maps.
    #[error("the Gibson maps were not found: set T2E_GIBSON_DIR or run from the project root with ../shared/maps/gibson beside it")]
    NoGibson,
    #[error("map folder {}: not found", .0.display())]
    NoFolder(PathBuf),
    #[error("cannot list {}: {}", .dir.display(), Chain(.cause))]
    Unlistable { dir: PathBuf, cause: std::io::Error },
    /// Two files of one folder that are the same map by name (`a.png`, `a.PNG`).
    #[error("map folder {}: {} and {} are both map '{name}'; keep one", .dir.display(), .first.display(), .second.display())]
    SameName {
        dir: PathBuf,
        name: String,
        first: PathBuf,
        second: PathBuf,
    },
    #[error("map folder {} holds no .png map", .0.display())]
    Empty(PathBuf),
    /// A class list (`splits.csv`, `manifest.csv`) that cannot be read, or
    /// that gives a map two classes.
    #[error("{}: {reason}", .file.display())]
    ClassList { file: PathBuf, reason: String },
    /// A map file that cannot be loaded.
    #[error(transparent)]
    Map(#[from] MapError),
}

fn spec_error(spec: &str, reason: impl Into<String>) -> MapLoadError {
    MapLoadError::Spec {
        spec: spec.to_string(),
        reason: reason.into(),
    }
}

/// One map file and the class its folder lists for it, if any.
#[derive(Clone, Debug)]
pub struct MapEntry {
    pub name: String,
    pub path: PathBuf,
    pub listed_class: Option<SizeClass>,
}

impl MapEntry {
    pub fn load(&self) -> Result<Grid, MapError> {
        load_png(&self.path)
    }
}

/// Where the Gibson test maps live: `$T2E_GIBSON_DIR`, else `../shared/maps/gibson`
/// from the working folder or from the project root.
pub fn gibson_dir() -> Option<PathBuf> {
    if let Ok(d) = std::env::var("T2E_GIBSON_DIR") {
        return Some(PathBuf::from(d));
    }
    let candidates = [
        PathBuf::from("../shared/maps/gibson"),
        Path::new(crate::PROJECT_ROOT).join("../shared/maps/gibson"),
    ];
    candidates.into_iter().find(|p| p.is_dir())
}

/// A file of the shared reference data (`../shared`: the reference traces,
/// the reference ASZ values), found two folders above the Gibson maps'
/// folder, else beside the project's root.
pub fn shared_file(relative: &str) -> Option<PathBuf> {
    let from_gibson = gibson_dir().map(|g| g.join("../..").join(relative));
    let beside = Path::new(crate::PROJECT_ROOT)
        .join("../shared")
        .join(relative);
    [from_gibson, Some(beside)]
        .into_iter()
        .flatten()
        .find(|p| p.is_file())
}

/// The maps the project ships (its embedded default).
pub fn shipped_dir() -> PathBuf {
    let local = PathBuf::from("maps");
    if local.join("manifest.csv").is_file() {
        return local;
    }
    Path::new(crate::PROJECT_ROOT).join("maps")
}

/// Where a class list gave a map its class: the file and the line.
#[derive(Clone, Debug, PartialEq)]
pub struct Listed {
    pub class: SizeClass,
    pub file: PathBuf,
    pub line: u64,
}

impl Listed {
    fn place(&self) -> String {
        format!("{} line {}", self.file.display(), self.line)
    }
}

/// Reads `map,split[,...]` rows of a class list into `out`. A map listed
/// twice with different classes (in this file or in another list of the
/// same folder) is refused, naming both places: taking either class would
/// silently move the map to another table row. A repeat with the same
/// class says nothing new and is accepted.
fn read_class_list(path: &Path, out: &mut BTreeMap<String, Listed>) -> Result<(), MapLoadError> {
    let refuse = |reason: String| MapLoadError::ClassList {
        file: path.to_path_buf(),
        reason,
    };
    let mut reader =
        csv::Reader::from_path(path).map_err(|e| refuse(format!("cannot read: {}", Chain(&e))))?;
    let headers = reader
        .headers()
        .map_err(|e| {
            refuse(format!(
                "cannot read its header (a CSV file in UTF-8 is expected): {}",
                Chain(&e)
            ))
        })?
        .clone();
    let col = |name: &str| headers.iter().position(|h| h.trim() == name);
    let (Some(map_col), Some(split_col)) = (col("map"), col("split")) else {
        return Err(refuse(format!(
            "needs the columns 'map' and 'split', found {headers:?}"
        )));
    };
    for (i, rec) in reader.records().enumerate() {
        let rec = rec.map_err(|e| {
            refuse(format!(
                "row {} (a CSV file in UTF-8 is expected): {}",
                i + 2,
                Chain(&e)
            ))
        })?;
        let line = rec.position().map_or(i as u64 + 2, |p| p.line());
        let class: SizeClass =
            rec[split_col]
                .parse()
                .map_err(|e: super::grid::UnknownSizeClass| {
                    refuse(format!("line {line}, field 'split': {e}"))
                })?;
        let map = rec[map_col].trim().to_string();
        if map.is_empty() {
            return Err(refuse(format!("line {line}, field 'map': empty")));
        }
        let here = Listed {
            class,
            file: path.to_path_buf(),
            line,
        };
        match out.get(&map) {
            Some(before) if before.class != class => {
                return Err(refuse(format!(
                    "map '{map}' is listed as {} and as {} ({}): which class is it? Remove one of the rows",
                    before.class,
                    class,
                    [before.place(), here.place()].join(" and ")
                )))
            }
            Some(_) => {}
            None => {
                out.insert(map, here);
            }
        }
    }
    Ok(())
}

/// The classes a folder's `splits.csv` and `manifest.csv` give its maps.
pub fn class_lists(dir: &Path) -> Result<BTreeMap<String, Listed>, MapLoadError> {
    let mut classes = BTreeMap::new();
    for list in ["splits.csv", "manifest.csv"] {
        let p = dir.join(list);
        if p.is_file() {
            read_class_list(&p, &mut classes)?;
        }
    }
    Ok(classes)
}

/// All PNG maps of a folder, sorted by name, with their listed classes.
pub fn list_dir(dir: &Path) -> Result<Vec<MapEntry>, MapLoadError> {
    if !dir.is_dir() {
        return Err(MapLoadError::NoFolder(dir.to_path_buf()));
    }
    let classes = class_lists(dir)?;
    let mut entries = Vec::new();
    let unlistable = |cause| MapLoadError::Unlistable {
        dir: dir.to_path_buf(),
        cause,
    };
    for e in std::fs::read_dir(dir).map_err(unlistable)? {
        let path = e.map_err(unlistable)?.path();
        // Any case: a folder of .PNG files (or a mix) is not silently
        // smaller than it looks.
        if !path
            .extension()
            .and_then(|x| x.to_str())
            .is_some_and(|x| x.eq_ignore_ascii_case("png"))
            || !path.is_file()
        {
            continue;
        }
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        // Maps are known by name (class lists, episode records): two files
        // of one name would be two maps nobody can tell apart.
        if let Some(other) = entries.iter().find(|e: &&MapEntry| e.name == name) {
            return Err(MapLoadError::SameName {
                dir: dir.to_path_buf(),
                name,
                first: other.path.clone(),
                second: path,
            });
        }
        entries.push(MapEntry {
            listed_class: classes.get(&name).map(|l| l.class),
            name,
            path,
        });
    }
    entries.sort_by(|a, b| a.name.cmp(&b.name));
    if entries.is_empty() {
        return Err(MapLoadError::Empty(dir.to_path_buf()));
    }
    Ok(entries)
}

/// Resolves a user's map selection:
/// - `small`, `medium`, `large`: that class of the Gibson test set;
/// - `gibson`: all 26 Gibson maps; `shipped`: the project's generated maps;
/// - a folder, or `FOLDER:CLASS` for one class of a folder;
/// - a single `.png` file.
pub fn resolve(spec: &str) -> Result<Vec<MapEntry>, MapLoadError> {
    let gibson = || gibson_dir().ok_or(MapLoadError::NoGibson);
    let (source, class) = match spec.rsplit_once(':') {
        Some((dir, c)) if c.parse::<SizeClass>().is_ok() => {
            (dir.to_string(), Some(c.parse::<SizeClass>().unwrap()))
        }
        _ => (spec.to_string(), None),
    };
    let (dir, class) = if let (Ok(c), None) = (source.parse::<SizeClass>(), class) {
        (gibson()?, Some(c))
    } else if source == "gibson" {
        (gibson()?, class)
    } else if source == "shipped" {
        (shipped_dir(), class)
    } else {
        let p = PathBuf::from(&source);
        if source.to_ascii_lowercase().ends_with(".png") && !p.is_file() {
            return Err(spec_error(
                spec,
                format!("map file {}: not found", p.display()),
            ));
        }
        if p.is_file() {
            let name = p
                .file_stem()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned();
            return Ok(vec![MapEntry {
                name,
                path: p,
                listed_class: None,
            }]);
        }
        if !p.is_dir() {
            if class.is_some() {
                return Err(spec_error(
                    spec,
                    format!("folder {}: not found", p.display()),
                ));
            }
            if let Some((_, bad)) = spec.rsplit_once(':') {
                return Err(spec_error(spec, format!("'{bad}' is not a size class (small, medium, large), and no folder '{spec}' was found")));
            }
            return Err(spec_error(spec, "not found: not a size class (small, medium, large), 'gibson', 'shipped', an existing folder or .png file"));
        }
        (p, class)
    };
    let mut entries = list_dir(&dir)?;
    if let Some(c) = class {
        // A class is the maps its list names: one listed but missing would
        // silently leave the set smaller than the table says.
        for (map, listed) in class_lists(&dir)? {
            if listed.class == c && !entries.iter().any(|e| e.name == map) {
                return Err(spec_error(
                    spec,
                    format!(
                        "{} lists the {c} map '{map}', but {} holds no {map}.png",
                        listed.place(),
                        dir.display()
                    ),
                ));
            }
        }
        entries.retain(|e| e.listed_class == Some(c));
        if entries.is_empty() {
            return Err(spec_error(
                spec,
                format!("{} lists no {c} map", dir.display()),
            ));
        }
    }
    Ok(entries)
}

/// The maps a user named, loaded and prepared in parallel: what an
/// environment plays on.
/// Also `generated:N` (N maps per size class from the project's generator,
/// seeds 1..=N, made in memory), `generated:N@S` (seeds S..S+N: other
/// maps of the same generator, e.g. a validation set) and either with
/// `:CLASS`.
pub fn load_prepared(spec: &str) -> Result<Arc<Vec<Arc<PreparedMap>>>, MapLoadError> {
    let spec = spec.trim();
    if spec.contains(',') {
        // A list of sets is their union, in order; a map named twice (by
        // content) is one map, so a list never weights a map twice.
        let generated: u64 = spec
            .split(',')
            .filter_map(|part| generated_set(part.trim()))
            .map(|(seeds, classes)| (seeds.end - seeds.start) * classes.len() as u64)
            .sum();
        let most = MAX_GENERATED_PER_CLASS * SizeClass::ALL.len() as u64;
        if generated > most {
            return Err(spec_error(spec, format!("{generated} generated maps; a map set holds at most {most} (each is prepared in memory)")));
        }
        let mut seen = std::collections::HashSet::new();
        let mut all = Vec::new();
        for part in spec.split(',').map(str::trim) {
            if part.is_empty() {
                return Err(spec_error(spec, "an empty entry in the list"));
            }
            for map in load_prepared(part)?.iter() {
                if seen.insert(map.grid.content_hash()) {
                    all.push(map.clone());
                }
            }
        }
        return Ok(Arc::new(all));
    }
    if let Some(rest) = spec.strip_prefix("generated:") {
        return generated(spec, rest);
    }
    let entries = resolve(spec)?;
    let maps = entries
        .par_iter()
        .map(|e| Ok(Arc::new(PreparedMap::new(e.load()?))))
        .collect::<Result<Vec<_>, MapLoadError>>()?;
    Ok(Arc::new(maps))
}

/// The most maps `generated:N` makes per class. Each prepared map holds
/// about 1 MB; past a few thousand, a set would fill memory (30,000 maps
/// took 26 GB) before anything was trained or written.
pub const MAX_GENERATED_PER_CLASS: u64 = 1_000;

/// The generator seeds of `N` or `N@S`.
fn generated_seeds(count: &str) -> Option<std::ops::Range<u64>> {
    let (n, first) = match count.split_once('@') {
        Some((n, s)) => (n, s.parse::<u64>().ok().filter(|&s| s >= 1)?),
        None => (count, 1),
    };
    let n: u64 = n
        .parse()
        .ok()
        .filter(|&n| (1..=MAX_GENERATED_PER_CLASS).contains(&n))?;
    Some(first..first.checked_add(n)?)
}

/// The generator seeds and classes a `generated:...` selection makes, or
/// None for any other selection (checks that two sets share no map).
pub fn generated_set(spec: &str) -> Option<(std::ops::Range<u64>, Vec<SizeClass>)> {
    let rest = spec.strip_prefix("generated:")?;
    let (count, classes) = match rest.split_once(':') {
        Some((n, c)) => (n, vec![c.parse::<SizeClass>().ok()?]),
        None => (rest, SizeClass::ALL.to_vec()),
    };
    Some((generated_seeds(count)?, classes))
}

fn generated(spec: &str, rest: &str) -> Result<Arc<Vec<Arc<PreparedMap>>>, MapLoadError> {
    use super::generate::{generate, GeneratorConfig};
    let (count, classes) = match rest.split_once(':') {
        Some((n, c)) => (
            n,
            vec![c
                .parse::<SizeClass>()
                .map_err(|e| spec_error(spec, e.to_string()))?],
        ),
        None => (rest, SizeClass::ALL.to_vec()),
    };
    let seeds = generated_seeds(count).ok_or_else(|| spec_error(spec, format!("expected generated:N (seeds 1..=N) or generated:N@S (seeds S..S+N), N in 1..={MAX_GENERATED_PER_CLASS}, S >= 1, optionally :small|medium|large")))?;
    let cfg = GeneratorConfig::default();
    let jobs: Vec<(u64, SizeClass)> = classes
        .iter()
        .flat_map(|&c| seeds.clone().map(move |s| (s, c)))
        .collect();
    let maps = jobs
        .par_iter()
        .map(|&(seed, class)| Arc::new(PreparedMap::new(generate(seed, class, &cfg))))
        .collect();
    Ok(Arc::new(maps))
}
