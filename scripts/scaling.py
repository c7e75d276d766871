"""How the default method's cost scales (issue #14, item 4).

    python scripts/scaling.py --out DIR [--rounds N]

Runs `cargo run --release --example scaling` (each point the median of N
rounds timed alternately with the physical floor, the Nigam-Jennings
recurrence of the bare structure over the same samples), writes
DIR/scaling.csv and DIR/scaling.png: cost against record length, structure
period, switch count and stack height, in microseconds and as a ratio to the
floor.
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
from pathlib import Path

import use_venv  # noqa: E402,F401  (re-runs this script under the repository's .venv if needed)
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def measure(rounds: int) -> list[dict]:
    cmd = ["cargo", "run", "--quiet", "--release", "--example", "scaling"]
    env = dict(os.environ, ROUNDS=str(rounds))
    rows = []
    with subprocess.Popen(cmd, cwd=ROOT, env=env, stdout=subprocess.PIPE, text=True) as proc:
        header = proc.stdout.readline().strip().split(",")
        for line in proc.stdout:
            row = dict(zip(header, line.strip().split(",")))
            rows.append(row)
            print(f"[{len(rows):2d}/28] {row['sweep']} {row['x']}: {float(row['engine_us']):.1f} us, "
                  f"{float(row['engine_us']) / float(row['floor_us']):.2f}x the floor, "
                  f"{row['events']} switches", flush=True)
    if proc.returncode:
        sys.exit(f"{' '.join(cmd)} failed")
    return rows


def plot(rows: list[dict], path: Path) -> None:
    panels = [
        ("length", "record length (s)", "two-block scene"),
        ("period", "structure period Tp (s)", "bare structure, 0.005 s samples"),
        ("events", "stick/slip switches", "one block, friction 0.02-1"),
        ("height", "blocks in the stack", "stacks of benches/frontier.rs"),
    ]
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5))
    for ax, (sweep, xlabel, title) in zip(axes.flat, panels):
        pts = [r for r in rows if r["sweep"] == sweep]
        x = [float(r["events"]) if sweep == "events" else float(r["x"]) for r in pts]
        us = [float(r["engine_us"]) for r in pts]
        floor = [float(r["floor_us"]) for r in pts]
        ax.plot(x, us, "o-", label="default settings")
        ax.plot(x, floor, "s--", color="grey", label="floor (Nigam-Jennings, bare)")
        if sweep in ("length", "period"):
            ax.set_xscale("log")
            ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel("microseconds per simulation")
        ax.set_title(title, fontsize=10)
        ratio = ax.twinx()
        ratio.plot(x, [u / f for u, f in zip(us, floor)], "^:", color="tab:red", label="ratio to floor")
        ratio.set_ylabel("ratio to the floor", color="tab:red")
        ratio.set_ylim(bottom=0)
        if sweep == "length":
            ax.legend(loc="upper left", fontsize=8)
            ratio.legend(loc="lower right", fontsize=8)
    fig.suptitle("Cost of one simulation at default settings (medians, timed alternately with the floor)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "scaling")
    ap.add_argument("--rounds", type=int, default=7)
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    rows = measure(args.rounds)
    with open(args.out / "scaling.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    plot(rows, args.out / "scaling.png")
    print(f"wrote {args.out}/scaling.csv and scaling.png")


if __name__ == "__main__":
    main()
