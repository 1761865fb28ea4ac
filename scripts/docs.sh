#!/usr/bin/env bash
# Builds the documentation: regenerates the CLI reference and the man pages
# from the binary's clap definitions, then builds the mdBook in docs/ into
# target/book/ (open target/book/index.html). Installs mdbook with cargo if
# it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
./target/release/t2e-league generate-docs --out docs/reference
if ! command -v mdbook >/dev/null; then
  echo "== cargo install mdbook"
  cargo install mdbook --locked --version '^0.4'
fi
mdbook build docs
echo "== the book is in target/book/index.html"
