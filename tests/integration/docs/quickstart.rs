//! The README's quick start, run as written with tiny budgets: every `sh`
//! block of its "Quick start" section, in order, in one shell, in a fresh
//! folder that holds links to the project's configs, maps and scripts.
//! Only budgets are changed (durations, episodes, a best response's env
//! steps), so a renamed flag, a moved config or a command that no longer
//! finds what the one before it wrote fails here.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The text of the `sh` code blocks of the section headed `heading`.
pub fn sh_blocks(markdown: &str, heading: &str) -> Vec<String> {
    let start = markdown
        .find(&format!("\n{heading}\n"))
        .unwrap_or_else(|| panic!("README.md has no '{heading}' section"));
    let section = &markdown[start + heading.len() + 2..];
    let section = &section[..section.find("\n## ").unwrap_or(section.len())];
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in section.lines() {
        match (&mut current, line.trim_end()) {
            (None, "```sh") => current = Some(String::new()),
            (Some(block), "```") => {
                blocks.push(std::mem::take(block));
                current = None;
            }
            (Some(block), text) => {
                block.push_str(text);
                block.push('\n');
            }
            (None, _) => {}
        }
    }
    blocks
}

/// The budget of a command made tiny: the value after each flag named here
/// is replaced, everything else stays as written.
const TINY_BUDGETS: &[(&str, &str)] =
    &[("--for", "25s"), ("--episodes", "2"), ("--budget", "3200")];

pub fn with_tiny_budgets(line: &str) -> String {
    let mut words: Vec<String> = line.split(' ').map(str::to_string).collect();
    for i in 0..words.len().saturating_sub(1) {
        if let Some((_, tiny)) = TINY_BUDGETS.iter().find(|(flag, _)| words[i] == *flag) {
            words[i + 1] = tiny.to_string();
        }
    }
    words.join(" ")
}

#[test]
fn the_quick_start_blocks_are_found_and_made_tiny() {
    let md = "# x\n\n## Quick start\n\ntext\n\n```sh\na --for 10m\n```\n\n```text\nno\n```\n\n```sh\nb --episodes 500 --out o\n```\n\n## Next\n\n```sh\nc\n```\n";
    assert_eq!(
        sh_blocks(md, "## Quick start"),
        vec!["a --for 10m\n", "b --episodes 500 --out o\n"]
    );
    assert_eq!(
        with_tiny_budgets("t --for 10m --episodes 500 --budget 200000 --out x"),
        "t --for 25s --episodes 2 --budget 3200 --out x"
    );
}

fn link(from: &Path, to: &Path) {
    std::os::unix::fs::symlink(from, to).unwrap();
}

#[test]
fn every_quick_start_command_runs() {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let blocks = sh_blocks(&readme, "## Quick start");
    assert!(
        blocks.len() >= 4,
        "the quick start has {} sh blocks",
        blocks.len()
    );
    let script: String = blocks
        .iter()
        .flat_map(|b| b.lines())
        .map(|line| with_tiny_budgets(line) + "\n")
        .collect();
    for command in [
        "eval", "train", "run", "status", "export", "exploit", "worker",
    ] {
        assert!(
            script.contains(&format!("t2e-league {command} "))
                || script.contains(&format!("t2e-league {command}\n")),
            "the quick start no longer shows `{command}`"
        );
    }

    let dir = tempfile::tempdir().unwrap();
    for name in ["configs", "maps", "scripts"] {
        link(&root().join(name), &dir.path().join(name));
    }
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_t2e-league"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let gibson = std::env::var("T2E_GIBSON_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|_| root().join("../shared/maps/gibson"));
    let out = Command::new("bash")
        .arg("-c")
        .arg(format!("set -euo pipefail -x\n{script}"))
        .current_dir(dir.path())
        .env("PATH", path)
        .env("T2E_GIBSON_DIR", gibson)
        .env("OMP_NUM_THREADS", "1")
        .env("RAYON_NUM_THREADS", "1")
        .output()
        .unwrap();
    let text = format!(
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.status.success(),
        "the quick start failed ({}):\n{text}",
        out.status
    );
    // What the commands wrote, each read back by the command after it.
    for written in [
        "runs/eval/heuristics",
        "runs/episode.gif",
        "runs/cpu-10min",
        "runs/league/default/league.db",
        "runs/export/target/meta.json",
    ] {
        assert!(
            dir.path().join(written).exists(),
            "the quick start did not write {written}:\n{text}"
        );
    }
}
