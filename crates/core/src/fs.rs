//! Files and folders written whole or not at all, for every writer in the
//! project (maps, checkpoints, league records, reports).
//!
//! Invariants:
//! - A file or folder is written under a temporary sibling
//!   (`.NAME.tmp-PID`), synced, then moved into place: a reader sees the old
//!   version or the new one, never half of one.
//! - A complete folder is never removed before its replacement is in place
//!   (the two are swapped in one step), and an identical one is not
//!   rewritten.
//! - Temporaries a killed process left behind are removed, and a folder it
//!   had moved aside is put back, by `clean_stale_temporaries`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What went wrong writing or cleaning, naming the path.
#[derive(Debug, thiserror::Error)]
pub enum FsError {
    /// An operating-system error; `what` says what was being done to which
    /// path, the cause follows it in the message.
    #[error("{what}: {cause}")]
    Io { what: String, cause: std::io::Error },
    /// `write_new_dir_atomically` found the folder already there.
    #[error("{}: already exists; refusing to replace it", .0.display())]
    Exists(PathBuf),
    /// A path such as `/` or `..` that names no file.
    #[error("{}: the path names no file", .0.display())]
    NoName(PathBuf),
}

fn io(what: impl FnOnce() -> String) -> impl FnOnce(std::io::Error) -> FsError {
    move |cause| FsError::Io {
        what: what(),
        cause,
    }
}

/// What `write_dir_atomically` did.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Written {
    /// The folder did not exist.
    Created,
    /// A folder with other content was swapped out for the new one.
    Replaced,
    /// The folder already held exactly this content; nothing was touched.
    Unchanged,
}

/// The folder that holds `path`: `.` for a bare name such as `out`, whose
/// `parent()` is the empty path (which cannot be opened or synced).
fn parent_dir(path: &Path) -> &Path {
    path.parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
}

fn sync_path(path: &Path) -> Result<(), FsError> {
    std::fs::File::open(path)
        .and_then(|f| f.sync_all())
        .map_err(io(|| format!("cannot sync {}", path.display())))
}

fn file_name(path: &Path) -> Result<String, FsError> {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .ok_or_else(|| FsError::NoName(path.to_path_buf()))
}

/// Do two folders hold the same files with the same bytes?
fn same_files(a: &Path, b: &Path) -> bool {
    let list = |d: &Path| -> Option<BTreeMap<String, PathBuf>> {
        std::fs::read_dir(d)
            .ok()?
            .map(|e| {
                e.ok()
                    .map(|e| (e.file_name().to_string_lossy().into_owned(), e.path()))
            })
            .collect()
    };
    let (Some(fa), Some(fb)) = (list(a), list(b)) else {
        return false;
    };
    fa.len() == fb.len()
        && fa.iter().all(|(name, pa)| {
            fb.get(name)
                .is_some_and(|pb| match (std::fs::read(pa), std::fs::read(pb)) {
                    (Ok(x), Ok(y)) => x == y,
                    _ => false,
                })
        })
}

/// Linux `renameat2(a, b, flags)`.
#[cfg(target_os = "linux")]
fn renameat2(a: &Path, b: &Path, flags: libc::c_uint) -> std::io::Result<()> {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    let ca = CString::new(a.as_os_str().as_bytes())?;
    let cb = CString::new(b.as_os_str().as_bytes())?;
    // SAFETY: both paths are valid NUL-terminated strings for the call's duration.
    let rc = unsafe {
        libc::syscall(
            libc::SYS_renameat2,
            libc::AT_FDCWD,
            ca.as_ptr(),
            libc::AT_FDCWD,
            cb.as_ptr(),
            flags,
        )
    };
    if rc == 0 {
        Ok(())
    } else {
        Err(std::io::Error::last_os_error())
    }
}

/// Swaps two paths in one step (Linux `renameat2(RENAME_EXCHANGE)`).
#[cfg(target_os = "linux")]
fn exchange(a: &Path, b: &Path) -> std::io::Result<()> {
    renameat2(a, b, libc::RENAME_EXCHANGE)
}

#[cfg(not(target_os = "linux"))]
fn exchange(_a: &Path, _b: &Path) -> std::io::Result<()> {
    Err(std::io::Error::from(std::io::ErrorKind::Unsupported))
}

/// Renames `a` to `b` unless `b` exists (Linux `RENAME_NOREPLACE`; elsewhere
/// a check, then the rename, which is enough for a writer holding its
/// learner's lock).
fn rename_no_replace(a: &Path, b: &Path) -> std::io::Result<()> {
    #[cfg(target_os = "linux")]
    match renameat2(a, b, libc::RENAME_NOREPLACE) {
        Ok(()) => return Ok(()),
        Err(e) if !matches!(e.raw_os_error(), Some(libc::EINVAL) | Some(libc::ENOSYS)) => {
            return Err(e)
        }
        Err(_) => {}
    }
    if b.exists() {
        return Err(std::io::Error::from(std::io::ErrorKind::AlreadyExists));
    }
    std::fs::rename(a, b)
}

/// Copies the plain files of the folder `src` into `dst` (a temporary that
/// `write_dir_atomically` or `write_new_dir_atomically` is filling): a
/// snapshot frozen for a best response, exported, or imported into a
/// league's pool.
pub fn copy_files(src: &Path, dst: &Path) -> Result<(), FsError> {
    let entries =
        std::fs::read_dir(src).map_err(io(|| format!("cannot read {}", src.display())))?;
    for e in entries {
        let path = e
            .map_err(io(|| format!("cannot read {}", src.display())))?
            .path();
        if path.is_file() {
            std::fs::copy(&path, dst.join(file_name(&path)?))
                .map_err(io(|| format!("cannot copy {}", path.display())))?;
        }
    }
    Ok(())
}

/// Writes a folder atomically: `fill` writes into a temporary sibling, whose
/// files are synced before it takes `dir`'s place. An existing `dir` with the
/// same content is left alone; one with other content is swapped with the
/// new folder in one step, so at every moment `dir` is one complete version.
/// (Where the swap is unsupported, the old folder is first renamed to
/// `.NAME.old-PID`, which `clean_stale_temporaries` puts back if the process
/// dies before the new one is in place.)
pub fn write_dir_atomically<E: From<FsError>>(
    dir: &Path,
    fill: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<Written, E> {
    write_dir(dir, fill, true)
}

/// Writes a folder that must not exist yet (a pool member, which never
/// changes once written): as `write_dir_atomically`, but an existing `dir`
/// is an error and is left untouched, checked before writing and again by
/// the rename itself (`RENAME_NOREPLACE`).
pub fn write_new_dir_atomically<E: From<FsError>>(
    dir: &Path,
    fill: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<Written, E> {
    write_dir(dir, fill, false)
}

fn write_dir<E: From<FsError>>(
    dir: &Path,
    fill: impl FnOnce(&Path) -> Result<(), E>,
    replace: bool,
) -> Result<Written, E> {
    if !replace && dir.exists() {
        return Err(FsError::Exists(dir.to_path_buf()).into());
    }
    let parent = parent_dir(dir);
    std::fs::create_dir_all(parent)
        .map_err(io(|| format!("cannot create {}", parent.display())))?;
    let name = file_name(dir)?;
    let tmp = parent.join(format!(".{name}.tmp-{}", std::process::id()));
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).map_err(io(|| format!("cannot remove {}", tmp.display())))?;
    }
    std::fs::create_dir_all(&tmp).map_err(io(|| format!("cannot create {}", tmp.display())))?;
    fill(&tmp)?;
    sync_tree(&tmp)?;
    if !replace {
        if let Err(cause) = rename_no_replace(&tmp, dir) {
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(FsError::Io {
                what: format!(
                    "cannot move {} into place (refusing to replace an existing folder)",
                    dir.display()
                ),
                cause,
            }
            .into());
        }
        sync_path(parent)?;
        return Ok(Written::Created);
    }
    let outcome = if !dir.exists() {
        std::fs::rename(&tmp, dir)
            .map_err(io(|| format!("cannot move {} into place", dir.display())))?;
        Written::Created
    } else if same_files(&tmp, dir) {
        std::fs::remove_dir_all(&tmp).map_err(io(|| format!("cannot remove {}", tmp.display())))?;
        return Ok(Written::Unchanged);
    } else {
        if exchange(&tmp, dir).is_err() {
            let aside = parent.join(format!(".{name}.old-{}", std::process::id()));
            std::fs::rename(dir, &aside)
                .map_err(io(|| format!("cannot move {} aside", dir.display())))?;
            std::fs::rename(&tmp, dir)
                .map_err(io(|| format!("cannot move {} into place", dir.display())))?;
            std::fs::rename(&aside, &tmp)
                .map_err(io(|| format!("cannot move {} back", aside.display())))?;
        }
        // `tmp` now holds the old version.
        std::fs::remove_dir_all(&tmp).map_err(io(|| format!("cannot remove {}", tmp.display())))?;
        Written::Replaced
    };
    sync_path(parent)?;
    Ok(outcome)
}

/// Syncs a folder's entries, then the folder.
fn sync_tree(dir: &Path) -> Result<(), FsError> {
    let entries =
        std::fs::read_dir(dir).map_err(io(|| format!("cannot read {}", dir.display())))?;
    for e in entries {
        sync_path(
            &e.map_err(io(|| format!("cannot read {}", dir.display())))?
                .path(),
        )?;
    }
    sync_path(dir)
}

/// Writes a file atomically (temporary sibling, synced, then renamed).
pub fn write_file_atomically(path: &Path, bytes: &[u8]) -> Result<(), FsError> {
    use std::io::Write;
    let name = file_name(path)?;
    let tmp = path.with_file_name(format!(".{name}.tmp-{}", std::process::id()));
    let mut f =
        std::fs::File::create(&tmp).map_err(io(|| format!("cannot write {}", tmp.display())))?;
    if let Err(cause) = f.write_all(bytes).and_then(|_| f.sync_all()) {
        // A full disk stays full with the half-written temporary on it.
        drop(f);
        std::fs::remove_file(&tmp).ok();
        return Err(FsError::Io {
            what: format!("cannot write {}", tmp.display()),
            cause,
        });
    }
    std::fs::rename(&tmp, path)
        .map_err(io(|| format!("cannot move {} into place", path.display())))?;
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        sync_path(parent)?;
    }
    Ok(())
}

/// Whether process `pid` is this one or still running (Linux's /proc).
pub(crate) fn pid_alive(pid: u32) -> bool {
    pid == std::process::id() || Path::new(&format!("/proc/{pid}")).exists()
}

/// Removes what killed processes left in `dir`: `.NAME.tmp-PID` files and
/// folders of processes no longer alive, and puts back a `.NAME.old-PID`
/// folder whose replacement never arrived. Returns what it removed or
/// restored. Call it when a run starts, before writing anything.
pub fn clean_stale_temporaries(dir: &Path) -> Result<Vec<PathBuf>, FsError> {
    let mut touched = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(touched);
    };
    for e in entries {
        let path = e
            .map_err(io(|| format!("cannot read {}", dir.display())))?
            .path();
        let file = path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .into_owned();
        let Some(rest) = file.strip_prefix('.') else {
            continue;
        };
        for (marker, restore) in [(".tmp-", false), (".old-", true)] {
            let Some((name, pid)) = rest.rsplit_once(marker) else {
                continue;
            };
            let Ok(pid) = pid.parse::<u32>() else {
                continue;
            };
            if pid != std::process::id() && pid_alive(pid) {
                continue;
            }
            let target = dir.join(name);
            let done = if restore && !target.exists() {
                std::fs::rename(&path, &target)
            } else if path.is_dir() {
                std::fs::remove_dir_all(&path)
            } else {
                std::fs::remove_file(&path)
            };
            done.map_err(io(|| format!("cannot clean up {}", path.display())))?;
            touched.push(path.clone());
        }
    }
    Ok(touched)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bare_name_lives_in_the_working_folder() {
        assert_eq!(parent_dir(Path::new("out")), Path::new("."));
        assert_eq!(parent_dir(Path::new("runs/out")), Path::new("runs"));
        assert_eq!(parent_dir(Path::new("/out")), Path::new("/"));
    }
}
