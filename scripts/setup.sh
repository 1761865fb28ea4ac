#!/usr/bin/env bash
# Sets up a fresh machine: a project-local virtualenv with PyTorch 2.11.0 from
# PyPI (the libtorch that tch 0.24 expects), a ./libtorch link to its torch
# folder (read by .cargo/config.toml), a release build of t2e-league, and the
# Python package (`import t2e`, built from python/ with maturin) with what its
# tests use. Idempotent: a second run only rebuilds what changed.
# --no-build: the virtualenv and its packages only.
# --trainers: also the MARL trainers the Python tests run the env with
#   (the test command's; the default job needs none of them).
set -euo pipefail
cd "$(dirname "$0")/.."
build=1
trainers=0
for arg in "$@"; do
  case $arg in
    --no-build) build=0 ;;
    --trainers) trainers=1 ;;
    *) echo "setup.sh: unknown argument $arg (expected --no-build, --trainers)" >&2; exit 2 ;;
  esac
done

TORCH_VERSION=2.11.0
PYTHON=${PYTHON:-python3}
# The Python side: the build backend, the env's dependencies, the test runner.
PY_PACKAGES="maturin==1.16.0 numpy==2.4.6 gymnasium==1.4.0 pettingzoo==1.27.0 pytest==9.2.0"
# The trainers the Python tests run the env with (python/pyproject.toml's
# `trainers` group), pinned with what they pull in. TorchRL is BenchMARL's
# (benchmarl 1.5.2 imports SyncDataCollector, gone from torchrl 0.14).
# Ray comes without its `rllib` extra, whose packages are listed instead:
# the extra pins gymnasium 1.2.2, and RLlib's PPO runs on our 1.4.0.
TRAINER_PACKAGES="supersuit==3.11.0 tinyscaler==1.2.8 stable-baselines3==2.9.2 matplotlib==3.11.2 cloudpickle==3.1.3 \
  torchrl==0.11.1 tensordict==0.11.0 benchmarl==1.5.2 torchvision==0.26.0 hydra-core==1.3.8 av==13.1.0 \
  ray==2.60.0 pandas==3.1.1 pyarrow==26.0.1 scipy==1.17.1 dm-tree==0.1.10 lz4==4.4.5 ormsgpack==1.13.1 \
  tensorboardX==2.6.5 pydantic==2.14.4 pyyaml==6.0.4 requests==2.34.2 fsspec==2026.9.0"

if [ ! -x .venv/bin/python ]; then
  echo "== creating .venv"
  "$PYTHON" -m venv .venv
fi
if [ -z "${LIBTORCH:-}" ]; then
  if ! .venv/bin/python -c "import torch, sys; sys.exit(torch.__version__.split('+')[0] != '$TORCH_VERSION')" 2>/dev/null; then
    echo "== installing torch==$TORCH_VERSION into .venv (about 5 GB, about a minute)"
    .venv/bin/python -m pip install --quiet --upgrade pip
    .venv/bin/python -m pip install --quiet "torch==$TORCH_VERSION"
  fi
  torch_dir=$(.venv/bin/python -c 'import torch, os; print(os.path.dirname(torch.__file__))')
  ln -sfn "$torch_dir" libtorch
  echo "== libtorch -> $torch_dir"
fi
# Pinned: a second run finds them installed and reaches no index.
# shellcheck disable=SC2086
.venv/bin/python -m pip install --quiet $PY_PACKAGES
if [ "$trainers" = 1 ]; then
  echo "== the trainers the Python tests use (SuperSuit, SB3, TorchRL, BenchMARL, RLlib)"
  # shellcheck disable=SC2086
  .venv/bin/python -m pip install --quiet $TRAINER_PACKAGES
fi

if [ "$build" = 1 ]; then
  echo "== cargo build --release"
  cargo build --release
  echo "== pip install ./python (import t2e)"
  PATH="$PWD/.venv/bin:$PATH" .venv/bin/python -m pip install --quiet --no-build-isolation ./python
fi
