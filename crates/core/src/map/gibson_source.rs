//! Where the Gibson test maps come from, and how a copy of them is made and
//! checked: the paper's public repository holds the 26 maps under
//! `scene/val/{easy,middle,hard}/` (also all together under
//! `scene/candidate/`); the folder names are the size classes. A copy is
//! accepted only when every map decodes to the working grid whose content
//! hash the project embeds (`map::testset::GIBSON_GRIDS`) and each folder
//! gives the map the class the embedded fingerprints give it: a changed
//! upstream file, a missing map or a map in another class folder is
//! refused, naming the file.

use super::grid::SizeClass;
use super::load::load_png;
use super::testset::{gibson_class, GIBSON_GRIDS};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The reference implementation, where the maps are published.
pub const REFERENCE_REPOSITORY: &str = "https://github.com/Dr-Xiaogaren/T2E";

/// The commit the maps are taken from (its newest on 2026-11-28). The maps
/// are checked by content, so a later commit with the same maps works too;
/// this one is what `maps fetch-gibson` checks out.
pub const REFERENCE_COMMIT: &str = "bb935fe24f5e794db9ec830f295c695bc39c5b18";

/// The reference repository's class folders under `scene/val/`, and the
/// project's names for them.
pub const CLASS_FOLDERS: [(&str, SizeClass); 3] = [
    ("easy", SizeClass::Small),
    ("middle", SizeClass::Medium),
    ("hard", SizeClass::Large),
];

#[derive(Debug, thiserror::Error)]
pub enum GibsonSourceError {
    #[error("{}: not a checkout of the reference repository ({REFERENCE_REPOSITORY}): {reason}", path.display())]
    NotACheckout { path: PathBuf, reason: String },
    #[error("{}: {reason}", path.display())]
    Map { path: PathBuf, reason: String },
    #[error("{}: the maps {missing:?} are missing (the reference repository at {REFERENCE_COMMIT} holds all 26)", folder.display())]
    Missing {
        folder: PathBuf,
        missing: Vec<String>,
    },
    /// `cause` is no `#[source]`: the message holds it once, so a chain
    /// printed whole does not repeat it.
    #[error("{}: cannot write: {cause}", path.display())]
    Write {
        path: PathBuf,
        cause: std::io::Error,
    },
    #[error("{}: {reason}", out.display())]
    Out { out: PathBuf, reason: String },
}

/// One map of a checked copy.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportedMap {
    pub name: String,
    pub class: SizeClass,
    /// `Grid::content_hash`, equal to the embedded one.
    pub content_hash: String,
}

/// Reads the 26 maps from a checkout of the reference repository at
/// `checkout` and checks each against the embedded hashes and classes.
/// Nothing is written.
pub fn read_checkout(checkout: &Path) -> Result<Vec<(ImportedMap, PathBuf)>, GibsonSourceError> {
    let val = checkout.join("scene").join("val");
    if !val.is_dir() {
        return Err(GibsonSourceError::NotACheckout {
            path: checkout.to_path_buf(),
            reason: "it has no scene/val/ folder".into(),
        });
    }
    let expected: BTreeMap<&str, &str> = GIBSON_GRIDS.iter().copied().collect();
    let mut found: BTreeMap<String, (ImportedMap, PathBuf)> = BTreeMap::new();
    for (folder, class) in CLASS_FOLDERS {
        let dir = val.join(folder);
        let entries = std::fs::read_dir(&dir).map_err(|e| GibsonSourceError::NotACheckout {
            path: checkout.to_path_buf(),
            reason: format!("cannot read scene/val/{folder}/: {e}"),
        })?;
        let mut paths: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "png"))
            .collect();
        paths.sort();
        for path in paths {
            let map = check_map(&path, (folder, class), &expected, &found)?;
            found.insert(map.name.clone(), (map, path));
        }
    }
    let missing: Vec<String> = expected
        .keys()
        .filter(|n| !found.contains_key(**n))
        .map(|n| n.to_string())
        .collect();
    if !missing.is_empty() {
        return Err(GibsonSourceError::Missing {
            folder: val,
            missing,
        });
    }
    let mut maps: Vec<(ImportedMap, PathBuf)> = found.into_values().collect();
    maps.sort_by(|(a, _), (b, _)| (a.class, &a.name).cmp(&(b.class, &b.name)));
    Ok(maps)
}

/// One PNG of a checkout against the embedded hash and class, and against
/// the maps already `found`; apart from `read_checkout` so each refusal
/// reads beside its rule.
fn check_map(
    path: &Path,
    (folder, class): (&str, SizeClass),
    expected: &BTreeMap<&str, &str>,
    found: &BTreeMap<String, (ImportedMap, PathBuf)>,
) -> Result<ImportedMap, GibsonSourceError> {
    let refuse = |reason: String| GibsonSourceError::Map {
        path: path.to_path_buf(),
        reason,
    };
    let name = path
        .file_stem()
        .and_then(|s| s.to_str())
        .ok_or_else(|| refuse("its name is not UTF-8".into()))?
        .to_string();
    let Some(want_hash) = expected.get(name.as_str()) else {
        return Err(refuse(
            "not one of the 26 Gibson test maps the project knows (an upstream change?)".into(),
        ));
    };
    refuse_unless_regular(path).map_err(refuse)?;
    let grid = load_png(path).map_err(|e| refuse(e.reason))?;
    let hash = grid.content_hash();
    if hash != *want_hash {
        return Err(refuse(format!(
            "its content (working grid SHA-256 {hash}) is not the test map's ({want_hash}): the file differs from the one the benchmark's figures were measured on"
        )));
    }
    let embedded = gibson_class(&name);
    if embedded != Some(class) {
        return Err(refuse(format!(
            "it is in the {folder}/ folder ({}), but the test set lists it as {}",
            class.name(),
            embedded.map_or("unclassed", |c| c.name())
        )));
    }
    if let Some((other, other_path)) = found.get(&name) {
        return Err(refuse(format!(
            "listed twice: also {} ({})",
            other_path.display(),
            other.class.name()
        )));
    }
    Ok(ImportedMap {
        name,
        class,
        content_hash: hash,
    })
}

/// Checks the checkout at `checkout` (`read_checkout`), then writes the 26
/// PNGs, byte for byte, and a `splits.csv` (`map,split`, the project's
/// class names) into `out`. The folder is filled under a temporary name and
/// renamed into place, so an interrupted copy never looks complete; an
/// existing `out` is refused unless it already holds this very set.
pub fn import_checkout(checkout: &Path, out: &Path) -> Result<Vec<ImportedMap>, GibsonSourceError> {
    let maps = read_checkout(checkout)?;
    let refuse = |reason: String| GibsonSourceError::Out {
        out: out.to_path_buf(),
        reason,
    };
    refuse_broken_links(out)?;
    if out.exists() {
        return existing_out(out, &maps);
    }
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if let Some(file) = parent.ancestors().find(|a| a.exists() && !a.is_dir()) {
        return Err(refuse(format!(
            "{} is a file, not a folder, so nothing can be written under it",
            file.display()
        )));
    }
    std::fs::create_dir_all(&parent)
        .map_err(|e| refuse(format!("cannot create its parent folder: {e}")))?;
    let staging = parent.join(format!(
        ".{}.partial-{}",
        out.file_name().and_then(|s| s.to_str()).unwrap_or("gibson"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&staging);
    remove_dead_stagings(&parent, out);
    let filled = fill_staging(&staging, &maps).and_then(|()| {
        std::fs::rename(&staging, out)
            .map_err(|e| refuse(format!("cannot move the maps into place: {e}")))
    });
    if filled.is_err() {
        // Nothing half-written is left behind, hidden or not.
        let _ = std::fs::remove_dir_all(&staging);
    }
    filled.map_err(|e| match e {
        // The staging folder is the program's business; the user gave `out`.
        GibsonSourceError::Write { cause, .. } => refuse(format!("cannot write: {cause}")),
        other => other,
    })?;
    Ok(maps.into_iter().map(|(m, _)| m).collect())
}

/// Refuses a dangling link or a loop of links on the way to `out`, which
/// would otherwise surface as "File exists" from create_dir_all.
fn refuse_broken_links(out: &Path) -> Result<(), GibsonSourceError> {
    let refuse = |reason: String| GibsonSourceError::Out {
        out: out.to_path_buf(),
        reason,
    };
    // Every link on the way must lead somewhere: a dangling one or a loop
    // would otherwise surface as "File exists" from create_dir_all.
    for at in out.ancestors().filter(|a| !a.as_os_str().is_empty()) {
        let Ok(link) = std::fs::read_link(at) else {
            continue;
        };
        let what = if at == out {
            "it is".to_string()
        } else {
            format!("{} is", at.display())
        };
        match std::fs::metadata(at) {
            Ok(_) => {}
            Err(e) if e.raw_os_error() == Some(libc_eloop()) => {
                return Err(refuse(format!(
                    "{what} a loop of symbolic links (through {}); remove a link of the loop",
                    link.display()
                )))
            }
            Err(_) => {
                return Err(refuse(format!(
                    "{what} a symbolic link to {}, which does not exist; remove the link or give the folder it should name",
                    link.display()
                )))
            }
        }
    }
    Ok(())
}

/// An `out` that already exists: the finished set itself (a second fetch is
/// not an error), else refused; apart so `import_checkout` reads as checks,
/// staging, rename.
fn existing_out(
    out: &Path,
    maps: &[(ImportedMap, PathBuf)],
) -> Result<Vec<ImportedMap>, GibsonSourceError> {
    let refuse = |reason: String| GibsonSourceError::Out {
        out: out.to_path_buf(),
        reason,
    };
    if !out.is_dir() {
        return Err(refuse(
            "exists and is not a folder; choose another --out".into(),
        ));
    }
    // Idempotent: a second fetch into a finished folder is not an error.
    if let Ok(existing) = read_flat(out) {
        if existing == maps.iter().map(|(m, _)| m.clone()).collect::<Vec<_>>() {
            return Ok(existing);
        }
    }
    let empty = std::fs::read_dir(out).is_ok_and(|mut d| d.next().is_none());
    Err(refuse(if empty {
        "exists (an empty folder); remove it, or choose a folder that does not exist yet".into()
    } else {
        "exists and is not this set of maps; choose another folder or remove it".into()
    }))
}

/// The 26 PNGs, byte for byte, and `splits.csv` into `staging`.
fn fill_staging(staging: &Path, maps: &[(ImportedMap, PathBuf)]) -> Result<(), GibsonSourceError> {
    let write_err = |path: &Path| {
        let path = path.to_path_buf();
        move |cause| GibsonSourceError::Write { path, cause }
    };
    std::fs::create_dir_all(staging).map_err(write_err(staging))?;
    let mut splits = String::from("map,split\n");
    for (map, source) in maps {
        let dest = staging.join(format!("{}.png", map.name));
        std::fs::copy(source, &dest).map_err(write_err(&dest))?;
        splits.push_str(&format!("{},{}\n", map.name, map.class.name()));
    }
    let splits_path = staging.join("splits.csv");
    std::fs::write(&splits_path, splits).map_err(write_err(&splits_path))
}

/// ELOOP, the error of a path that loops through symbolic links (40 on
/// Linux; the crate links no libc).
fn libc_eloop() -> i32 {
    40
}

/// Removes `.OUT.partial-PID` folders that a fetch killed before its rename
/// left beside `out`, where process PID is gone (a live one is another
/// fetch at work).
fn remove_dead_stagings(parent: &Path, out: &Path) {
    let Some(name) = out.file_name().and_then(|s| s.to_str()) else {
        return;
    };
    let prefix = format!(".{name}.partial-");
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let file = entry.file_name();
        let Some(pid) = file.to_str().and_then(|f| f.strip_prefix(&prefix)) else {
            continue;
        };
        let alive = pid.parse::<u32>().is_ok_and(crate::fs::pid_alive);
        if !alive {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// A map file must be a regular file (a symbolic link to one is): reading
/// a FIFO or a device in its place would block or never end.
fn refuse_unless_regular(path: &Path) -> Result<(), String> {
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => Ok(()),
        Ok(_) => Err("not a regular file (a FIFO, device or folder in a map's place)".into()),
        Err(e) => Err(format!("cannot read: {e}")),
    }
}

/// The maps of a flat folder as `import_checkout` writes it, checked the
/// same way (content hash and class), in the same order.
pub fn read_flat(dir: &Path) -> Result<Vec<ImportedMap>, GibsonSourceError> {
    let entries = super::catalog::list_dir(dir).map_err(|e| GibsonSourceError::Map {
        path: dir.to_path_buf(),
        reason: format!("{e:#}"),
    })?;
    let expected: BTreeMap<&str, &str> = GIBSON_GRIDS.iter().copied().collect();
    let mut maps = Vec::new();
    for entry in entries {
        let refuse = |reason: String| GibsonSourceError::Map {
            path: entry.path.clone(),
            reason,
        };
        refuse_unless_regular(&entry.path).map_err(refuse)?;
        let grid = load_png(&entry.path).map_err(|e| refuse(e.reason))?;
        let hash = grid.content_hash();
        if expected.get(entry.name.as_str()) != Some(&hash.as_str()) {
            return Err(refuse("not the test map of that name".into()));
        }
        let class = gibson_class(&entry.name).ok_or_else(|| refuse("unclassed".into()))?;
        if entry.listed_class != Some(class) {
            return Err(refuse(format!(
                "splits.csv does not list it as {}",
                class.name()
            )));
        }
        maps.push(ImportedMap {
            name: entry.name,
            class,
            content_hash: hash,
        });
    }
    maps.sort_by(|a, b| (a.class, &a.name).cmp(&(b.class, &b.name)));
    Ok(maps)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn class_folders_cover_each_class_once() {
        let classes: Vec<SizeClass> = CLASS_FOLDERS.iter().map(|(_, c)| *c).collect();
        assert_eq!(classes, SizeClass::ALL.to_vec());
    }

    #[test]
    fn a_folder_without_scene_val_is_not_a_checkout() {
        let dir = tempfile::tempdir().unwrap();
        let err = read_checkout(dir.path()).unwrap_err();
        assert!(
            matches!(err, GibsonSourceError::NotACheckout { .. }),
            "{err}"
        );
        assert!(err.to_string().contains("scene/val"), "{err}");
    }

    #[test]
    fn an_unknown_png_is_refused_by_name() {
        let dir = tempfile::tempdir().unwrap();
        for (folder, _) in CLASS_FOLDERS {
            std::fs::create_dir_all(dir.path().join("scene/val").join(folder)).unwrap();
        }
        let stray = dir
            .path()
            .join("scene/val/easy/Nowhere_floor_trav_0_v3.png");
        std::fs::write(&stray, b"not a png").unwrap();
        let err = read_checkout(dir.path()).unwrap_err().to_string();
        assert!(err.contains("Nowhere_floor_trav_0_v3.png"), "{err}");
        assert!(err.contains("not one of the 26"), "{err}");
    }

    #[test]
    fn an_empty_checkout_names_the_missing_maps() {
        let dir = tempfile::tempdir().unwrap();
        for (folder, _) in CLASS_FOLDERS {
            std::fs::create_dir_all(dir.path().join("scene/val").join(folder)).unwrap();
        }
        match read_checkout(dir.path()).unwrap_err() {
            GibsonSourceError::Missing { missing, .. } => assert_eq!(missing.len(), 26),
            other => panic!("{other}"),
        }
    }
}
