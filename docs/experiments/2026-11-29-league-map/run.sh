#!/usr/bin/env bash
# The league with sight and a coarse map (league-map.toml), tested as the
# sighted league was: the same stages, test teams, settings and table
# (../2026-11-29-league-sight/run.sh and its paired.py).
#   bash run.sh BIN LEAGUE OUT MAPPO_RUN MAPPO_SIGHT_RUN [STAGE...]
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
CONFIG=$here/league-map.toml exec bash "$here/../2026-11-29-league-sight/run.sh" "$@"
