//! The documentation checked against the code: every relative link in
//! README.md and docs/ resolves, every page is in docs/SUMMARY.md, the CLI
//! reference is what the binary generates, the config references list every
//! field, the README's quick start runs, and the core crate stays below
//! libtorch and the database (ARCHITECTURE.md).
mod architecture;
mod cli_reference;
mod config_reference;
mod configs;
mod imports;
mod layering;
mod links;
mod quickstart;
mod readme_figures;
