"""Where methods fail: a map over structure period and communication step.

    python scripts/stability.py --out DIR [--quick]

A co-simulation master drives the FMU with a harmonic ground acceleration
(0.3 g at 1.5 Hz, 6 s) sampled at each communication point and held over the
step. For every structure period Tp (0.01 s to 10 s) and communication step h
(1e-4 s to 1 s), on a single block with mus = 0.15 > muk = 0.1, it runs:

- event (auto): solver 1 with automatic internal steps (the FMU's default);
- step-end, h: solver 2 with maxStep = h (the paper's approach; our engine
  still caps the step at the RK4 stability bound 2.5 / omega_p);
- tanh, h: solver 3 (eps = 1e-2 m/s) with maxStep = h; plain RK4 diverges
  where h |lambda| > 2.785 (lambda the larger of omega_p and the regularized
  friction's stiffness), and since issue 13 the FMU's solver 3 never steps
  above 2.5 / lambda (docs/robustness.md), so it stays bounded there too;

and the reference, solver 1 at maxStep 1e-5 s with the same held input. It
writes DIR/stability.csv (bounded: finite and within 100 times the reference
peak drift; Tp, h, method, bounded, err_peak_drift, err_history,
n_events, ref_events, n_ambiguous) and DIR/stability.png: the error of each
method as a colour map (crosses where it diverged), with the plain-RK4 limit
h omega_p = 2.83 drawn, and the chatter (mode switches or friction sign changes
over the reference's switches) of step-end switching and regularized friction.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path

import use_venv  # noqa: E402,F401  (re-runs this script under the repository's .venv if needed)
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

from sll import Model  # noqa: E402

G = 9.81
RK4_LIMIT = 2.83  # |R(i y)| = 1 for plain RK4 at y = 2.828 (undamped)
PERIODS = np.geomspace(0.01, 10.0, 13)
STEPS = np.array([1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3, 1.0])
SCENE = {"nBlocks": 1, "alpha[1]": 0.5, "mus[1]": 0.15, "muk[1]": 0.1, "zeta": 0.05}
TANH_EPS = 1e-2
REF_STEP = 1e-5
METHODS = {
    "event (auto)": lambda h: {"solver": 1},
    "step-end, h": lambda h: {"solver": 2, "maxStep": h},
    "tanh, h": lambda h: {"solver": 3, "maxStep": h, "frictionEps": TANH_EPS},
}
COLUMNS = ["Tp", "h", "method", "bounded", "err_peak_drift", "err_history", "n_events",
           "ref_events", "n_ambiguous"]


def held_input(h: float, duration: float) -> np.ndarray:
    """The ground acceleration a master samples at each communication point."""
    n = max(1, int(round(duration / h)))
    return 0.3 * G * np.sin(2 * np.pi * 1.5 * np.arange(n) * h)


def cell(model: Model, tp: float, h: float, duration: float,
         methods: dict = METHODS) -> list[dict]:
    """Every method and the reference at one (Tp, h); one row per method."""
    ag = held_input(h, duration)
    scene = dict(SCENE, Tp=tp)
    ref = model.run_input(ag, h, dict(scene, maxStep=REF_STEP))
    peak_ref = float(np.max(np.abs(ref["up"])))
    rows = []
    for name, settings in methods.items():
        r = model.run_input(ag, h, dict(scene, **settings(h)))
        # Bounded: finite, and not beyond 100 times the reference peak drift
        # (an unstable RK4 grows by orders of magnitude, a stable one does not).
        bounded = (not r["failed"] and bool(np.all(np.isfinite(r["up"])))
                   and float(np.max(np.abs(r["up"]))) <= 100 * peak_ref)
        if bounded:
            err_peak = abs(float(np.max(np.abs(r["up"]))) - peak_ref) / peak_ref
            err_hist = float(np.max(np.abs(r["up"] - ref["up"]))) / peak_ref
        else:
            err_peak = err_hist = float("nan")
        peaks = r["peaks"]
        rows.append({"Tp": tp, "h": h, "method": name, "bounded": bounded,
                     "err_peak_drift": err_peak, "err_history": err_hist,
                     "n_events": peaks.get("nEvents", -1), "ref_events": ref["peaks"]["nEvents"],
                     "n_ambiguous": peaks.get("nAmbiguous", -1)})
    return rows


def plot(rows: list[dict], path: Path):
    tps = sorted({r["Tp"] for r in rows})
    hs = sorted({r["h"] for r in rows})
    methods = list(dict.fromkeys(r["method"] for r in rows))
    fig, axes = plt.subplots(2, len(methods), figsize=(5.2 * len(methods), 9), squeeze=False)
    # Cell edges: geometric means of neighbours, mirrored at the ends.
    edges = lambda v: np.sqrt(np.r_[v[0] ** 3 / v[1], v[:-1] * v[1:], v[-1] ** 3 / v[-2]])  # noqa: E731
    tx, hy = edges(np.array(tps)), edges(np.array(hs))
    limit_t = np.geomspace(tps[0], tps[-1], 50)
    for col, method in enumerate(methods):
        err = np.full((len(hs), len(tps)), np.nan)
        chatter = np.full((len(hs), len(tps)), np.nan)
        diverged = []
        for r in rows:
            if r["method"] != method:
                continue
            i, j = hs.index(r["h"]), tps.index(r["Tp"])
            if r["bounded"]:
                err[i, j] = max(r["err_peak_drift"], 1e-16)
                chatter[i, j] = r["n_events"] / max(r["ref_events"], 1)
            else:
                diverged.append((r["Tp"], r["h"]))
        for row, (data, label, norm) in enumerate([
                (err, "relative error of peak drift", LogNorm(1e-12, 1.0)),
                (chatter, "switches / reference switches", LogNorm(0.1, 1e3))]):
            ax = axes[row, col]
            mesh = ax.pcolormesh(tx, hy, np.ma.masked_invalid(data), norm=norm, cmap="viridis")
            fig.colorbar(mesh, ax=ax, label=label)
            if diverged:
                ax.plot(*zip(*diverged), "x", color="red", ms=7, label="diverged")
            ax.loglog(limit_t, RK4_LIMIT * limit_t / (2 * np.pi), "w--", lw=1.5,
                      label="h omega_p = 2.83")
            ax.set_xlim(tx[0], tx[-1])
            ax.set_ylim(hy[0], hy[-1])
            ax.set_xlabel("structure period Tp (s)")
            ax.set_ylabel("communication step h (s)")
            ax.set_title(f"{method}: {'error' if row == 0 else 'chatter'}")
            ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--quick", action="store_true", help="3 periods, h >= 1e-3 s, 2 s (for tests)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    periods = PERIODS[::6] if args.quick else PERIODS
    steps = STEPS[STEPS >= 1e-3] if args.quick else STEPS
    duration = 2.0 if args.quick else 6.0
    rows = []
    started = time.perf_counter()
    with Model() as model:
        jobs = [(tp, h) for tp in periods for h in steps]
        for k, (tp, h) in enumerate(jobs, 1):
            rows += cell(model, float(tp), float(h), duration)
            done = ", ".join(f"{r['method']}: " + (f"{r['err_peak_drift']:.1e}" if r["bounded"] else "DIVERGED")
                             for r in rows[-len(METHODS):])
            print(f"[{k}/{len(jobs)} {time.perf_counter() - started:5.0f} s] Tp {tp:.3g} s, h {h:g} s: {done}",
                  flush=True)
    with open(args.out / "stability.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    plot(rows, args.out / "stability.png")
    for method in METHODS:
        sub = [r for r in rows if r["method"] == method]
        bounded = [r for r in sub if r["bounded"]]
        worst = max((r["err_peak_drift"] for r in bounded), default=float("nan"))
        over = [r for r in sub if r["h"] * 2 * math.pi / r["Tp"] > RK4_LIMIT]
        print(f"{method}: bounded in {len(bounded)}/{len(sub)} cells (diverged in "
              f"{sum(not r['bounded'] for r in over)}/{len(over)} cells beyond h omega_p = 2.83); "
              f"worst peak-drift error {worst:.2e}; "
              f"switches {sum(r['n_events'] for r in bounded)} vs reference {sum(r['ref_events'] for r in bounded)}")
    event = [r for r in rows if r["method"] == "event (auto)"]
    print(f"selection rule (mus > muk) decided {sum(r['n_ambiguous'] for r in event)} of "
          f"{sum(r['n_events'] for r in event)} mode switches of the default's runs")
    print(f"wrote {args.out}/stability.csv and stability.png in {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()
