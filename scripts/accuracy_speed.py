"""Error against cost for every reasonable way to compute a sliding stack, on the
same scenes, measured in one run.

    python scripts/accuracy_speed.py --out DIR [--quick] [--repeats 3]

Writes DIR/accuracy_speed.csv (scene,record,method,setting,err_peak_drift,
err_peak_slip,err_history,seconds), DIR/accuracy_speed.png (log-log error of the
peak drift against seconds per simulation, one line per method and one panel per
scene and record) and DIR/summary.txt (time to reach 1e-6 per method, speed
ratios, whether the default settings are on the efficient front).

Methods: the FMU's exact default (solver 1, automatic substeps and one shorter
maxStep: exact at both, only the cost differs), RK4 with step-end switching (solver
2, the paper's method) over a range of internal steps; tanh-regularized friction
(solver 3) for several eps; OpenSees (zeroLength + ElasticPP) for the single block,
over several dt and stick stiffnesses. The reference is solver 1 at maxStep 1e-5 s,
itself checked against exact solutions in the test suite.
Errors: relative error of the peak structure drift, of the largest peak slip
(empty when the reference does not slip), and the largest drift-history error
over the record's samples divided by the reference peak drift. Seconds: median
wall time of the computation alone (one fmi2DoStep over the whole record; the
OpenSees analysis loop), over --repeats runs. The physical floor of each
record, drawn as a vertical line: the exact Nigam-Jennings recurrence of the bare
structure over its samples, in Rust (examples/floor.rs), median of 31 rounds.
"""

from __future__ import annotations

import argparse
import csv
import math
import statistics
import subprocess
import time
from pathlib import Path

import use_venv  # noqa: E402,F401  (re-runs this script under the repository's .venv if needed)
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from sll import ROOT, Model, opensees_block, read_record  # noqa: E402

G = 9.81
REAL_RECORD = ROOT.parent / "shared" / "ground_motions" / "RSN6_IMPVALL.I_I-ELC180.AT2"
TARGET = 1e-6
REF_STEP = 1e-5
COLUMNS = ["scene", "record", "method", "setting", "err_peak_drift", "err_peak_slip",
           "err_history", "seconds"]

# Scenes in FMU parameters. "rigid": a block that never slides (mu = 10).
SCENES = {
    "stack2": {"nBlocks": 2, "Tp": 0.5, "alpha[1]": 0.25, "alpha[2]": 0.25,
               "mus[1]": 0.1, "muk[1]": 0.1, "mus[2]": 0.05, "muk[2]": 0.05},
    "single": {"nBlocks": 1, "Tp": 0.5, "alpha[1]": 0.5, "mus[1]": 0.1, "muk[1]": 0.1},
    "rigid": {"nBlocks": 1, "Tp": 0.5, "alpha[1]": 0.5, "mus[1]": 10.0, "muk[1]": 10.0},
}


def harmonic_record(out: Path, duration: float = 10.0, dt: float = 0.005) -> Path:
    """0.3 g at 1.5 Hz, 10 s, as a CSV the FMU reads (time,accel in m/s2)."""
    t = np.arange(int(round(duration / dt)) + 1) * dt
    a = 0.3 * G * np.sin(2 * np.pi * 1.5 * t)
    path = out / "harmonic_0.3g_1.5Hz.csv"
    np.savetxt(path, np.column_stack([t, a]), delimiter=",", header="time,accel",
               comments="", fmt="%.10g")
    return path


def tanh_stable_step(params: dict, eps: float) -> float:
    """Explicit RK4 limit h |lambda| < 2.785 of the regularized law at v = 0:
    the largest eigenvalue of M^-1 (C + B^T D B), D = mu N / eps per interface."""
    n = int(params["nBlocks"])
    mp = 1000.0
    m = [mp] + [params[f"alpha[{j}]"] * mp for j in range(1, n + 1)]
    above = [sum(m[i:]) for i in range(n + 1)]
    c = 2 * 0.05 * math.sqrt(mp * (2 * math.pi / params["Tp"]) ** 2 * mp)
    k = np.zeros((n + 1, n + 1))
    k[0, 0] = c
    for j in range(1, n + 1):
        d = params[f"muk[{j}]"] * above[j] * G / eps
        k[j - 1, j - 1] += d
        k[j, j] += d
        k[j - 1, j] -= d
        k[j, j - 1] -= d
    lam = max(abs(np.linalg.eigvals(np.diag(1 / np.array(m)) @ k)))
    return 2.785 / lam


def errors(run: dict, ref: dict, n_blocks: int, t_ref: np.ndarray, up_ref: np.ndarray) -> tuple:
    peak_ref = ref["peakUp"]
    e_drift = abs(run["peakUp"] - peak_ref) / peak_ref
    slip_ref = max((ref[f"peakSlip[{j}]"] for j in range(1, n_blocks + 1)), default=0.0)
    if slip_ref > 1e-6 * peak_ref:
        e_slip = max(abs(run[f"peakSlip[{j}]"] - ref[f"peakSlip[{j}]"])
                     for j in range(1, n_blocks + 1)) / slip_ref
    else:
        e_slip = float("nan")
    up = np.interp(t_ref, run["time"], run["up"])
    e_hist = float(np.max(np.abs(up - up_ref))) / peak_ref
    return e_drift, e_slip, e_hist


class Bench:
    def __init__(self, model: Model, repeats: int):
        self.m = model
        self.repeats = repeats

    def fmu(self, record: Path, params: dict, sample_dt: float) -> dict | None:
        """Peaks and median seconds from one-doStep runs, history from a sampled run."""
        times = []
        try:
            for _ in range(self.repeats):
                r = self.m.run(record, params)
                times.append(r["seconds"])
            hist = self.m.run(record, params, dt=sample_dt)
        except Exception:
            return None  # diverged (the FMU reports a non-finite state and stops)
        out = dict(r["peaks"])
        out.update(time=hist["time"], up=hist["up"], seconds=statistics.median(times))
        return out

    def opensees(self, record: Path, params: dict, dt: float, k_stick: float) -> dict | None:
        t, a = read_record(record)
        times = []
        for _ in range(self.repeats):
            o = opensees_block.run(a, t[1] - t[0], dt, 1000.0, params["Tp"], 0.05,
                                   params["alpha[1]"], params["muk[1]"], G, k_stick)
            if not o["converged"]:
                return None
            times.append(o["seconds"])
        return {"peakUp": o["peakUp"], "peakSlip[1]": o["peakSlip"], "time": o["time"],
                "up": o["up"], "seconds": statistics.median(times)}


def sweep(bench: Bench, scene: str, record: Path, quick: bool, progress) -> list[dict]:
    params = SCENES[scene]
    n = int(params["nBlocks"])
    t_rec, _ = read_record(record)
    rec_dt = float(t_rec[1] - t_rec[0])
    ref = bench.fmu(record, dict(params, maxStep=REF_STEP), rec_dt)
    t_ref, up_ref = ref["time"], ref["up"]
    rows = []
    label = "harmonic" if record.suffix == ".csv" else record.stem

    def add(method: str, setting: str, run: dict | None):
        if run is None:
            progress(f"{scene}/{label}: {method} {setting}: diverged or failed")
            return
        e = errors(run, ref, n, t_ref, up_ref)
        rows.append(dict(zip(COLUMNS, [scene, label, method, setting, *e, run["seconds"]])))
        progress(f"{scene}/{label}: {method} {setting}: err {e[0]:.2e} in {run['seconds'] * 1e3:.2f} ms")

    halvings = range(0, 5 if quick else 9)
    # The exact default: its automatic substeps, and a shorter maxStep (exact
    # too: it only costs more).
    add("exact", "auto", bench.fmu(record, params, rec_dt))
    h = rec_dt / 4
    add("exact", f"maxStep={h:.3g}", bench.fmu(record, dict(params, maxStep=h), rec_dt))
    add("step-end", "auto", bench.fmu(record, dict(params, solver=2), rec_dt))
    for k in halvings:
        h = rec_dt / 2 ** k
        add("step-end", f"maxStep={h:.3g}", bench.fmu(record, dict(params, solver=2, maxStep=h), rec_dt))
    for eps in ([1e-3] if quick else [1e-2, 1e-3, 1e-4]):
        h_stable = tanh_stable_step(params, eps)
        for factor in (0.9, 0.45, 0.225):
            h = min(factor * h_stable, rec_dt)
            if t_rec[-1] / h > 3e6:
                progress(f"{scene}/{label}: tanh eps={eps:g} step {h:.2g}: skipped (over 3e6 steps)")
                continue
            add(f"tanh eps={eps:g}", f"maxStep={h:.3g}",
                bench.fmu(record, dict(params, solver=3, frictionEps=eps, maxStep=h), rec_dt))
    if scene == "single" and opensees_block.available() is None:
        for k_stick in ([1e7] if quick else [1e6, 1e7, 1e8]):
            for dt in ([rec_dt, rec_dt / 4] if quick else [rec_dt, rec_dt / 2, rec_dt / 5, rec_dt / 10, rec_dt / 20]):
                add(f"opensees ks={k_stick:g}", f"dt={dt:.3g}", bench.opensees(record, params, dt, k_stick))
    return rows


def time_to_reach(points: list[tuple[float, float]], target: float) -> tuple[float, bool]:
    """(seconds, extrapolated): the least time from which every point of the
    method has error <= target (a lucky point of a method whose error does not
    fall monotonically does not count); otherwise a least-squares line in
    log-log through the four most expensive points (the trend), trusted only if the method is still converging there (error falls
    at least as fast as 1/seconds^0.5) and the target is within three decades of
    its best error. inf: the method does not reach the target (an error floor)."""
    by_cost = sorted(points, key=lambda p: p[1])
    reached = None
    for e, s in reversed(by_cost):
        if e > target:
            break
        reached = s
    if reached is not None:
        return reached, False
    pts = [(e, s) for e, s in by_cost if e > 0][-4:]
    if len(pts) < 2 or target < min(pts)[0] * 1e-3:
        return float("inf"), True
    x = np.log([s for _, s in pts])
    y = np.log([e for e, _ in pts])
    if np.ptp(x) == 0:
        return float("inf"), True
    slope, icpt = np.polyfit(x, y, 1)  # log error = slope log seconds + icpt
    if slope > -0.5:
        return float("inf"), True
    return float(np.exp((math.log(target) - icpt) / slope)), True


def summarize(rows: list[dict]) -> list[str]:
    lines = []
    panels = sorted({(r["scene"], r["record"]) for r in rows})
    for scene, record in panels:
        sub = [r for r in rows if r["scene"] == scene and r["record"] == record]
        lines.append(f"{scene} / {record}:")
        reach = {}
        for method in sorted({r["method"] for r in sub}):
            pts = [(r["err_peak_drift"], r["seconds"]) for r in sub if r["method"] == method]
            s, extrapolated = time_to_reach(pts, TARGET)
            reach[method] = s
            best = min(pts)
            note = " (extrapolated)" if extrapolated and math.isfinite(s) else ""
            when = f"{s * 1e3:.3g} ms{note}" if math.isfinite(s) else "not reached (an error floor, or no trend to extrapolate)"
            lines.append(f"  {method:18s} reaches {TARGET:g}: {when}; best error {best[0]:.2e} in {best[1] * 1e3:.3g} ms")
        ev = reach.get("exact", float("inf"))
        for method, s in reach.items():
            if method == "exact":
                continue
            if math.isfinite(s):
                lines.append(f"  at error {TARGET:g} exact is {s / ev:.3g}x faster than {method}")
            else:
                pts = [(r["err_peak_drift"], r["seconds"]) for r in sub if r["method"] == method]
                best_err, best_s = min(pts)
                ev_there, _ = time_to_reach(
                    [(r["err_peak_drift"], r["seconds"]) for r in sub if r["method"] == "exact"], best_err)
                lines.append(f"  {method} does not reach {TARGET:g} (exact: infinitely faster); at its best "
                             f"error {best_err:.2g} exact is {best_s / ev_there:.3g}x faster")
        default = next(r for r in sub if r["method"] == "exact" and r["setting"] == "auto")
        dominated = [r for r in sub if r["err_peak_drift"] < default["err_peak_drift"]
                     and r["seconds"] < default["seconds"]]
        lines.append(f"  default (exact, auto): error {default['err_peak_drift']:.2e} in "
                     f"{default['seconds'] * 1e3:.3g} ms; on the efficient front: {'yes' if not dominated else 'no'}"
                     + ("" if not dominated else f" (beaten by {dominated[0]['method']} {dominated[0]['setting']})"))
    return lines


def floor_seconds(record: Path) -> float | None:
    """Median seconds of the Nigam-Jennings recurrence over `record` (Tp 0.5 s,
    5 %), from examples/floor.rs; None when cargo cannot run it."""
    try:
        out = subprocess.run(["cargo", "run", "--quiet", "--release", "--example", "floor", "--",
                              str(record)], cwd=ROOT, capture_output=True, text=True, check=True)
        return float(out.stdout.strip())
    except (OSError, subprocess.CalledProcessError, ValueError):
        return None


def plot(rows: list[dict], path: Path, floors: dict | None = None):
    panels = sorted({(r["scene"], r["record"]) for r in rows})
    cols = 2
    fig, axes = plt.subplots(math.ceil(len(panels) / cols), cols, figsize=(12, 4.2 * math.ceil(len(panels) / cols)),
                             squeeze=False)
    # One colour per method across all panels.
    others = sorted({r["method"] for r in rows} - {"exact", "step-end"})
    styles = {"exact": ("C0", "o"), "step-end": ("C3", "s")}
    styles.update({m: (f"C{(i + 4) % 10}", "^" if m.startswith("tanh") else "D") for i, m in enumerate(others)})
    for ax, (scene, record) in zip(axes.flat, panels):
        sub = [r for r in rows if r["scene"] == scene and r["record"] == record]
        for method in sorted({r["method"] for r in sub}):
            pts = sorted((r["seconds"], max(r["err_peak_drift"], 1e-16)) for r in sub if r["method"] == method)
            color, marker = styles[method]
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker=marker, color=color, label=method, ms=4)
        d = next(r for r in sub if r["method"] == "exact" and r["setting"] == "auto")
        ax.loglog(d["seconds"], max(d["err_peak_drift"], 1e-16), "*", color="k", ms=14, label="default")
        if floors and floors.get(record):
            ax.axvline(floors[record], color="k", ls=":", lw=1.0,
                       label="floor: Nigam-Jennings, bare SDOF (Rust)")
        ax.axhline(TARGET, color="gray", ls="--", lw=0.8)
        ax.set_title(f"{scene} under {record}")
        ax.set_xlabel("seconds per simulation")
        ax.set_ylabel("relative error of peak drift")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    for ax in axes.flat[len(panels):]:
        ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--quick", action="store_true", help="harmonic record and fewer settings (for tests)")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per point (median)")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    reason = opensees_block.available()
    if reason:
        print(f"OpenSees is not available ({reason}); its points are left out", flush=True)
    records = [harmonic_record(args.out)] + ([] if args.quick else [REAL_RECORD])
    scenes = ["single"] if args.quick else list(SCENES)
    started = time.perf_counter()
    rows = []
    with Model() as model:
        bench = Bench(model, args.repeats)
        jobs = [(s, r) for r in records for s in scenes]
        for i, (scene, record) in enumerate(jobs, 1):
            def progress(msg, i=i):
                print(f"[{i}/{len(jobs)} {time.perf_counter() - started:6.0f} s] {msg}", flush=True)
            rows += sweep(bench, scene, record, args.quick, progress)
    with open(args.out / "accuracy_speed.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    floors = {}
    for record in records:
        label = "harmonic" if record.suffix == ".csv" else record.stem
        floors[label] = floor_seconds(record)
    plot(rows, args.out / "accuracy_speed.png", floors)
    summary = summarize(rows)
    for label, floor in floors.items():
        if floor:
            for r in rows:
                if r["record"] == label and r["method"] == "exact" and r["setting"] == "auto":
                    summary.append(f"{r['scene']} / {label}: default {r['seconds'] * 1e6:.0f} us = "
                                   f"{r['seconds'] / floor:.1f}x the floor ({floor * 1e6:.1f} us, "
                                   f"Nigam-Jennings of the bare structure in Rust, FMU call included)")
    (args.out / "summary.txt").write_text("\n".join(summary) + "\n")
    print("\n".join(summary))
    print(f"wrote {args.out}/accuracy_speed.csv, accuracy_speed.png, summary.txt "
          f"in {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()
