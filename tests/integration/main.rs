//! Every integration test in one binary, each file a module, so the test
//! command compiles and links libtorch into one test binary rather than
//! one per file. Run one file's tests with `./scripts/test.sh --test
//! integration FILE::` (for example `store::`).
mod bad_inputs;
mod common;
mod conformance;
mod docs;
mod env;
mod eval;
mod exploit;
mod gibson_maps;
mod heuristics;
mod inputs;
mod league;
mod league_faults;
mod league_folders;
mod learn;
mod protocol;
mod sight;
mod slurm;
mod store;
mod stored_runs;
mod tch_smoke;
mod trust;
mod workers;
