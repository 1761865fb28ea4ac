#!/usr/bin/env bash
# Where the planned targets leave the rule-based target's move: the robust
# lookahead target (several captor models) and the single-model lookahead
# target, against test teams they never modelled, on the large
# Gibson maps at 1.0:1.2, with |ASZ| measured every step so that every
# decision is placed by the target's nearest-captor distance and its |ASZ|
# (each setting's departures.csv). Held-out protocol, one thread per
# command, evaluation seed 0 (the same starts for every team and target).
#   bash run.sh BIN OUT
# The MAPPO team is the captors-vs-robust experiment's team R (rule.toml
# there: cooperative MAPPO, 2 M env steps at 1.0:1.2 against the
# rule-based target), trained here if OUT/mappo-rule is not there.
set -euo pipefail
bin=$1
out=$2
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
episodes=${EPISODES:-100}
mkdir -p "$out"
resume=$([ -f "$out/mappo-rule/state.json" ] && echo --resume || true)
"$bin" train --config "$here/../2026-12-02-captors-vs-robust/rule.toml" \
    --out "$out/mappo-rule" --threads 1 --quiet $resume
# SETTINGS: "CAPTORS TEAM TARGET" per setting; the page's, by default.
robust=robust:10:heuristic+expert:1+expert:2
settings=${SETTINGS:-"ckpt:$out/mappo-rule mappo $robust
ckpt:$out/mappo-rule mappo lookahead:10
expert:7 expert7 $robust"}
while read -r captors team target; do
    name=$team-$(echo "$target" | cut -d: -f1)
    "$bin" eval --captors "$captors" --target "$target" --k 3 --speed-ratio 1.2 \
        --maps large --episodes "$episodes" --episode-length 500 --seed 0 \
        --soa-every 1 --quiet --resume --out "$out/$name"
done <<< "$settings"
