#!/usr/bin/env bash
# Sets up a fresh machine and runs the default job on the maps the project
# ships: the heuristic captors against the rule-based target (the paper's
# protocol, 3:1, speed ratio 1.0), its table, SoA plot and one rendered
# episode, all under runs/default/.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
bin=./target/release/t2e-league
$bin maps list --maps shipped
$bin eval --maps shipped --k 3 --speed-ratio 1.0 --episodes 200 --episode-length 500 --seed 0 --out runs/default
$bin render --maps shipped --seed 3 --every 2 --out runs/default/episode.gif
echo "== results in runs/default: table.md, summary.json, */soa.png, episode.gif"
