"""The departures of every setting run.sh played, by where they were taken:
one markdown row per team, target and view, each bin's departure share
(%) with its decisions.
    python3 places.py OUT"""
import csv
import json
import sys
from pathlib import Path

out = Path(sys.argv[1])
print("| captors | target | SR % | departures % | by | " + " | ".join(f"bin {i}" for i in range(1, 5)) + " |")
print("|---|---|---|---|---|---|---|---|---|")
for folder in sorted(p for p in out.iterdir() if p.is_dir()):
    settings = [d for d in folder.iterdir() if (d / "setting.json").exists()]
    if not settings:
        continue  # a training run's folder
    (setting,) = settings
    summary = json.load(open(setting / "summary.json"))
    rows = list(csv.DictReader(open(setting / "departures.csv")))
    team, target = folder.name.rsplit("-", 1)
    for by in ("nearest_captor", "asz"):
        cells = [
            f"{float(r['departure_pct']):.2f} ({r['bin']}, {int(r['decisions']):,})"
            if r["departure_pct"] else f"- ({r['bin']}, 0)"
            for r in rows if r["by"] == by
        ]
        print(f"| {team} | {target} | {summary['sr']:.1f} | {summary['target_departure']:.2f} | {by} | " + " | ".join(cells) + " |")
