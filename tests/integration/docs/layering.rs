//! ARCHITECTURE.md's floors as the build sees them: the core crate reaches
//! neither libtorch nor a database, by any path through its dependencies,
//! so it builds and tests where neither is installed; the learners' crate
//! reaches no database and not the league.

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
