"""The default's speed on every real record in ../shared/ground_motions
(issue #21: the targets on records the engine was not tuned on).

    python scripts/speed_on_records.py --out DIR [--rounds N] [--runs K] [--scenes n0 n2 ...]
                                       [--records NAME ...]

Runs `cargo run --release --example ratio` with RECORDS set to every record
(its first 20 s) for the bench's scenes: the bare structure, the paper's two
blocks, eight blocks with mus = muk and issue #21's eight blocks with
mus > muk. Each figure is the median of N rounds timed alternately with the
floor (the exact Nigam-Jennings recurrence of the bare structure over the
same samples); with --runs K, the median of K such runs, every other one
taking the records backward (a single run on a shared machine can be off by
a third, the last record's more often). Writes DIR/speed_on_records.csv and DIR/speed_on_records.png:
the ratio to the floor against the switches per 1 000 samples (the bare
structure: against the sample interval).
"""

from __future__ import annotations

import argparse
import csv
import os
import statistics
import subprocess
import sys
from pathlib import Path

import use_venv  # noqa: E402,F401  (re-runs this script under the repository's .venv if needed)
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
RECORDS = ROOT.parent / "shared" / "ground_motions"
SCENES = {"n0": ("bare structure", 3), "n2": ("two blocks (paper)", 6),
          "n8": ("8 blocks, mus = muk", 12), "n8s": ("8 blocks, mus > muk (#21)", 12)}


def parse(line: str) -> dict:
    """One line of `examples/ratio`:
    "NAME SCENE  x us / floor  y us = r.rrx, k switches, n samples"."""
    w = line.replace(",", " ").split()
    return {"record": w[0], "scene": w[1], "engine_us": float(w[2]), "floor_us": float(w[6]),
            "ratio": float(w[9].rstrip("x")), "switches": int(w[10]), "samples": int(w[12])}


def measure(rounds: int, scenes: list[str], names: list[str] | None, backward: bool = False
            ) -> list[dict]:
    paths = sorted((p for p in RECORDS.iterdir() if p.suffix.lower() == ".at2"
                    and (not names or p.stem in names)), reverse=backward)
    env = dict(os.environ, ROUNDS=str(rounds), REPS="10", RECORDS=":".join(map(str, paths)))
    cmd = ["cargo", "run", "--quiet", "--release", "--example", "ratio", "--", *scenes]
    rows = []
    with subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, text=True) as proc:
        for line in proc.stdout:
            row = parse(line)
            rows.append(row)
            print(f"[{len(rows):3d}/{len(paths) * len(scenes)}] {row['record']:30s} {row['scene']:4s} "
                  f"{row['ratio']:7.2f}x the floor, {row['switches']} switches", flush=True)
    if proc.returncode:
        sys.exit(f"{' '.join(cmd)} failed")
    return rows


def median_of_runs(runs: list[list[dict]]) -> list[dict]:
    """Each (record, scene) of the first run with the median ratio and times of all runs."""
    key = lambda r: (r["record"], r["scene"])  # noqa: E731
    by_key = [{key(r): r for r in run} for run in runs]
    out = []
    for row in runs[0]:
        same = [run[key(row)] for run in by_key]
        med = {k: statistics.median(r[k] for r in same) for k in ("engine_us", "floor_us", "ratio")}
        out.append({**row, **med})
    return out


def plot(rows: list[dict], path: Path) -> None:
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    for ax, (scene, (title, target)) in zip(axes.flat, SCENES.items()):
        pts = [r for r in rows if r["scene"] == scene]
        if not pts:
            ax.set_visible(False)
            continue
        # The bare structure never switches: its cost follows the sampling.
        per_sample = scene == "n0"
        x = [20.0 / r["samples"] if per_sample else 1000 * r["switches"] / r["samples"]
             for r in pts]
        y = [r["ratio"] for r in pts]
        ax.scatter(x, y, s=18)
        for xi, yi, r in zip(x, y, pts):
            ax.annotate(r["record"][:14], (xi, yi), fontsize=6, alpha=0.7)
        ax.axhline(target, color="red", lw=1, ls="--", label=f"target {target}x")
        ax.set_yscale("log")
        ax.set_xlabel("sample interval (s)" if per_sample else "switches per 1000 samples")
        ax.set_ylabel("engine / floor")
        ax.set_title(title, fontsize=10)
        ax.legend(fontsize=8)
    fig.suptitle("The default against the floor on the 20 shared records (first 20 s)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--runs", type=int, default=1, help="runs of every record (medians)")
    ap.add_argument("--scenes", nargs="+", choices=list(SCENES), default=list(SCENES))
    ap.add_argument("--records", nargs="+", metavar="NAME",
                    help="record file names without extension (default: all)")
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    runs = []
    for k in range(args.runs):
        if args.runs > 1:
            print(f"run {k + 1} of {args.runs}", flush=True)
        # Every other run takes the records backward: a record's place in the run
        # (the first or the last) does not weigh on its median.
        runs.append(measure(args.rounds, args.scenes, args.records, backward=k % 2 == 1))
    rows = median_of_runs(runs) if runs[0] else []
    if not rows:
        sys.exit("no record measured (check --records against ../shared/ground_motions)")
    with open(args.out / "speed_on_records.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    plot(rows, args.out / "speed_on_records.png")
    print(f"wrote {args.out / 'speed_on_records.csv'} and {args.out / 'speed_on_records.png'}")


if __name__ == "__main__":
    main()
