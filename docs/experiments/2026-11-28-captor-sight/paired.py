"""Paired comparison of captors with the spec's inputs and with sight, on
the same starts: per seed and class, each one's SR (95% Wilson) and Time
(mean steps), and the mean paired difference of captures (sight minus
spec) with its 95% normal interval; then pooled over the seeds.

    python paired.py OUT   (the folders run.sh wrote)
"""

import csv
import math
import re
import sys
from pathlib import Path


def wilson(k: int, n: int) -> tuple[float, float]:
    z = 1.959964
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return 100 * (centre - half), 100 * (centre + half)


def episodes(folder: Path) -> dict[str, list[dict]]:
    """Map class -> episodes of the eval folder."""
    out = {}
    for setting in sorted(folder.iterdir()):
        f = setting / "episodes.csv"
        if f.exists():
            m = re.search(r"_k\d+_r[0-9p]+_(.+)_[0-9a-f]{12}$", setting.name)
            assert m, f"{setting}: not an eval setting folder"
            out[m.group(1)] = list(csv.DictReader(open(f)))
    return out


def row(label: str, a: list[dict], b: list[dict]) -> str:
    assert [(e["seed"], e["map"]) for e in a] == [(e["seed"], e["map"]) for e in b], f"{label}: not the same starts"
    n = len(a)
    ca = [e["captured"] == "true" for e in a]
    cb = [e["captured"] == "true" for e in b]
    d = [int(y) - int(x) for x, y in zip(ca, cb)]
    mean = sum(d) / n
    sd = math.sqrt(sum((x - mean) ** 2 for x in d) / (n - 1)) if n > 1 else 0.0
    half = 1.959964 * sd / math.sqrt(n)
    time = lambda es: sum(int(e["steps"]) for e in es) / len(es)
    la, ha = wilson(sum(ca), n)
    lb, hb = wilson(sum(cb), n)
    return (
        f"| {label} | {n} | {100 * sum(ca) / n:.1f} [{la:.1f}, {ha:.1f}] | {time(a):.0f} "
        f"| {100 * sum(cb) / n:.1f} [{lb:.1f}, {hb:.1f}] | {time(b):.0f} "
        f"| {100 * mean:+.1f} [{100 * (mean - half):+.1f}, {100 * (mean + half):+.1f}] |"
    )


def main(out: Path) -> None:
    print("| seed, maps | episodes | spec inputs SR % [95%] | Time | sight SR % [95%] | Time | paired difference, points [95%] |")
    print("|---|---|---|---|---|---|---|")
    pooled: dict[str, tuple[list, list]] = {}
    for seed in (0, 1):
        spec_dir, sight_dir = out / f"eval-spec-s{seed}", out / f"eval-sight-s{seed}"
        if not (spec_dir.exists() and sight_dir.exists()):
            continue
        spec, sight = episodes(spec_dir), episodes(sight_dir)
        for maps in spec:
            if maps in sight:
                print(row(f"{seed}, {maps}", spec[maps], sight[maps]))
                a, b = pooled.setdefault(maps, ([], []))
                a.extend(spec[maps])
                b.extend(sight[maps])
    for maps, (a, b) in pooled.items():
        if len(a) > 500:
            print(row(f"pooled, {maps}", a, b))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
