"""Coupling error against macro step for each master (docs/coupling.md).

    python scripts/couple.py --out out/coupling [--quick]

Two buildings under a seeded broadband record (10 s at 5 ms, PGA 3 m/s2;
--quick: 4 s and fewer steps), one FMU instance per storey (sll/coupling.py):
- linear: storey 1 (Tp 0.4 s, 1000 kg) under storey 2 (Tp 0.3 s, 800 kg,
  carrying two blocks that cannot slip, mu 20), against the exact shear
  building; every master (Jacobi, Gauss-Seidel) with every extrapolation
  (hold, history, derivative);
- sliding: the same building with the stack free to slide (mu1 0.12 > muk1
  0.1, mu2 0.06): self-convergence against the finest run (event-aware
  Gauss-Seidel at an eighth of the smallest step), plain and event-aware.
Writes DIR/coupling.csv (one row per run: case, master, extrapolation,
event_aware, H, drift error, peak-slip error, FMU steps, rollbacks, seconds),
DIR/coupling.png and DIR/summary.txt (observed orders), and prints the orders.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import use_venv  # noqa: E402,F401  (re-runs this script under the repository's .venv if needed)
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import NullFormatter  # noqa: E402
import numpy as np  # noqa: E402

from sll.coupling import (EXTRAPOLATIONS, MASTERS, Building, broadband_record, drift_error,  # noqa: E402
                      exact_building, observed_order)

LOWER = {"nBlocks": 0, "Tp": 0.4, "mp": 1000.0}
STACK = {"nBlocks": 2, "Tp": 0.3, "mp": 800.0, "alpha[1]": 0.3, "alpha[2]": 0.2}
RIGID = [LOWER, {**STACK, "mus[1]": 20.0, "muk[1]": 20.0, "mus[2]": 20.0, "muk[2]": 20.0}]
# The sliding stack on the lower storey: its switches make apAbs of floor 1,
# the upper storey's support acceleration, jump.
SLIDING = [{**STACK, "Tp": 0.4, "mp": 1000.0, "mus[1]": 0.12, "muk[1]": 0.1, "mus[2]": 0.06, "muk[2]": 0.06},
           {"nBlocks": 0, "Tp": 0.3, "mp": 800.0}]
STEPS = [0.02, 0.01, 0.005, 0.0025, 0.00125]
COLUMNS = ["case", "master", "extrapolation", "event_aware", "H", "drift_error", "peak_slip_error",
           "fmu_steps", "rollbacks", "seconds"]


def supported(building: Building) -> tuple[list[str], bool]:
    """Extrapolations and event awareness the loaded FMU supports."""
    md = building.models[0].md
    order = getattr(md.coSimulation, "maxOutputDerivativeOrder", 0) or 0
    extrapolations = [e for e in EXTRAPOLATIONS if e != "derivative" or order >= 1]
    return extrapolations, "tSwitch" in building.models[0].vars


def peak_slips(run: dict) -> np.ndarray:
    return np.array([p.get("peakSlip[1]", 0.0) for p in run["peaks"]])


STACK_STOREY = 0  # index of the storey that carries the sliding stack


def linear_case(b: Building, rec, steps, extrapolations, progress) -> list[dict]:
    rows = []
    for master in MASTERS:
        for extrapolation in extrapolations:
            for h in steps:
                run = b.couple(RIGID, rec, h, master=master, extrapolation=extrapolation)
                exact = exact_building(RIGID, rec, run["time"], b.defaults)
                if not exact["never_slips"]:
                    raise RuntimeError("the linear case's stack would slip: the exact reference does not apply")
                rows.append({"case": "linear", "master": master, "extrapolation": extrapolation,
                             "event_aware": False, "H": h, "drift_error": drift_error(run, exact),
                             "peak_slip_error": 0.0, "fmu_steps": run["fmu_steps"],
                             "rollbacks": 0, "seconds": run["seconds"]})
                progress(rows[-1])
    return rows


def sliding_case(b: Building, rec, steps, extrapolation, event_aware_ok, progress) -> tuple[list[dict], dict]:
    h_ref = steps[-1] / 8
    ref = b.couple(SLIDING, rec, h_ref, master="gauss-seidel", extrapolation=extrapolation,
                   event_aware=event_aware_ok)
    half = b.couple(SLIDING, rec, 2 * h_ref, master="gauss-seidel", extrapolation=extrapolation,
                    event_aware=event_aware_ok)
    grid = ref["on_grid"]
    ref_up, ref_slip = ref["up"][:, grid], peak_slips(ref)
    scale = np.max(np.abs(ref_up))
    info = {"H_ref": h_ref, "ref_self_error": float(np.max(np.abs(half["up"][:, half["on_grid"]]
                                                                - ref_up[:, ::2])) / scale),
            "ref_peak_slip": float(ref_slip[STACK_STOREY]), "extrapolation": extrapolation}
    rows = []
    for master in MASTERS:
        for event_aware in ([False, True] if event_aware_ok else [False]):
            for h in steps:
                run = b.couple(SLIDING, rec, h, master=master, extrapolation=extrapolation,
                               event_aware=event_aware)
                stride = int(round(h / h_ref))
                err = np.max(np.abs(run["up"][:, run["on_grid"]] - ref_up[:, ::stride])) / scale
                slip_err = abs(peak_slips(run)[STACK_STOREY] - ref_slip[STACK_STOREY]) / ref_slip[STACK_STOREY]
                rows.append({"case": "sliding", "master": master, "extrapolation": extrapolation,
                             "event_aware": event_aware, "H": h, "drift_error": float(err),
                             "peak_slip_error": float(slip_err), "fmu_steps": run["fmu_steps"],
                             "rollbacks": run["rollbacks"], "seconds": run["seconds"]})
                progress(rows[-1])
    return rows, info


def series(rows, **match):
    picked = [r for r in rows if all(r[k] == v for k, v in match.items())]
    return np.array([r["H"] for r in picked]), picked


def fitted_order(h, picked, key="drift_error", points=3) -> float:
    """Order over the `points` smallest steps (the large ones may be unstable)."""
    err = np.array([r[key] for r in picked])
    keep = np.argsort(h)[:points]
    return observed_order(h[keep], err[keep]) if np.all(err[keep] > 0) else float("nan")


def plot(rows, info, path: Path):
    fig, axes = plt.subplots(1, 3, figsize=(16, 5))
    styles = {"hold": ":", "history": "--", "derivative": "-"}
    colors = {"jacobi": "tab:blue", "gauss-seidel": "tab:red"}
    ax = axes[0]
    for master in MASTERS:
        for extrapolation in styles:
            h, picked = series(rows, case="linear", master=master, extrapolation=extrapolation)
            if len(h):
                ax.loglog(h, [r["drift_error"] for r in picked], styles[extrapolation], marker="o",
                          color=colors[master],
                          label=f"{master}, {extrapolation}: order {fitted_order(h, picked):.2f}")
    ax.set_title("linear 2-storey building vs exact")
    ax.set_ylabel("max drift error / max drift")
    ex = info["extrapolation"]
    for col, key, title in ((1, "drift_error", f"sliding stack, {ex}: drift (self-convergence)"),
                            (2, "peak_slip_error", f"sliding stack, {ex}: peak slip of block 1")):
        ax = axes[col]
        for master in MASTERS:
            for aware in (False, True):
                h, picked = series(rows, case="sliding", master=master, event_aware=aware)
                if len(h):
                    ax.loglog(h, [max(r[key], 1e-16) for r in picked], "-" if aware else "--",
                              marker="o", color=colors[master],
                              label=f"{master}{', event-aware' if aware else ''}: "
                                    f"order {fitted_order(h, picked, key):.2f}")
        ax.set_title(title)
        ax.set_ylabel(f"relative error (reference: H = {info['H_ref']:g} s)")
    steps = sorted(set(r["H"] for r in rows))
    for ax in axes:
        ax.set_xticks(steps, [f"{1000 * h:g}" for h in steps])
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("macro step H (ms)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def summary(rows, info, extrapolation) -> list[str]:
    lines = []
    for case in ("linear", "sliding"):
        for master in MASTERS:
            for ex in EXTRAPOLATIONS:
                for aware in (False, True):
                    h, picked = series(rows, case=case, master=master, extrapolation=ex, event_aware=aware)
                    if not len(h):
                        continue
                    errs = " ".join(f"{r['drift_error']:.2e}" for r in picked)
                    line = (f"{case:8s} {master:12s} {ex:10s} {'event-aware' if aware else 'plain':11s} "
                            f"drift order {fitted_order(h, picked):5.2f}  errors {errs}")
                    if case == "sliding":
                        line += "  peak-slip errors " + " ".join(f"{r['peak_slip_error']:.2e}" for r in picked)
                    lines.append(line + f"  at H = {h[-1]:g}: FMU steps {picked[-1]['fmu_steps']}, "
                                        f"rollbacks {picked[-1]['rollbacks']}, "
                                        f"{picked[-1]['seconds']:.2f} s (one run)")
    lines.append(f"steps H: {sorted(set(r['H'] for r in rows), reverse=True)}; orders fitted over the "
                 "three smallest")
    lines.append(f"sliding reference: gauss-seidel, {extrapolation}, H = {info['H_ref']:g} s; its "
                 f"difference from H = {2 * info['H_ref']:g} s: {info['ref_self_error']:.2e}; "
                 f"peak slip of block 1: {info['ref_peak_slip']:.4g} m")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, default=Path("out/coupling"))
    ap.add_argument("--quick", action="store_true", help="4 s record, three steps (for tests)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    rec = broadband_record(2026, duration=4.0 if args.quick else 10.0)
    steps = STEPS[1:4] if args.quick else STEPS
    count = [0]

    def progress(row):
        count[0] += 1
        print(f"  [{count[0]}] {row['case']} {row['master']} {row['extrapolation']}"
              f"{' event-aware' if row['event_aware'] else ''} H={row['H']:g}: "
              f"drift error {row['drift_error']:.2e} ({row['seconds']:.2f} s)", flush=True)

    with Building(2) as b:
        extrapolations, event_aware_ok = supported(b)
        best = extrapolations[-1]
        rows = linear_case(b, rec, steps, extrapolations, progress)
        sliding, info = sliding_case(b, rec, steps, best, event_aware_ok, progress)
    rows += sliding
    with open(args.out / "coupling.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    plot(rows, info, args.out / "coupling.png")
    lines = summary(rows, info, best)
    (args.out / "summary.txt").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    print(f"wrote {args.out / 'coupling.png'}, coupling.csv, summary.txt")


if __name__ == "__main__":
    main()
