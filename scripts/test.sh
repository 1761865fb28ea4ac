#!/usr/bin/env bash
# The test command (README, CI): installs what a fresh machine lacks, then
# runs every test against the Gibson maps in ../shared/maps/gibson: the Rust
# tests, then the Python package's (python/tests). The
# store's tests run against real PostgreSQL servers that the tests start
# with scripts/postgres.sh in a folder of this run's own; they are stopped
# and removed when the tests end, pass or fail.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh --no-build --trainers
T2E_PG_TEST_DIR=$(mktemp -d /tmp/t2e-pg-test.XXXXXX)
chmod 755 "$T2E_PG_TEST_DIR"
export T2E_PG_TEST_DIR
cleanup() {
    for cluster in "$T2E_PG_TEST_DIR"/*/; do
        [ -d "$cluster/data" ] && ./scripts/postgres.sh stop "$cluster" >/dev/null 2>&1 || true
    done
    rm -rf "$T2E_PG_TEST_DIR"
}
trap cleanup EXIT
cargo test --release "$@"
# The Python package, built as a user installs it, and its tests: ours and
# PettingZoo's own API and seed tests. Only for the whole suite: arguments
# select Rust tests.
if [ $# -eq 0 ]; then
  echo "== pip install ./python"
  PATH="$PWD/.venv/bin:$PATH" .venv/bin/python -m pip install --quiet --no-build-isolation ./python
  echo "== pytest python/tests"
  # The trainers' tests fail, not skip, when setup did not install them.
  T2E_TRAINERS_REQUIRED=1 .venv/bin/pytest -q python/tests
fi
