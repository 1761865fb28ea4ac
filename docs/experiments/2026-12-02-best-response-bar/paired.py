"""Evaluation seed 1 of two best responses, each against its own target,
on the same starts: each SR and the mean paired difference of captures
(second minus first) with its 95% normal interval.

    python paired.py OUT/seed1-heuristic-1.2 OUT/seed1-robust-1.2
"""

import csv, math, sys
from pathlib import Path
def eps(folder):
    (d,) = [x for x in Path(folder).iterdir() if (x / "episodes.csv").exists()]
    return list(csv.DictReader(open(d / "episodes.csv")))
a, b = eps(sys.argv[1]), eps(sys.argv[2])
assert [e["seed"] for e in a] == [e["seed"] for e in b] and [e["map"] for e in a] == [e["map"] for e in b]
ca = [e["captured"] == "true" for e in a]; cb = [e["captured"] == "true" for e in b]
n = len(a); d = [int(y) - int(x) for x, y in zip(ca, cb)]; m = sum(d) / n
sd = math.sqrt(sum((x - m) ** 2 for x in d) / (n - 1)); h = 1.959964 * sd / math.sqrt(n)
print(f"n={n} first {100*sum(ca)/n:.1f} second {100*sum(cb)/n:.1f} diff {100*m:+.1f} [{100*(m-h):+.1f}, {100*(m+h):+.1f}]")
