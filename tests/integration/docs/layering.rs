//! ARCHITECTURE.md's floors as the build sees them: the core crate reaches
//! neither libtorch nor a database, by any path through its dependencies,
//! so it builds and tests where neither is installed.

#[test]
fn the_core_crate_depends_on_no_libtorch_and_no_database() {
    let out = std::process::Command::new(env!("CARGO"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "tree",
            "--offline",
            "-p",
            "t2e-core",
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
    let tree = String::from_utf8_lossy(&out.stdout);
    let crates: Vec<&str> = tree
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect();
    assert!(
        crates.contains(&"t2e-core") && crates.contains(&"rayon"),
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
            !crates.contains(&banned),
            "t2e-core reaches {banned}:\n{tree}"
        );
    }
}
