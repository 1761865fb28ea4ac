//! ARCHITECTURE.md's floors as the build sees them: the core crate reaches
//! neither libtorch nor a database, by any path through its dependencies,
//! so it builds and tests where neither is installed; the learners' crate
//! reaches no database and not the league; the league crate has no command
//! line, and its rules name neither its store nor its processes.

/// Every package `package` reaches through its normal and build
/// dependencies, itself included.
fn reached_by(package: &str) -> Vec<String> {
    let out = std::process::Command::new(env!("CARGO"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "tree",
            "--offline",
            "-p",
            package,
            "--edges",
            "normal,build",
            "--prefix",
            "none",
            "--format",
            "{p}",
        ])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect()
}

#[test]
fn the_core_crate_depends_on_no_libtorch_and_no_database() {
    let crates = reached_by("t2e-core");
    let tree = crates.join("\n");
    assert!(
        crates.iter().any(|c| c == "t2e-core") && crates.iter().any(|c| c == "rayon"),
        "{tree}"
    );
    for banned in [
        "tch",
        "torch-sys",
        "sqlx",
        "sqlx-core",
        "libsqlite3-sys",
        "tokio",
    ] {
        assert!(
            !crates.iter().any(|c| c == banned),
            "t2e-core reaches {banned}:\n{tree}"
        );
    }
}

#[test]
fn the_learners_crate_depends_on_no_database_and_not_on_the_league() {
    let crates = reached_by("t2e-learners");
    let tree = crates.join("\n");
    assert!(
        ["t2e-learners", "t2e-core", "tch"]
            .iter()
            .all(|want| crates.iter().any(|c| c == want)),
        "{tree}"
    );
    for banned in [
        "t2e-league",
        "league",
        "sqlx",
        "sqlx-core",
        "libsqlite3-sys",
        "tokio",
        "skillratings",
    ] {
        assert!(
            !crates.iter().any(|c| c == banned),
            "t2e-learners reaches {banned}:\n{tree}"
        );
    }
}

#[test]
fn the_league_crate_has_no_command_line_and_sits_below_the_cli() {
    let crates = reached_by("league");
    let tree = crates.join("\n");
    assert!(
        ["league", "t2e-learners", "t2e-core", "sqlx"]
            .iter()
            .all(|want| crates.iter().any(|c| c == want)),
        "{tree}"
    );
    assert!(
        !crates.iter().any(|c| c == "t2e-league"),
        "the league crate reaches the CLI's package:\n{tree}"
    );
    // Its own dependencies, as its manifest names them: no argument parser
    // (the learners' crate still carries clap for its own flags).
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("league/Cargo.toml");
    let text = std::fs::read_to_string(&manifest).unwrap();
    let table: toml::Table = text.parse().unwrap();
    for section in ["dependencies", "build-dependencies"] {
        if let Some(deps) = table.get(section).and_then(|d| d.as_table()) {
            for banned in ["clap", "clap_mangen", "clap-markdown", "t2e-league"] {
                assert!(
                    !deps.contains_key(banned),
                    "{}: [{section}] names {banned}",
                    manifest.display()
                );
            }
        }
    }
}

/// The words by which league code reaches the store or the processes.
const STORE_OR_PROCESSES: [&str; 4] = ["crate::store", "crate::run", "sqlx", "std::process"];

#[test]
fn the_league_rules_name_neither_the_store_nor_the_processes() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("league/src/rules");
    let mut files = 0;
    for entry in std::fs::read_dir(&root).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        // Tests may build their data any way they like.
        let code = match text.find("#[cfg(test)]") {
            Some(at) => &text[..at],
            None => &text[..],
        };
        for banned in STORE_OR_PROCESSES {
            assert!(
                !code.contains(banned),
                "{} names {banned}: the rules compute from data alone",
                path.display()
            );
        }
        // A rule's errors are typed (`ConfigError` and the like), so a
        // caller can tell them apart; anyhow belongs to the command line.
        assert!(
            !code.contains("anyhow"),
            "{} uses anyhow: the rules' errors are typed",
            path.display()
        );
        files += 1;
    }
    assert!(files >= 10, "{files} files in {}", root.display());
    // And the data they compute with has no process either.
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("league/src/data.rs");
    let text = std::fs::read_to_string(&data).unwrap();
    for banned in ["crate::store", "crate::run", "std::process"] {
        assert!(!text.contains(banned), "{} names {banned}", data.display());
    }
}

/// The modules of `crates/learners/src/learn` (a folder is one module) and
/// the learn modules each names, from the tree's file imports
/// (imports.rs); "mod" is learn/mod.rs.
fn learn_imports() -> std::collections::BTreeMap<String, std::collections::BTreeSet<String>> {
    use std::collections::{BTreeMap, BTreeSet};
    use std::path::Path;
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let learn = Path::new("crates/learners/src/learn");
    let module = |file: &Path| -> Option<String> {
        let rel = file.strip_prefix(learn).ok()?;
        let first = rel.iter().next()?.to_string_lossy().into_owned();
        Some(first.trim_end_matches(".rs").to_string())
    };
    let mut graph: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (file, targets) in super::imports::file_imports(repo) {
        let Some(from) = module(&file) else { continue };
        let names = graph.entry(from.clone()).or_default();
        names.extend(
            targets
                .iter()
                .filter_map(|t| module(t))
                .filter(|t| *t != from),
        );
    }
    graph
}

#[test]
fn the_learn_floor_has_no_import_circle_and_its_side_configs_are_a_leaf() {
    let graph = learn_imports();
    for module in [
        "side_config",
        "learner",
        "kind",
        "run_config",
        "train",
        "ppo",
    ] {
        assert!(graph.contains_key(module), "no learn::{module}: {graph:?}");
    }
    // The reader sees what it must: the registry names the algorithms,
    // and the algorithms their settings.
    assert!(
        graph["kind"].contains("mappo") && graph["kind"].contains("maac"),
        "{:?}",
        graph["kind"]
    );
    assert!(graph["ppo"].contains("side_config"), "{:?}", graph["ppo"]);
    assert!(
        graph["side_config"].is_empty(),
        "learn::side_config imports {:?}: the settings structs are a leaf",
        graph["side_config"]
    );
    for algorithm in ["ppo", "mappo", "ippo", "maddpg", "maac", "offpolicy"] {
        for above in ["kind", "run_config", "train"] {
            assert!(
                !graph[algorithm].contains(above),
                "learn::{algorithm} imports learn::{above}, a floor above it"
            );
        }
    }
    let left = super::imports::on_circles(&graph);
    assert!(
        left.is_empty(),
        "import circle among learn modules: {left:?}"
    );
}

/// Every `.rs` file under `dir`, at any depth.
fn rust_files(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(rust_files(&path));
        } else if path.extension().is_some_and(|x| x == "rs") {
            files.push(path);
        }
    }
    files
}

#[test]
fn the_library_crates_use_no_anyhow() {
    // A library's errors are typed (`LearnError`, `MapLoadError`,
    // `LeagueError`, ...), so a caller can tell them apart; anyhow belongs
    // to the command line. Each entry is a crate's source folder, its
    // manifest beside it.
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    for src in ["crates/core/src", "crates/learners/src", "league/src"] {
        let files = rust_files(&repo.join(src));
        assert!(!files.is_empty(), "no .rs file under {src}");
        for path in files {
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(
                !text.contains("anyhow"),
                "{} mentions anyhow: a library crate's errors are typed",
                path.display()
            );
        }
        let manifest = repo.join(src).parent().unwrap().join("Cargo.toml");
        let table: toml::Table = std::fs::read_to_string(&manifest).unwrap().parse().unwrap();
        for section in ["dependencies", "build-dependencies"] {
            if let Some(deps) = table.get(section).and_then(|d| d.as_table()) {
                assert!(
                    !deps.contains_key("anyhow"),
                    "{}: [{section}] names anyhow",
                    manifest.display()
                );
            }
        }
    }
}
