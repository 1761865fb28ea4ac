#!/usr/bin/env bash
# The ceiling of hand-made targets: CMA-ES over the rule-based target's
# family (tune-target), then the best member found beside the rule-based
# target on the same starts, on teams and maps the search never met.
#   bash run.sh BIN OUT BR12 BR10
# BR12, BR10: the run folders of the best responses to the rule-based
# target at 1.0:1.2 and 1.0:1.0 (../2026-12-02-best-response-bar/run.sh).
# Held-out protocol: the search plays generated maps, the test the Gibson
# maps. One thread throughout.
set -euo pipefail
bin=$1
out=$2
br12=$3
br10=$4
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
[ -f "$out/search/tune.json" ] || "$bin" tune-target \
    --panel heuristic,expert:11,expert:12,greedy:4 --maps generated:20 --speed-ratio 1.2 \
    --episodes 60 --generations 8 --population 8 --seed 0 --threads 1 --out "$out/search"
best=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['best']['target'])" "$out/search/tune.json")
play() { # NAME CAPTORS RATIO MAPS EPISODES SEED
    for target in heuristic "$best"; do
        tag=$([ "$target" = heuristic ] && echo rule || echo tuned)
        "$bin" eval --captors "$2" --target "$target" --k 3 --speed-ratio "$3" --maps "$4" \
            --episodes "$5" --episode-length 500 --seed "$6" --soa-every 0 --quiet --resume \
            --out "$out/$1-$tag-$3-$4"
    done
}
# The training panel's worst team again, on new starts (seed 1).
play panel-greedy4 greedy:4 1.2 generated:20 300 1
# Teams the search never met, on the Gibson maps (seed 0).
play expert7 expert:7 1.2 large 500 0
play br ckpt:"$br12" 1.2 large 500 0
play br ckpt:"$br10" 1.0 large 500 0
play greedy2 greedy:2 1.2 large 200 0
