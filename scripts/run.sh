#!/usr/bin/env bash
# Sets up a fresh machine and runs the default job on the maps the project
# ships, all under runs/default/:
#  1. the heuristic captors against the rule-based target (the paper's
#     protocol, 3:1, speed ratio 1.0): table, SoA plot, one rendered episode;
#  2. a short MAPPO training run (configs/quick.toml): metrics, curves,
#     checkpoints; then its checkpoint evaluated with the same protocol.
# The league (`t2e-league run`) replaces this job once it exists.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
bin=./target/release/t2e-league
out=runs/default
$bin maps list --maps shipped
$bin eval --maps shipped --k 3 --speed-ratio 1.0 --episodes 200 --episode-length 500 --seed 0 --out $out
$bin render --maps shipped --seed 3 --every 2 --out $out/episode.gif
rm -rf $out/quick
$bin train --config configs/quick.toml --out $out/quick
$bin eval --captors ckpt:$out/quick --maps shipped --k 3 --speed-ratio 1.0 --episodes 50 --episode-length 500 --seed 0 --soa-every 10 --out $out/quick/eval
echo "== results in $out: table.md, summary.json, */soa.png, episode.gif; quick/ (training run: metrics.csv, curves.png, checkpoints/, eval/)"
