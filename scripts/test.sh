#!/usr/bin/env bash
# The test command (README, CI): installs what a fresh machine lacks, then
# runs every test against the Gibson maps in ../shared/maps/gibson.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh --no-build
cargo test --release "$@"
