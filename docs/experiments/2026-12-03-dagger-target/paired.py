"""Every target beside the rule-based target on the same starts: per team
and speed ratio, each target's capture rate (SR, 95% Wilson) and mean Time
(steps; an escape counts 500), and the mean paired difference of captures
(the target minus the rule-based target) with its 95% normal interval.
Prints a Markdown table. The helpers are the distillation page's.

    python paired.py OUT [LEAGUE_OUT]
OUT: what run.sh wrote; LEAGUE_OUT: what
../2026-12-03-league-robust-member/run.sh wrote, whose plays of the
rule-based and the robust target against team R (the same command as
`play-team-r`'s) are the team-r rows' baseline.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "2026-12-02-distilled-target"))
from paired import episodes, table_row  # noqa: E402

LABELS = {
    "heuristic": "rule-based",
    "robust": "robust (the teacher)",
    "dagger-w1": "DAgger, prior 10",
    "dagger-w10": "DAgger, prior 10, departures x10",
    "dagger-w10-large-sight": "DAgger, prior 10, departures x10, larger network, sight",
    "dagger-w10-large-sight-more-data": "DAgger, as the larger one, 3x the aggregate, 2.08 M env steps",
    "dagger-w10-large-sight-one-model": "DAgger, as the larger one, teacher robust:10:heuristic",
    "dagger-w10-large-sight-then-rl": "DAgger as the larger one, then 600 k of PPO with a KL of 5 to the teacher",
}


def main(out: Path, league_out: Path | None) -> None:
    print("| captors | v_p:v_e | target | episodes | SR % [95%] | Time | minus the rule-based target, points [95%] |")
    print("|---|---|---|---|---|---|---|")
    done = lambda f: f.exists() and any((x / "episodes.csv").exists() for x in f.iterdir())  # noqa: E731
    for team, ratio in [("mappo-sight", "1.0"), ("mappo-sight", "1.2"), ("expert7", "1.2"), ("greedy2", "1.2"), ("team-r", "1.2")]:
        def folder(name: str) -> Path:
            if team == "team-r" and name in ("heuristic", "robust") and league_out is not None:
                return league_out / f"rule-vs-{'rule' if name == 'heuristic' else 'robust'}-{ratio}"
            return out / f"{team}-{name}-{ratio}"
        if not done(folder("heuristic")):
            continue
        rule = episodes(folder("heuristic"))
        for name, label in LABELS.items():
            if done(folder(name)):
                print(table_row(team, ratio, label, folder(name), rule, name == "heuristic"))


if __name__ == "__main__":
    main(Path(sys.argv[1]), Path(sys.argv[2]) if len(sys.argv) > 2 else None)
