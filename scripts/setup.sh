#!/usr/bin/env bash
# Sets up a fresh machine: a project-local virtualenv with PyTorch 2.11.0 from
# PyPI (the libtorch that tch 0.24 expects), a ./libtorch link to its torch
# folder (read by .cargo/config.toml), and a release build of t2e-league.
# Idempotent: a second run only rebuilds what changed.
set -euo pipefail
cd "$(dirname "$0")/.."

TORCH_VERSION=2.11.0
PYTHON=${PYTHON:-python3}

if [ -z "${LIBTORCH:-}" ]; then
  if [ ! -x .venv/bin/python ]; then
    echo "== creating .venv"
    "$PYTHON" -m venv .venv
  fi
  if ! .venv/bin/python -c "import torch, sys; sys.exit(torch.__version__.split('+')[0] != '$TORCH_VERSION')" 2>/dev/null; then
    echo "== installing torch==$TORCH_VERSION into .venv (about 5 GB, about a minute)"
    .venv/bin/python -m pip install --quiet --upgrade pip
    .venv/bin/python -m pip install --quiet "torch==$TORCH_VERSION"
  fi
  torch_dir=$(.venv/bin/python -c 'import torch, os; print(os.path.dirname(torch.__file__))')
  ln -sfn "$torch_dir" libtorch
  echo "== libtorch -> $torch_dir"
fi

if [ "${1:-}" != "--no-build" ]; then
  echo "== cargo build --release"
  cargo build --release
fi
