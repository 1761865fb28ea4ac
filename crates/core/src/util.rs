//! Small helpers shared across the crate: hashing files and text, and names
//! safe to use as one folder component.

use sha2::{Digest, Sha256};
use std::io::Read;
use std::path::Path;
use std::time::Duration;

/// Lower-case hex of bytes.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// SHA-256 (hex) of some bytes.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// SHA-256 (hex) of a file's content, streamed.
pub fn sha256_file(path: &Path) -> std::io::Result<String> {
    let mut f = std::fs::File::open(path)?;
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    loop {
        let n = f.read(&mut buf)?;
        if n == 0 {
            break;
        }
        h.update(&buf[..n]);
    }
    Ok(hex(&h.finalize()))
}

/// Text made safe as a single path component: letters, digits, '-', '_'
/// and '+' are kept, every other run of characters becomes one '_', and the
/// result is cut to `max` characters. Never empty, never "." or "..", never
/// holds a separator: a folder named from it stays inside its parent.
pub fn safe_component(text: &str, max: usize) -> String {
    let mut out = String::new();
    let mut gap = false;
    for ch in text.chars() {
        if ch.is_ascii_alphanumeric() || matches!(ch, '-' | '_' | '+') {
            if gap && !out.is_empty() {
                out.push('_');
            }
            gap = false;
            out.push(ch);
        } else {
            gap = true;
        }
    }
    out.truncate(max);
    if out.is_empty() {
        out.push('_');
    }
    out
}

/// A TOML text that does not fit its schema, at `path` (`target.play`; `.`
/// for the whole document).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}{message}", if path == "." { String::new() } else { format!("{path}: ") })]
pub struct TomlError {
    pub path: String,
    pub message: String,
}

/// Reads a TOML document into `T`; the error names the field it stopped
/// at, which toml's own message leaves to a line number.
pub fn from_toml<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, TomlError> {
    serde_path_to_error::deserialize(toml::Deserializer::new(text)).map_err(|e| TomlError {
        path: e.path().to_string(),
        message: e.into_inner().to_string(),
    })
}

/// A duration option that cannot be read: `--for 0: must be more than 0`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{option} {text}: {why}")]
pub struct DurationError {
    pub option: String,
    pub text: String,
    pub why: String,
}

/// Parses a wall-clock duration given to `option` (`--for`,
/// `--eval-every`): `90` or `90s`, `10m`, `2h`; more than 0, at most 30
/// days, and finite, so 0, negatives and garbage are refused by name.
pub fn parse_duration(option: &str, text: &str) -> Result<Duration, DurationError> {
    let refuse = |why: String| DurationError {
        option: option.to_string(),
        text: text.to_string(),
        why,
    };
    let t = text.trim();
    let (num, unit) = match t.char_indices().find(|(_, c)| c.is_ascii_alphabetic()) {
        Some((i, _)) => (&t[..i], &t[i..]),
        None => (t, "s"),
    };
    let n: f64 = num
        .parse()
        .map_err(|_| refuse("expected a duration such as 90s, 10m or 2h".into()))?;
    let secs = match unit {
        "s" => n,
        "m" | "min" => n * 60.0,
        "h" => n * 3600.0,
        _ => return Err(refuse(format!("unknown unit '{unit}' (s, m or h)"))),
    };
    if !(secs.is_finite() && secs > 0.0 && secs <= 30.0 * 86400.0) {
        return Err(refuse("must be more than 0 and at most 30 days".into()));
    }
    Ok(Duration::from_secs_f64(secs))
}

/// How many threads a process takes when nobody said: libtorch and rayon
/// each assume they own every core, and beside one other busy process a
/// run that did fell 15x (491 env steps/s on 2 threads against 7,417 on 1).
/// `asked` (a `--threads` of 1 or more) wins; then `OMP_NUM_THREADS`, the
/// convention libtorch reads; else the cores the 1-minute load average
/// leaves free, at least one. Returns the count and where it came from.
pub fn thread_count(asked: usize) -> (usize, String) {
    if asked > 0 {
        return (asked, "--threads".into());
    }
    if let Some(n) = std::env::var("OMP_NUM_THREADS")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
        .filter(|n| *n > 0)
    {
        return (n, "OMP_NUM_THREADS".into());
    }
    let cores = cores();
    match load_average() {
        Some(load) => (
            free_cores(cores, load),
            format!("the free cores: {cores} cores, load {load:.1}"),
        ),
        None => (cores, format!("{cores} cores")),
    }
}

/// The machine's cores (as the scheduler lets this process use them).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// The 1-minute load average (Linux), None where it cannot be read.
pub fn load_average() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// Cores the other processes leave: `cores` less the load, rounded, at
/// least one.
pub fn free_cores(cores: usize, load: f64) -> usize {
    let busy = if load.is_finite() && load > 0.0 {
        load.round() as usize
    } else {
        0
    };
    cores.saturating_sub(busy).clamp(1, cores.max(1))
}

/// The running binary, for spawning copies of this program (learners,
/// workers, periodic evaluations). On Linux `/proc/self/exe`, which still
/// opens the file this process was started from after a rebuild replaced
/// it on disk; `current_exe` then names a path that is gone (" (deleted)"),
/// and a training run beside a `cargo build` would lose every periodic
/// evaluation.
pub fn own_exe() -> std::io::Result<std::path::PathBuf> {
    let proc_exe = std::path::Path::new("/proc/self/exe");
    if proc_exe.exists() {
        Ok(proc_exe.to_path_buf())
    } else {
        std::env::current_exe()
    }
}

/// A command that runs this program again (`own_exe`), shown in `ps` under
/// the path it was started from.
pub fn own_command() -> std::io::Result<std::process::Command> {
    use std::os::unix::process::CommandExt;
    let mut cmd = std::process::Command::new(own_exe()?);
    if let Ok(path) = std::env::current_exe() {
        let shown = path.to_string_lossy().into_owned();
        cmd.arg0(shown.trim_end_matches(" (deleted)"));
    }
    Ok(cmd)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_busy_machine_gets_fewer_threads_and_never_none() {
        assert_eq!(free_cores(2, 0.05), 2);
        assert_eq!(free_cores(2, 1.0), 1);
        assert_eq!(free_cores(2, 0.6), 1);
        assert_eq!(free_cores(2, 7.0), 1);
        assert_eq!(free_cores(16, 3.4), 13);
        assert_eq!(free_cores(4, f64::NAN), 4);
        assert_eq!(thread_count(3).0, 3);
    }

    #[test]
    fn safe_components_never_leave_their_folder() {
        assert_eq!(safe_component("ckpt:../../etc/x", 60), "ckpt_etc_x");
        assert_eq!(safe_component("..", 60), "_");
        assert_eq!(safe_component("heuristic", 60), "heuristic");
        assert_eq!(safe_component("a/b\\c d", 3), "a_b");
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn durations_parse_and_nonsense_is_refused() {
        assert_eq!(
            parse_duration("--for", "90").unwrap(),
            Duration::from_secs(90)
        );
        assert_eq!(
            parse_duration("--for", "10m").unwrap(),
            Duration::from_secs(600)
        );
        assert_eq!(
            parse_duration("--for", "1.5h").unwrap(),
            Duration::from_secs(5400)
        );
        for bad in ["", "0", "-5m", "10x", "nanm", "1e9h", "0s"] {
            let e = parse_duration("--eval-every", bad).unwrap_err();
            assert!(e.to_string().starts_with("--eval-every"), "{bad}: {e}");
        }
    }
}
