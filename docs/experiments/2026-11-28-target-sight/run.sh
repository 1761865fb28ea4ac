#!/usr/bin/env bash
# Does sight make a learned target harder to catch? Three MAPPO targets
# trained against the expert captors (target-spec.toml; target-sight.toml,
# the same with 12 wall rays; target-sight-kl.toml, that with the KL to
# the rule-based target annealed away), 3.5 M env steps each, then each and the
# rule-based target against captor teams on the Gibson maps, on the same
# starts (evaluation seed 0): the expert (trained against), the ASZ-greedy
# planner greedy:2 and the CPU default's MAPPO captors (held out: neither
# learned target ever met them). Held-out protocol.
#   bash run.sh BIN OUT MAPPO_RUN [TEAM...]   TEAM: expert, mappo, greedy2
# MAPPO_RUN: the CPU default held-out run, seed 0, 3.5 M env steps
# (configs/cpu-3v1-1.0-heldout.toml, `train --total-env-steps 3500000`).
set -euo pipefail
bin=$1
out=$2
mappo=$3
shift 3
teams=${*:-expert mappo greedy2}
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
for v in spec sight sight-kl; do
    "$bin" train --config "$here/target-$v.toml" --out "$out/target-$v" --quiet --resume
done
for team in $teams; do
    case $team in
        expert) captors=heuristic; episodes=200 ;;
        mappo) captors=ckpt:$mappo; episodes=200 ;;
        greedy2) captors=greedy:2; episodes=100 ;;
    esac
    for target in heuristic "ckpt:$out/target-spec" "ckpt:$out/target-sight" "ckpt:$out/target-sight-kl"; do
        case $target in
            heuristic) name=rule ;;
            *) name=${target##*/target-} ;;
        esac
        "$bin" eval --captors "$captors" --target "$target" --k 3 --speed-ratio 1.0 \
            --maps small,medium,large --episodes $episodes --episode-length 500 --seed 0 \
            --soa-every 0 --quiet --resume --out "$out/eval-$team-$name"
    done
done
python3 "$here/paired.py" "$out"
