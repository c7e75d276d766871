"""The scene advisor: which model of a stacked live load may an engineer use for this structure?

    python scripts/advise.py --Tp 0.8 --alpha 0.25 0.25 --mu 0.1 0.05 [--muk ...] [--zeta 0.05]
                             [--zone III|V [--level DBE|MCE] | --records DIR] [--scale F]
                             [--cost-tol 0.25] [--unconservative-tol 0] [--mu-uncertainty 0.3]
                             [--mu-points 5] [--max-slip M [M ...]] [--json FILE] [--png FILE]

Runs the stack as given (1 to 8 blocks, bottom first) over every record of a suite,
and the simpler models of the same live load:
- bare:   the bare structure, the live load carrying no seismic mass;
- rigid:  the whole live load rigidly attached (a linear SDOF of mass mp (1 + alpha));
- single: one block of the total mass with the bottom interface's friction.
bare and rigid are linear models (a response-spectrum analysis can use them);
single still needs a time-history analysis.

The rule is asymmetric. A simpler model is accepted only if its mean peak drift is
- never below the stack's by more than --unconservative-tol (default 0), at the
  nominal friction and at every point of the friction sweep (every mu times
  1 -+ --mu-uncertainty, default 30 %; --mu-points common factors, plus for two
  blocks or more the splits where the lower interfaces are high and the upper low
  and vice versa), and
- above the stack's by at most --cost-tol (default 25 %) at the nominal friction.
Relative differences below 1e-6 (the engine's accuracy target) count as equal. Of
the accepted linear models the one closest to the stack wins; else the single
block if accepted; else the stack itself.

Also reported: each model's ratio to the stack per record (min, max, percentiles,
on how many records it is below the stack), the peak slip of every block relative
to the body below against --max-slip (a warning when a block would slide off), and
the effective seismic-mass fraction: the share of the live load that, rigidly
attached, gives the stack's mean peak drift (a root of the rigid model's mean drift
over the attached fraction), with its spread over the records and over the friction
sweep. Everything goes to --json; --png draws the scene's charts.

Suites: --zone III or V (the paper's 11 records matched to IS 1893 hard soil DBE;
built on first use) at --level DBE (as matched) or MCE (records x 2), or --records
DIR (every .AT2 and .csv file in it, used as they are); --scale F multiplies either.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import study  # noqa: E402
import sll  # noqa: E402
from sll import seismic, study_tasks  # noqa: E402

FLOOR = 1e-6  # relative differences below the engine's accuracy target count as equal
SIMPLER = ("bare", "rigid", "single")
LINEAR = ("bare", "rigid")
PERCENTILES = (10, 50, 90)
FRACTION_GRID = np.round(np.linspace(0.0, 1.0, 11), 12)  # attached share of the live load
FRACTION_MAX = 2.0  # searched up to here when the stack drifts more than the fully attached load
FRACTION_XTOL = 1e-4

WORDS = {
    "bare": "leave the live load out of the seismic mass (the bare structure)",
    "rigid": "count the whole live load as seismic mass, rigidly attached to the structure",
    "single": "model the stack as one sliding block (total mass, bottom friction)",
    "stack": "model the stack: no simpler model passes the rule",
}


class Runner:
    """Runs of one scene's models over a suite, each (record, parameters) once."""

    def __init__(self, records: list[Path], scale: float):
        self.records, self.scale, self.cache = [str(r) for r in records], scale, {}

    def peak(self, record: str, params: dict) -> dict:
        if self.scale != 1.0:
            params = {**params, "recordScale": self.scale}
        key = (record, tuple(sorted(params.items())))
        if key not in self.cache:
            self.cache[key] = study_tasks.peaks(record, params)
        return self.cache[key]

    def peaks(self, params: dict) -> list[dict]:
        return [self.peak(r, params) for r in self.records]

    def drifts(self, params: dict) -> np.ndarray:
        return np.array([p["peakUp"] for p in self.peaks(params)])


def stack_params(tp, zeta, alphas, mus, muks) -> dict:
    p = study_tasks.stack_params(tp, alphas, mus, zeta)
    p.update({f"muk[{j}]": mk for j, mk in enumerate(muks, 1)})
    return p


def single_params(tp, zeta, alphas, mu1, muk1) -> dict:
    return {**study_tasks.single_params(tp, sum(alphas), mu1, zeta), "muk[1]": muk1}


def rigid_params(tp, zeta, alphas, fraction: float = 1.0) -> dict:
    """The structure with `fraction` of the live load rigidly attached (0: bare)."""
    return study_tasks.rigid_params(tp, fraction * sum(alphas), zeta)


def sweep_factors(n: int, uncertainty: float, points: int) -> list[tuple[float, ...]]:
    """Factors on every interface's mu: `points` common factors over 1 -+ uncertainty
    (nominal always included) and, for n >= 2, each split of the stack with the
    interfaces below it high and above it low, and the reverse."""
    if uncertainty == 0.0:
        return [(1.0,) * n]
    common = sorted({round(float(f), 12) for f in np.linspace(1 - uncertainty, 1 + uncertainty, points)} | {1.0})
    out = [(f,) * n for f in common]
    lo, hi = 1.0 - uncertainty, 1.0 + uncertainty
    for k in range(1, n):
        out.append((hi,) * k + (lo,) * (n - k))
        out.append((lo,) * k + (hi,) * (n - k))
    return out


def direction(ratio: float) -> str:
    if abs(ratio - 1.0) <= FLOOR:
        return "equal"
    return "conservative" if ratio > 1.0 else "unconservative"


def spread(values: np.ndarray) -> dict:
    return {"min": float(np.min(values)), "max": float(np.max(values)),
            **{f"p{q}": float(np.percentile(values, q)) for q in PERCENTILES}}


def illinois(f, a: float, b: float, fa: float, fb: float, tol: float) -> float:
    """A root of f in [a, b] (fa, fb of opposite signs) by the Illinois method."""
    side = 0
    for _ in range(60):
        c = (a * fb - b * fa) / (fb - fa)
        fc = f(c)
        if fc == 0.0 or b - a < FRACTION_XTOL:
            return c
        if (fc > 0) == (fb > 0):
            b, fb = c, fc
            if side == -1:
                fa /= 2
            side = -1
        else:
            a, fa = c, fc
            if side == 1:
                fb /= 2
            side = 1
        if abs(fc) <= tol:
            return c
    return c


def fraction_roots(drift, target: float) -> dict:
    """Attached fractions f in [0, FRACTION_MAX] with drift(f) = target: every sign
    change of drift - target on the grid, refined. Where drift(f) is not monotonic
    there are several; `fraction` is the one nearest the linear interpolation
    between the bare structure (0) and the whole load attached (1), which picks 0
    at mu = 0 and 1 at mu -> infinity. Without a root: `below` (the stack drifts
    less than the bare structure) or `above` (more than FRACTION_MAX of the load
    attached)."""
    tol = FLOOR * target
    grid = list(FRACTION_GRID)
    g = [drift(f) - target for f in grid]
    if g[-1] < -tol:  # the stack drifts more than with the whole load attached: look further
        extra = np.round(np.arange(1.1, FRACTION_MAX + 1e-9, 0.1), 12)
        grid += list(extra)
        g += [drift(f) - target for f in extra]
    roots = [f for f, v in zip(grid, g) if abs(v) <= tol]
    for (a, ga), (b, gb) in zip(zip(grid, g), zip(grid[1:], g[1:])):
        if abs(ga) > tol and abs(gb) > tol and (ga > 0) != (gb > 0):
            roots.append(illinois(lambda f: drift(f) - target, a, b, ga, gb, tol))
    roots = sorted(roots)
    increasing = all(b >= a for a, b in zip(g, g[1:]))
    if roots:
        d0, d1 = g[0], g[len(FRACTION_GRID) - 1]
        guess = min(max(-d0 / (d1 - d0), 0.0), FRACTION_MAX) if d1 != d0 else 0.5
        best = min(roots, key=lambda f: (abs(f - guess), -f))
        return {"fraction": best, "roots": roots, "status": "found", "increasing": increasing}
    below = g[0] > 0
    return {"fraction": 0.0 if below else grid[-1], "roots": [], "status": "below" if below else "above",
            "increasing": increasing}


def advise(records: list[Path], tp: float, zeta: float, alphas: list[float], mus: list[float],
           muks: list[float], cost_tol: float = 0.25, unconservative_tol: float = 0.0,
           mu_uncertainty: float = 0.3, mu_points: int = 5, max_slip: list[float] | None = None,
           scale: float = 1.0) -> dict:
    n = len(alphas)
    run = Runner(records, scale)
    names = [Path(r).stem for r in records]

    def at(factors):
        m = [mu * f for mu, f in zip(mus, factors)]
        mk = [mu * f for mu, f in zip(muks, factors)]
        stack = run.peaks(stack_params(tp, zeta, alphas, m, mk))
        return {"factors": list(factors), "mus": m, "muks": mk,
                "stack": np.array([p["peakUp"] for p in stack]),
                "single": run.drifts(single_params(tp, zeta, alphas, m[0], mk[0])),
                "slips": np.array([[p[f"peakSlip{j}"] for j in range(1, n + 1)] for p in stack])}

    points = [at(f) for f in sweep_factors(n, mu_uncertainty, mu_points)]
    nominal = next(p for p in points if all(f == 1.0 for f in p["factors"]))
    drifts = {"stack": nominal["stack"], "single": nominal["single"],
              "rigid": run.drifts(rigid_params(tp, zeta, alphas)),
              "bare": run.drifts(rigid_params(tp, zeta, alphas, 0.0))}
    for name, d in zip(names, nominal["stack"]):
        if not d > 0.0:
            raise ValueError(f"record {name}: the stack's peak drift is {d}: an empty record? Every record must "
                             "move the structure")
    u = {k: float(np.mean(v)) for k, v in drifts.items()}

    models = {}
    for m in SIMPLER:
        ratio = u[m] / u["stack"]
        per_record = drifts[m] / drifts["stack"]
        below = per_record < 1.0 - FLOOR
        sweep = [float(np.mean(p[m] if m == "single" else drifts[m]) / np.mean(p["stack"])) for p in points]
        worst = int(np.argmin(sweep))
        accepted, why = judge(ratio, sweep, [p["factors"] for p in points], cost_tol, unconservative_tol,
                              mu_uncertainty)
        models[m] = {
            "mean_peak_drift": u[m], "ratio_to_stack": ratio, "direction": direction(ratio),
            "per_record": {"ratios": per_record.tolist(), **spread(per_record),
                           "unconservative_records": int(np.sum(below)),
                           "largest_shortfall": float(max(0.0, 1.0 - np.min(per_record)))},
            "friction_sweep": {"ratios": sweep, "worst_ratio": sweep[worst],
                               "worst_at_factors": points[worst]["factors"]},
            "accepted": accepted, "reason": why,
        }
    linear = [m for m in LINEAR if models[m]["accepted"]]
    if linear:
        verdict = min(linear, key=lambda m: (abs(models[m]["ratio_to_stack"] - 1.0), m != "rigid"))
    elif models["single"]["accepted"]:
        verdict = "single"
    else:
        verdict = "stack"

    # The effective seismic-mass fraction: nominal mean, per record, over the sweep.
    def mean_rigid(f):
        return float(np.mean(run.drifts(rigid_params(tp, zeta, alphas, f))))

    frac = fraction_roots(mean_rigid, u["stack"])
    per_rec = [fraction_roots(lambda f, rec=rec: run.peak(rec, rigid_params(tp, zeta, alphas, f))["peakUp"],
                              float(drifts["stack"][i])) for i, rec in enumerate(run.records)]
    values = np.array([r["fraction"] for r in per_rec])
    over_sweep = [fraction_roots(mean_rigid, float(np.mean(p["stack"])))["fraction"] for p in points]
    fraction = {
        "mean": frac["fraction"], "status": frac["status"], "roots": frac["roots"],
        "rigid_drift_increasing": frac["increasing"],
        "per_record": {"values": values.tolist(), **spread(values),
                       "below_zero": sum(r["status"] == "below" for r in per_rec),
                       "above_max": sum(r["status"] == "above" for r in per_rec)},
        "friction_sweep": {"values": over_sweep, "min": min(over_sweep), "max": max(over_sweep)},
        # With the rigid model's mean drift rising with the attached share, the
        # sweep's largest fraction is not unconservative anywhere in the sweep.
        "design_value": max(over_sweep) if frac["increasing"] else None,
    }

    slips = slip_check(points, nominal, names, max_slip)
    warnings = list(slips["warnings"])
    chosen = models.get(verdict)
    if chosen and chosen["per_record"]["unconservative_records"]:
        warnings.append(
            f"{verdict}: below the stack's peak drift on {chosen['per_record']['unconservative_records']} of "
            f"{len(records)} records (by up to {100 * chosen['per_record']['largest_shortfall']:.1f} %); the rule "
            f"judges the mean over the suite, as design codes do")
    if frac["status"] == "found" and len(frac["roots"]) > 1:
        warnings.append("the rigid model's mean drift is not monotonic in the attached fraction: several fractions "
                        f"give the stack's drift ({', '.join(f'{r:.3f}' for r in frac['roots'])}); the one nearest "
                        "the linear interpolation between bare and fully attached is reported")
    return {
        "scene": {"Tp": tp, "zeta": zeta, "alphas": alphas, "mus": mus, "muks": muks, "blocks": n},
        "records": [str(r) for r in records], "record_scale": scale,
        "rule": {"cost_tolerance": cost_tol, "unconservative_tolerance": unconservative_tol,
                 "equal_below": FLOOR, "mu_uncertainty": mu_uncertainty, "mu_points": mu_points,
                 "text": "a simpler model is accepted if its mean peak drift is at most "
                         f"{100 * unconservative_tol:g} % below the stack's at every friction point and at most "
                         f"{100 * cost_tol:g} % above it at the nominal friction"},
        "mean_peak_drift": u, "DRR1": u["stack"] / u["rigid"], "DRR2": u["single"] / u["rigid"],
        "error_against_stack": {m: models[m]["ratio_to_stack"] - 1.0 for m in SIMPLER},
        "models": models, "verdict": verdict, "advice": WORDS[verdict],
        "effective_mass_fraction": fraction, "peak_slips": slips,
        "friction_sweep": [{"factors": p["factors"], "mus": p["mus"], "muks": p["muks"],
                            "u_stack": float(np.mean(p["stack"])), "u_single": float(np.mean(p["single"])),
                            "max_peak_slips": p["slips"].max(axis=0).tolist(), "fraction": f}
                           for p, f in zip(points, over_sweep)],
        "per_record": {"names": names, **{k: v.tolist() for k, v in drifts.items()},
                       "peak_slips": nominal["slips"].tolist()},
        "warnings": warnings,
    }


def judge(ratio: float, sweep: list[float], factors: list, cost_tol: float, unc_tol: float,
          uncertainty: float) -> tuple[bool, str]:
    """The rule for one simpler model, from its mean drift over the stack's at the
    nominal friction (`ratio`) and at each point of the friction sweep: accepted if
    never more than `unc_tol` below the stack and, at the nominal friction, at most
    `cost_tol` above it. Returns the decision and a message saying which way and by
    how much."""
    def how(r):
        d = direction(r)
        return "equal to the stack" if d == "equal" else f"{d} by {100 * abs(r - 1):.1f} %"

    worst = int(np.argmin(sweep))
    safe = sweep[worst] >= 1.0 - unc_tol - FLOOR
    cheap = ratio - 1.0 <= cost_tol + FLOOR
    text = f"{how(ratio)} at the nominal friction"
    if uncertainty and len(sweep) > 1:
        text += f"; worst over mu x (1 -+ {uncertainty:g}): {how(sweep[worst])} (mu factors {fmt_factors(factors[worst])})"
    if not safe:
        return False, f"rejected: {text}; allowed below the stack: {100 * unc_tol:g} %"
    if not cheap:
        return False, f"rejected: {text}; cost tolerance {100 * cost_tol:g} %"
    return True, f"accepted: {text}"


def fmt_factors(factors) -> str:
    return " ".join(f"{f:g}" for f in factors)


def slip_check(points, nominal, names, max_slip) -> dict:
    """Peak slip of each block relative to the body below, per record, against the
    allowable displacement (one value for every block, or one per block)."""
    n = nominal["slips"].shape[1]
    allow = None if not max_slip else (list(max_slip) * n if len(max_slip) == 1 else list(max_slip))
    blocks, warnings = [], []
    for j in range(n):
        s = nominal["slips"][:, j]
        worst_point = max(points, key=lambda p: p["slips"][:, j].max())
        entry = {"block": j + 1, "mean": float(np.mean(s)), "max": float(np.max(s)),
                 "record_of_max": names[int(np.argmax(s))] if np.max(s) > 0 else None,
                 "max_over_friction_sweep": float(worst_point["slips"][:, j].max()),
                 "at_factors": worst_point["factors"]}
        if allow:
            entry["allowable"] = allow[j]
            entry["records_beyond"] = int(np.sum(s > allow[j]))
            entry["slides_off"] = bool(entry["records_beyond"] or entry["max_over_friction_sweep"] > allow[j])
            if entry["records_beyond"]:
                warnings.append(f"block {j + 1} would slide off: its peak slip on the body below reaches "
                                f"{entry['max']:.3f} m ({entry['record_of_max']}), beyond the allowable "
                                f"{allow[j]:g} m on {entry['records_beyond']} of {len(s)} records; the drifts "
                                "assume it stays on")
            elif entry["slides_off"]:
                warnings.append(f"block {j + 1} would slide off with mu x ({fmt_factors(entry['at_factors'])}): "
                                f"peak slip {entry['max_over_friction_sweep']:.3f} m against the allowable "
                                f"{allow[j]:g} m (at the nominal friction it stays on: {entry['max']:.3f} m)")
        blocks.append(entry)
    return {"allowable": allow, "blocks": blocks, "slides_off": any(b.get("slides_off") for b in blocks),
            "warnings": warnings}


def print_report(r: dict, suite_name: str):
    s = r["scene"]
    print(f"Scene: Tp {s['Tp']:g} s, zeta {s['zeta']:g}; {s['blocks']} block(s), bottom first: alpha "
          f"{' '.join(f'{a:g}' for a in s['alphas'])}, mus {' '.join(f'{m:g}' for m in s['mus'])}, "
          f"muk {' '.join(f'{m:g}' for m in s['muks'])}")
    print(f"Suite: {suite_name}; {len(r['records'])} records")
    u = r["mean_peak_drift"]
    print(f"Mean peak drift of the stack: {u['stack']:.5g} m (DRR1 {r['DRR1']:.3f}, DRR2 {r['DRR2']:.3f})")
    print(f"{'model':7s} {'drift / stack':>13s}  records: {'min':>5s} {'p50':>5s} {'max':>5s} {'below':>6s}  "
          f"{'worst mu':>8s}  verdict")
    for m in SIMPLER:
        x = r["models"][m]
        pr, sw = x["per_record"], x["friction_sweep"]
        print(f"{m:7s} {x['ratio_to_stack']:13.3f}  {'':8s} {pr['min']:5.2f} {pr['p50']:5.2f} {pr['max']:5.2f} "
              f"{pr['unconservative_records']:>2d}/{len(r['records']):<3d}  {sw['worst_ratio']:8.3f}  {x['reason']}")
    print(f"Advice ({r['rule']['text']}): {r['verdict']} — {r['advice']}.")
    f = r["effective_mass_fraction"]
    pr, sw = f["per_record"], f["friction_sweep"]
    status = {"found": "", "below": " (the stack drifts less than the bare structure: 0 is conservative)",
              "above": f" (the stack drifts more than with {FRACTION_MAX:g} x the load attached)"}[f["status"]]
    print(f"Effective seismic-mass fraction: {f['mean']:.3f} of the live load{status}; records: min {pr['min']:.2f}, "
          f"p10 {pr['p10']:.2f}, median {pr['p50']:.2f}, p90 {pr['p90']:.2f}, max {pr['max']:.2f}; over the "
          f"friction sweep {sw['min']:.3f}-{sw['max']:.3f}"
          + (f"; design value {f['design_value']:.3f}" if f["design_value"] is not None else ""))
    for b in r["peak_slips"]["blocks"]:
        allow = f" (allowable {b['allowable']:g} m)" if "allowable" in b else ""
        where = f" ({b['record_of_max']})" if b["record_of_max"] else ""
        print(f"Block {b['block']}: peak slip on the body below mean {b['mean']:.4f} m, max {b['max']:.4f} m{where}, "
              f"{b['max_over_friction_sweep']:.4f} m over the friction sweep{allow}")
    for w in r["warnings"]:
        print(f"WARNING: {w}")


def plot(r: dict, path: Path, title: str):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rule = r["rule"]
    fig, axes = plt.subplots(2, 2, figsize=(12, 8.5))
    ax = axes[0, 0]
    names = r["per_record"]["names"]
    for k, m in enumerate(SIMPLER):
        ratios = r["models"][m]["per_record"]["ratios"]
        ax.scatter(np.full(len(ratios), k) + np.linspace(-0.2, 0.2, len(ratios)), ratios, s=14, color=f"C{k}")
        ax.plot([k - 0.3, k + 0.3], [r["models"][m]["ratio_to_stack"]] * 2, color="k", lw=2)
    ax.axhspan(1 - rule["unconservative_tolerance"], 1 + rule["cost_tolerance"], color="tab:green", alpha=0.12,
               label="accepted band (mean)")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(range(len(SIMPLER)), [f"{m}\n{r['models'][m]['direction']}" for m in SIMPLER])
    ax.set_ylabel("peak drift / stack's, per record (bar: mean)")
    ax.set_title(f"models against the stack over {len(names)} records; advice: {r['verdict']}", fontsize=10)
    ax.legend(fontsize=8)
    ax = axes[0, 1]
    sweep = r["friction_sweep"]
    x = np.arange(len(sweep))
    for k, m in enumerate(SIMPLER):
        ax.plot(x, r["models"][m]["friction_sweep"]["ratios"], "o-", color=f"C{k}", label=m)
    ax.axhspan(1 - rule["unconservative_tolerance"], 1 + rule["cost_tolerance"], color="tab:green", alpha=0.12)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(x, [fmt_factors(p["factors"]) for p in sweep], rotation=45, fontsize=7)
    ax.set_xlabel("mu factors per interface (bottom first)")
    ax.set_ylabel("mean drift / stack's")
    ax.set_title(f"friction uncertainty: every mu x (1 -+ {rule['mu_uncertainty']:g})", fontsize=10)
    ax.legend(fontsize=8)
    ax = axes[1, 0]
    f = r["effective_mass_fraction"]
    ax.hist(f["per_record"]["values"], bins=10, color="0.7", label="per record")
    ax.axvline(f["mean"], color="tab:red", lw=2, label=f"from the mean drifts: {f['mean']:.3f}")
    ax.axvspan(f["friction_sweep"]["min"], f["friction_sweep"]["max"], color="tab:red", alpha=0.15,
               label="over the friction sweep")
    ax.set_xlabel("effective seismic-mass fraction of the live load")
    ax.set_ylabel("records")
    ax.set_title("share of the live load that, rigidly attached, gives the stack's drift", fontsize=10)
    ax.legend(fontsize=8)
    ax = axes[1, 1]
    slips = np.array(r["per_record"]["peak_slips"])
    for j in range(slips.shape[1]):
        ax.scatter(np.full(len(slips), j + 1) + np.linspace(-0.2, 0.2, len(slips)), slips[:, j], s=14, color=f"C{j}")
        b = r["peak_slips"]["blocks"][j]
        if "allowable" in b:
            ax.plot([j + 0.6, j + 1.4], [b["allowable"]] * 2, color="tab:red", lw=2)
    ax.set_xticks(range(1, slips.shape[1] + 1))
    ax.set_xlabel("block (bottom first); red: allowable displacement")
    ax.set_ylabel("peak slip on the body below (m)")
    ax.set_title("sliding-off check, per record at the nominal friction", fontsize=10)
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--Tp", type=float, required=True, help="period of the bare structure (s)")
    ap.add_argument("--zeta", type=float, default=0.05)
    ap.add_argument("--alpha", type=float, nargs="+", required=True, help="block masses / mp, bottom first")
    ap.add_argument("--mu", type=float, nargs="+", required=True, help="static friction of each interface")
    ap.add_argument("--muk", type=float, nargs="+", help="kinetic friction (default: = mu)")
    src = ap.add_mutually_exclusive_group()
    src.add_argument("--zone", choices=["III", "V"], help="the paper's suite (default V)")
    src.add_argument("--records", type=Path, help="a folder of .AT2 / .csv records")
    ap.add_argument("--level", choices=list(seismic.LEVELS),
                    help="with --zone: DBE (the suite as matched, default) or MCE (records x 2)")
    ap.add_argument("--scale", type=float, default=1.0, help="a further factor on every record")
    ap.add_argument("--cost-tol", "--tol", type=float, default=0.25,
                    help="how far above the stack's mean drift a simpler model may be (default 0.25; --tol is "
                         "its old name, from when the tolerance was symmetric)")
    ap.add_argument("--unconservative-tol", type=float, default=0.0,
                    help="how far below the stack's mean drift a simpler model may be (default 0)")
    ap.add_argument("--mu-uncertainty", type=float, default=0.3, help="relative friction uncertainty (default 0.3)")
    ap.add_argument("--mu-points", type=int, default=5, help="common friction factors in the sweep (default 5)")
    ap.add_argument("--max-slip", type=float, nargs="+",
                    help="allowable slip of a block on the body below (m): one value, or one per block")
    ap.add_argument("--json", type=Path, help="also write the result here")
    ap.add_argument("--png", type=Path, help="draw the scene's charts here")
    args = ap.parse_args(argv)
    muks = args.muk or args.mu
    n = len(args.alpha)
    checks = [
        (1 <= n <= 8 and len(args.mu) == n and len(muks) == n,
         "give one --alpha, --mu (and --muk) value per block, 1 to 8 blocks"),
        (math.isfinite(args.Tp) and args.Tp > 0, f"--Tp {args.Tp}: must be finite and > 0"),
        (0 <= args.zeta < 1, f"--zeta {args.zeta}: must be in [0, 1)"),
        (all(math.isfinite(a) and a > 0 for a in args.alpha), f"--alpha {args.alpha}: each must be finite and > 0"),
        (all(math.isfinite(m) and m >= 0 for m in args.mu + muks), "--mu, --muk: each must be finite and >= 0"),
        (all(k <= s for s, k in zip(args.mu, muks)), f"--muk {muks}: each must be <= its --mu {args.mu}"),
        (math.isfinite(args.scale) and args.scale > 0, f"--scale {args.scale}: must be finite and > 0"),
        (args.cost_tol >= 0, f"--cost-tol {args.cost_tol}: must be >= 0"),
        (0 <= args.unconservative_tol < 1, f"--unconservative-tol {args.unconservative_tol}: must be in [0, 1)"),
        (0 <= args.mu_uncertainty < 1, f"--mu-uncertainty {args.mu_uncertainty}: must be in [0, 1)"),
        (args.mu_points >= 1, f"--mu-points {args.mu_points}: must be >= 1"),
        (not args.max_slip or (len(args.max_slip) in (1, n) and all(x > 0 for x in args.max_slip)),
         f"--max-slip {args.max_slip}: one value or one per block, each > 0 (m)"),
        (not (args.records and args.level), "--level applies to the paper's suites (--zone), which are matched to "
                                             "DBE; scale your own records with --scale"),
    ]
    for ok, message in checks:
        if not ok:
            ap.error(message)
    level = args.level or "DBE"
    if args.records is None and args.zone is None:
        args.zone = "V"
    if args.records is not None and not args.records.is_dir():
        ap.error(f"--records {args.records}: no such folder")
    if args.records:
        records = sorted(p for p in args.records.iterdir() if p.suffix.lower() in (".at2", ".csv"))
        if not records:
            ap.error(f"no .AT2 or .csv files in {args.records}")
        for path in records:  # a bad file is named with its line, not a traceback
            try:
                sll.read_record(path)
            except (ValueError, OSError) as e:
                ap.error(f"--records: {e}")
        scale = args.scale
        suite_name = f"{args.records}" + (f" x {scale:g}" if scale != 1.0 else "")
    else:
        records = study.suite(args.zone, quick=False)
        label, scale = study.intensity(level, args.scale)
        suite_name = (f"Zone {args.zone} at {label} (11 records matched to IS 1893 hard soil DBE, x {scale:g}; "
                      f"design PGA {study.design_pga(args.zone, label):.3g} g)")
    r = advise(records, args.Tp, args.zeta, args.alpha, args.mu, muks, args.cost_tol, args.unconservative_tol,
               args.mu_uncertainty, args.mu_points, args.max_slip, scale)
    r["suite"] = suite_name
    r["zone"], r["level"] = (None, None) if args.records else (args.zone, label)
    print_report(r, suite_name)
    if args.json:
        args.json.write_text(json.dumps(r, indent=1) + "\n")
    if args.png:
        s = r["scene"]
        plot(r, args.png, f"Tp {s['Tp']:g} s, alpha {' '.join(f'{a:g}' for a in s['alphas'])}, mu "
                          f"{' '.join(f'{m:g}' for m in s['mus'])}; {suite_name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
