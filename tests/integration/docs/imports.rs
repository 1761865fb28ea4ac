//! The files of every crate, and which file each one imports, read from
//! the source: no import circle anywhere in the tree, so no file imports
//! from its own folder's mod.rs what that mod.rs takes from the file's
//! siblings (a child reaching back up to its parent), and a folder's
//! files stand on floors. Test modules are left out: they see their
//! parent's names.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The crates' source roots, from the repository's root.
const CRATES: [&str; 5] = [
    "crates/core/src",
    "crates/learners/src",
    "league/src",
    "src",
    "python/src",
];

fn ident(s: &str) -> String {
    s.chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
        .collect()
}

/// One crate's modules: module path (["run", "status"]) to its file.
fn modules(root: &Path) -> BTreeMap<Vec<String>, PathBuf> {
    let mut found = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().and_then(|e| e.to_str()) != Some("rs") {
                continue;
            }
            let rel = path.strip_prefix(root).unwrap().with_extension("");
            let mut module: Vec<String> = rel
                .iter()
                .map(|c| c.to_string_lossy().into_owned())
                .collect();
            if matches!(module.last().map(String::as_str), Some("mod")) {
                module.pop();
            }
            if module.len() == 1 && matches!(module[0].as_str(), "lib" | "main") {
                if module[0] == "main" {
                    continue;
                }
                module.clear();
            }
            found.insert(module, path);
        }
    }
    found
}

/// The module a path reaches from `base`: down through each segment that
/// names a module, stopping at the first that does not (an item).
fn reach(
    modules: &BTreeMap<Vec<String>, PathBuf>,
    base: &[String],
    segments: &[String],
) -> Vec<String> {
    let mut at = base.to_vec();
    for seg in segments {
        let mut next = at.clone();
        next.push(seg.clone());
        if modules.contains_key(&next) {
            at = next;
        } else {
            break;
        }
    }
    at
}

/// The segments of a path from `text` on (`a::b::{c, d::e}` gives
/// [a, b, c] and [a, b, d, e]).
fn paths_at(text: &str) -> Vec<Vec<String>> {
    let mut head = Vec::new();
    let mut rest = text;
    loop {
        let name = ident(rest);
        if name.is_empty() {
            if let Some(group) = rest.strip_prefix('{') {
                let end = group.find('}').unwrap_or(group.len());
                return group[..end]
                    .split(',')
                    .map(|item| {
                        let mut p = head.clone();
                        for seg in item.trim().split("::") {
                            let seg = ident(seg.trim());
                            if !seg.is_empty() {
                                p.push(seg);
                            }
                        }
                        p
                    })
                    .collect();
            }
            return vec![head];
        }
        rest = &rest[name.len()..];
        head.push(name);
        match rest.strip_prefix("::") {
            Some(r) => rest = r,
            None => return vec![head],
        }
    }
}

/// Every file of the tree and the files it imports (itself left out).
pub(super) fn file_imports(repo: &Path) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let mut graph: BTreeMap<PathBuf, BTreeSet<PathBuf>> = BTreeMap::new();
    for krate in CRATES {
        let root = repo.join(krate);
        let modules = modules(&root);
        for (module, file) in &modules {
            let text = std::fs::read_to_string(file).unwrap();
            let code = match text.find("#[cfg(test)]\nmod tests") {
                Some(at) => &text[..at],
                None => &text[..],
            };
            let children: BTreeSet<String> = modules
                .keys()
                .filter(|m| m.len() == module.len() + 1 && m.starts_with(module))
                .map(|m| m.last().unwrap().clone())
                .collect();
            // Comments name paths too (`crate::fs`): code lines only.
            let code: String = code
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect::<Vec<_>>()
                .join("\n");
            let mut targets = BTreeSet::new();
            let bytes = code.as_bytes();
            let mut starts = Vec::new();
            for (i, &b) in bytes.iter().enumerate() {
                let c = b as char;
                let prev = if i == 0 { ' ' } else { bytes[i - 1] as char };
                if (c.is_ascii_alphabetic() || c == '_')
                    && !(prev.is_ascii_alphanumeric() || prev == '_' || prev == ':')
                    && code[i + ident(&code[i..]).len()..].starts_with("::")
                {
                    starts.push((i, i + ident(&code[i..]).len()));
                }
            }
            for (start, at) in starts {
                let first = &code[start..at];
                let mut ups = 0;
                let base: Vec<String>;
                let mut tail = &code[start..];
                if first == "crate" {
                    base = Vec::new();
                    tail = &tail["crate::".len()..];
                } else if first == "super" {
                    while let Some(t) = tail.strip_prefix("super::") {
                        ups += 1;
                        tail = t;
                    }
                    base = module[..module.len().saturating_sub(ups)].to_vec();
                } else if first == "self" {
                    base = module.clone();
                    tail = &tail["self::".len()..];
                } else if children.contains(first) {
                    base = module.clone();
                } else {
                    continue;
                }
                for path in paths_at(tail) {
                    let reached = reach(&modules, &base, &path);
                    if &reached != module {
                        targets.insert(modules[&reached].clone());
                    }
                }
            }
            let rel = |p: &Path| p.strip_prefix(repo).unwrap().to_path_buf();
            graph
                .entry(rel(file))
                .or_default()
                .extend(targets.iter().map(|t| rel(t)));
        }
    }
    graph
}

/// What of `graph` lies on an import circle, or leads only into one:
/// Kahn's algorithm, whatever cannot be peeled off as a leaf.
pub(super) fn on_circles<T: Ord + Clone>(
    graph: &BTreeMap<T, BTreeSet<T>>,
) -> BTreeMap<T, BTreeSet<T>> {
    let mut left = graph.clone();
    while let Some(leaf) = left
        .iter()
        .find(|(_, targets)| targets.is_empty())
        .map(|(f, _)| f.clone())
    {
        left.remove(&leaf);
        for targets in left.values_mut() {
            targets.remove(&leaf);
        }
    }
    left
}

#[test]
fn no_import_circle_in_the_whole_tree() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let graph = file_imports(repo);
    // The reader sees what it must: a few arrows known to be there.
    let has = |from: &str, to: &str| {
        graph
            .get(Path::new(from))
            .is_some_and(|t| t.contains(Path::new(to)))
    };
    for (from, to) in [
        (
            "league/src/run/processes/manager.rs",
            "league/src/run/processes/supervising_loop.rs",
        ),
        (
            "league/src/store/players.rs",
            "league/src/store/connection.rs",
        ),
        (
            "crates/learners/src/nn/policy.rs",
            "crates/learners/src/nn/run_dir.rs",
        ),
        (
            "crates/learners/src/learn/train/collect.rs",
            "crates/learners/src/learn/train/trainer.rs",
        ),
        ("src/cli/mod.rs", "src/cli/league_commands.rs"),
    ] {
        assert!(
            has(from, to),
            "{from} -> {to} not read: {:?}",
            graph.get(Path::new(from))
        );
    }
    let left = on_circles(&graph);
    let circle: Vec<String> = left
        .iter()
        .map(|(f, t)| {
            format!(
                "{} -> {}",
                f.display(),
                t.iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
        .collect();
    assert!(
        circle.is_empty(),
        "files on an import circle (a child importing what its mod.rs re-exports is one):\n{}",
        circle.join("\n")
    );
}
