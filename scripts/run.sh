#!/usr/bin/env bash
# Sets up a fresh machine and runs the default job on the maps the project
# ships, all under runs/default/:
#  1. the heuristic captors against the rule-based target (the paper's
#     protocol, 3:1, speed ratio 1.0): table, SoA plot, one rendered episode;
#  2. a short league (configs/league-default.toml, about two minutes per
#     learner on 2 cores): MAPPO captors and MAPPO target against pools of
#     each other's snapshots and the heuristics;
#  3. the league's status, the export of the best member of each side, and
#     the evaluation of both exports against the heuristics, with the
#     heuristics alone on the same episodes as the bar.
# Training maps are the shipped generated maps; evaluation here uses them
# too (the Gibson test maps are for `eval --maps small,medium,large`).
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
bin=./target/release/t2e-league
out=runs/default
rm -rf "$out"
$bin maps list --maps shipped
# SoA every 10th step: the per-robot fields cost several ms a step.
$bin eval --maps shipped --k 3 --speed-ratio 1.0 --episodes 200 --episode-length 500 --seed 0 --soa-every 10 --out $out/heuristics
$bin render --maps shipped --seed 3 --every 2 --out $out/episode.gif
$bin run --config configs/league-default.toml --dir $out/league
$bin status --dir $out/league --plot $out/league.png | tee $out/status.txt
$bin status --dir $out/league --json > $out/status.json
best() {
  python3 -c "import json,sys; r=json.load(open('$out/status.json')); p=[x for x in r['players'] if x['side']=='$1' and x['kind']!='heuristic' and x['games']>0 and not x['quarantined']]; print(max(p, key=lambda x: x['bt_elo'])['name'])"
}
captors=$(best captors)
target=$(best target)
$bin export "$captors" --dir $out/league --out $out/export-captors
$bin export "$target" --dir $out/league --out $out/export-target
$bin eval --captors ckpt:$out/export-captors --maps shipped --k 3 --speed-ratio 1.0 --episodes 100 --episode-length 500 --seed 0 --soa-every 0 --out $out/eval-captors
$bin eval --target ckpt:$out/export-target --maps shipped --k 3 --speed-ratio 1.0 --episodes 100 --episode-length 500 --seed 0 --soa-every 0 --out $out/eval-target
# The bar for both lines above: the rule-based robots on the same 100
# episodes (same seed, same starts).
echo "== the rule-based baseline on the same episodes"
$bin eval --maps shipped --k 3 --speed-ratio 1.0 --episodes 100 --episode-length 500 --seed 0 --soa-every 0 --out $out/eval-baseline
echo "== results in $out: heuristics/ (table, SoA), episode.gif, league/ (the league), status.txt, export-*/ (best members), eval-*/ (them against the heuristics; eval-baseline: the heuristics alone, the bar)"
