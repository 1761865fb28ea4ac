//! ARCHITECTURE.md against the tree: every repository path it names in
//! backticks exists, every test it names beside a path (`FILE::test`) is
//! defined in that file, and the page stays short enough to be read whole
//! (500 lines at most: the code map is the code's own).

use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn architecture() -> String {
    std::fs::read_to_string(root().join("ARCHITECTURE.md")).expect("ARCHITECTURE.md")
}

/// Inline code spans outside fenced blocks, each with its line number. A
/// line with an odd number of backticks is an error: a code span broken
/// across lines would pair the wrong backticks.
fn code_spans(text: &str) -> Result<Vec<(usize, String)>, String> {
    let mut spans = Vec::new();
    let mut fenced = false;
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        if line.matches('`').count() % 2 == 1 {
            return Err(format!(
                "ARCHITECTURE.md line {n}: an odd number of backticks; keep each code span on one line"
            ));
        }
        for span in line.split('`').skip(1).step_by(2) {
            spans.push((n, span.to_string()));
        }
    }
    Ok(spans)
}

/// A backticked token that names a file or folder of the repository, as
/// (path, test name): it contains a '/' or ends in a source or document
/// extension, once a `::name` suffix is taken off. Not paths: anything with
/// a space, '*', '<' or '{', a URL, a run folder (`runs/`), an option
/// (leading '-'), or a path outside the repository (`../`).
fn repository_path(token: &str) -> Option<(&str, Option<&str>)> {
    if token.contains([' ', '*', '<', '{'])
        || token.contains("://")
        || token.contains("runs/")
        || token.starts_with('-')
        || token.starts_with("../")
    {
        return None;
    }
    let (path, name) = match token.split_once("::") {
        Some((path, name)) => (path, Some(name)),
        None => (token, None),
    };
    let looks_like_path = path.contains('/')
        || [".rs", ".md", ".toml", ".py", ".sh"]
            .iter()
            .any(|ext| path.ends_with(ext));
    looks_like_path.then_some((path, name))
}

/// Whether `file` defines the function or test `name`: `fn name(` or
/// `fn name<` in Rust, `def name(` in Python.
fn defines(file: &Path, text: &str, name: &str) -> bool {
    if file.extension().is_some_and(|e| e == "py") {
        text.contains(&format!("def {name}("))
    } else {
        text.contains(&format!("fn {name}(")) || text.contains(&format!("fn {name}<"))
    }
}

#[test]
fn every_path_architecture_names_exists() {
    let text = architecture();
    let spans = code_spans(&text).unwrap_or_else(|e| panic!("{e}"));
    let mut missing = Vec::new();
    let (mut paths, mut tests) = (0, 0);
    for (line, token) in &spans {
        let Some((path, name)) = repository_path(token) else {
            continue;
        };
        paths += 1;
        let file = root().join(path);
        if !file.exists() {
            missing.push(format!(
                "line {line}: `{path}` does not exist; name the path as the tree has it, or drop it"
            ));
            continue;
        }
        let Some(name) = name else { continue };
        tests += 1;
        let found = std::fs::read_to_string(&file).is_ok_and(|src| defines(&file, &src, name));
        if !found {
            missing.push(format!(
                "line {line}: `{path}` defines no `{name}`; name the test that holds the invariant, or drop the claim"
            ));
        }
    }
    assert!(
        paths > 50 && tests > 30,
        "only {paths} paths and {tests} tests found in ARCHITECTURE.md: is the parser broken?"
    );
    assert!(
        missing.is_empty(),
        "{} names in ARCHITECTURE.md are not in the tree:\n{}",
        missing.len(),
        missing.join("\n")
    );
}

#[test]
fn architecture_is_at_most_500_lines() {
    let lines = architecture().lines().count();
    assert!(
        lines <= 500,
        "ARCHITECTURE.md has {lines} lines: keep it to 500, stating facts and invariants and leaving the file map to the code"
    );
}

#[test]
fn architecture_speaks_of_the_code_not_of_how_the_work_was_organised() {
    let words = super::links::process_words(&architecture());
    assert!(
        words.is_empty(),
        "ARCHITECTURE.md mentions {words:?}: say what the code does instead"
    );
}

#[test]
fn the_path_parser_takes_paths_and_tests_and_leaves_the_rest() {
    assert_eq!(
        repository_path("league/src/run/folder/pool.rs"),
        Some(("league/src/run/folder/pool.rs", None))
    );
    assert_eq!(
        repository_path("tests/integration/docs/layering.rs::some_test"),
        Some(("tests/integration/docs/layering.rs", Some("some_test")))
    );
    assert_eq!(
        repository_path("crates/core/src/"),
        Some(("crates/core/src/", None))
    );
    assert_eq!(repository_path("Cargo.toml"), Some(("Cargo.toml", None)));
    for not_a_path in [
        "league::rules::config",
        "t2e_core::env",
        "greedy:K",
        "--store URL",
        "runs/league/NAME",
        "https://example.org/a.md",
        "league/migrations/{sqlite,postgres}",
        "Result<_, String>",
        "checkpoints/*",
        "../shared/T2E-SPEC.md",
        "meta.json",
    ] {
        assert_eq!(repository_path(not_a_path), None, "{not_a_path}");
    }
    let spans = code_spans("a `x/y.rs` b\n```\n`fenced/z.rs`\n```\n`t.md::f`\n").unwrap();
    assert_eq!(
        spans,
        vec![(1, "x/y.rs".to_string()), (5, "t.md::f".to_string())]
    );
    assert!(code_spans("broken `span\nacross lines`").is_err());
}
