"""How close each DAgger target came to its teacher over the last LAST
iterations (default 50) of its run: on the new rollouts before each fit
(teacher.csv, states it was never fitted on) and on the aggregate's states
it was fitted on (dagger.csv). Per file: the teacher's departures (share
of decisions), recall (the share of them where the policy's greedy move is
the teacher's), strays (the policy departs where the teacher keeps the
rule, share of those decisions) and precision (the share of the policy's
departures that are the teacher's move). Prints a Markdown table.

    python agreement.py OUT [LAST]
"""

import csv
import sys
from pathlib import Path


def row(path: Path, last: int) -> str:
    rows = list(csv.DictReader(open(path)))[-last:]
    total = {k: sum(int(r[k]) for r in rows) for k in ("decisions", "teacher_departures", "followed", "strayed")}
    d, t, f, s = total["decisions"], total["teacher_departures"], total["followed"], total["strayed"]
    # A departure that is not the teacher's move where the teacher departs
    # is counted in neither; precision is over the policy's departures the
    # counts can place: followed and strays.
    return (f"{100 * t / d:.2f}% | {100 * f / t:.1f}% | {100 * s / (d - t):.2f}% | "
            f"{100 * f / max(f + s, 1):.1f}% | {rows[0]['iteration']}-{rows[-1]['iteration']}")


def main(out: Path, last: int) -> None:
    print("| target | states | teacher departs | recall | strays | precision | iterations |")
    print("|---|---|---|---|---|---|---|")
    for run in sorted(out.glob("dagger-*")):
        for name, what in [("teacher.csv", "new rollout, before the fit"), ("dagger.csv", "fitted on")]:
            if (run / name).exists():
                print(f"| {run.name} | {what} | {row(run / name, last)} |")


if __name__ == "__main__":
    main(Path(sys.argv[1]), int(sys.argv[2]) if len(sys.argv) > 2 else 50)
