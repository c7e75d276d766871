"""The scene advisor: which model of a stacked live load may an engineer use for this structure?

    python scripts/advise.py --Tp 0.8 --alpha 0.25 0.25 --mu 0.1 0.05 [--muk ...] [--zeta 0.05]
                             [--zone III|V [--level DBE|MCE] | --records DIR] [--scale F]
                             [--cost-tol 0.25] [--unconservative-tol 0] [--mu-uncertainty 0.3]
                             [--max-slip M [M ...]] [--occupancy storage|office|residential|shopping]
                             [--imposed-load KN_M2] [--json FILE] [--png FILE]

Runs the stack as given (1 to 8 blocks, bottom first) over every record of a suite,
and the simpler models of the same live load:
- bare:   the bare structure, the live load carrying no seismic mass;
- rigid:  the whole live load rigidly attached (a linear SDOF of mass mp (1 + alpha));
- single: one block of the total mass with the bottom interface's friction.
bare and rigid are linear models (a response-spectrum analysis can use them);
single still needs a time-history analysis.

The rule is asymmetric. A simpler model is accepted only if its mean peak drift is
- never below the stack's by more than --unconservative-tol (default 0) anywhere in
  the friction box: every interface's mu (static and kinetic) times its own factor
  in 1 -+ --mu-uncertainty (default 30 %), searched on a grid with refinement around
  the worst points (scripts/sll/box_search.py), judged with the search's margin, and
- above the stack's by at most --cost-tol (default 25 %) at the nominal friction.
Relative differences below 1e-6 (the engine's accuracy target) count as equal. Of
the accepted linear models the one closest to the stack wins; else the single
block if accepted; else the stack itself.

Sliding off is a verdict: with --max-slip, if a block's slip on the body below
passes the allowable displacement on any record anywhere in the friction box, the
advice says which block, on how many records, by how much, and what to do, with
the drift of the structure once that block (and everything on it) is gone,
computed by runs of the reduced stack.

Also reported: each model's ratio to the stack per record, at the nominal friction
and at the model's worst point of the box; the effective seismic-mass fraction
(the share of the live load that, rigidly attached, gives the stack's mean peak
drift) with its spread; and beside it the live-load share that IS 1893 (Part
1):2016, ASCE 7-16 and EN 1998-1 would count for --occupancy (scripts/sll/codes.py),
with the drift each gives and whether it is unconservative for this scene.
Everything goes to --json; --png draws the scene's charts.

Suites: --zone III or V (the paper's 11 records matched to IS 1893 hard soil DBE;
built on first use with progress, cached under ~/.cache/stacked-live-load) at
--level DBE (as matched) or MCE (records x 2), checked over the scene's periods
(ASCE 7-16 16.2: 0.2 x the bare period to 2 x the loaded period); or --records DIR
(every .AT2 and .csv file in it, used as they are); --scale F multiplies either.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import use_venv  # noqa: E402,F401  (re-runs this script under the repository's .venv if needed)
import numpy as np  # noqa: E402

import ground_motions  # noqa: E402
import study  # noqa: E402
import sll  # noqa: E402
from sll import box_search, codes, seismic, study_tasks  # noqa: E402

FLOOR = 1e-6  # relative differences below the engine's accuracy target count as equal
SIMPLER = ("bare", "rigid", "single")
LINEAR = ("bare", "rigid")
PERCENTILES = (10, 50, 90)
FRACTION_GRID = np.round(np.linspace(0.0, 1.0, 11), 12)  # attached share of the live load
FRACTION_MAX = 2.0  # searched up to here when the stack drifts more than the fully attached load
FRACTION_XTOL = 1e-4
REDUCED_BUDGET = 200  # grid points for the stack left when blocks slide off

WORDS = {
    "bare": "leave the live load out of the seismic mass (the bare structure)",
    "rigid": "count the whole live load as seismic mass, rigidly attached to the structure",
    "single": "model the stack as one sliding block (total mass, bottom friction)",
    "stack": "model the stack: no simpler model passes the rule",
    "slides-off": "a block slides off: restrain it, give it more edge distance, or design for the loss of its mass",
}


class Runner:
    """Runs of one scene's models over a suite through the library's batch entry
    (`sllRunBatch`, one call per record for many parameter sets), each (record,
    parameters) once."""

    def __init__(self, records: list[Path], scale: float):
        self.records, self.scale, self.cache = [str(r) for r in records], scale, {}
        self.model = sll.shared_model()
        self.runs = 0

    @staticmethod
    def key(params: dict) -> tuple:
        return tuple(sorted((k, float(v)) for k, v in params.items()))

    def run(self, params_list: list[dict]) -> list[list[dict]]:
        """Peaks per parameter set, per record."""
        keys = [self.key(p) for p in params_list]
        todo = {}
        for k, p in zip(keys, params_list):
            if (k, self.records[0]) not in self.cache and k not in todo:
                todo[k] = p
        if todo:
            for rec in self.records:
                rows = self.model.run_batch(rec, list(todo.values()), scale=self.scale)
                for k, row in zip(todo, rows):
                    self.cache[(k, rec)] = row
            self.runs += len(todo) * len(self.records)
        return [[self.cache[(k, rec)] for rec in self.records] for k in keys]

    def peaks(self, params: dict) -> list[dict]:
        return self.run([params])[0]

    def drifts(self, params: dict) -> np.ndarray:
        return np.array([p["peakUp"] for p in self.peaks(params)])

    def peak(self, record: str, params: dict) -> dict:
        return self.peaks(params)[self.records.index(record)]


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
    """Named points of the friction box, evaluated besides the box search and listed in
    the report: `points` common factors over 1 -+ uncertainty (nominal always
    included) and, for n >= 2, each split of the stack with the interfaces below it
    high and above it low, and the reverse."""
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


def how(r: float) -> str:
    d = direction(r)
    return "equal to the stack" if d == "equal" else f"{d} by {100 * abs(r - 1):.1f} %"


def versus(r: float) -> str:
    """A ratio of drifts in words: "12.0 % above", "3.1 % below", "equal to"."""
    if abs(r - 1.0) <= FLOOR:
        return "equal to"
    return f"{100 * abs(r - 1):.1f} % {'above' if r > 1 else 'below'}"


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


class Scene:
    """One structure and stack over a suite: the stack and the single block at any
    friction factors (batched), and the rigid model at any attached share."""

    def __init__(self, run: Runner, tp, zeta, alphas, mus, muks, allow=None, progress=False):
        self.run, self.tp, self.zeta, self.alphas = run, tp, zeta, list(alphas)
        self.mus, self.muks, self.allow, self.progress = list(mus), list(muks), allow, progress
        self.n = len(alphas)
        self.seen: dict[tuple, dict] = {}
        self.started = self.shown = time.perf_counter()

    def key(self, f) -> tuple:
        return tuple(round(float(x), 10) for x in f)

    def points(self, factors) -> list[dict]:
        """Per-record drifts and slips of the stack and the single block at each factor vector."""
        factors = [tuple(float(x) for x in f) for f in factors]
        todo = [f for f in dict.fromkeys(factors) if self.key(f) not in self.seen]
        if todo:
            stacks = [stack_params(self.tp, self.zeta, self.alphas, [m * x for m, x in zip(self.mus, f)],
                                   [m * x for m, x in zip(self.muks, f)]) for f in todo]
            singles = [single_params(self.tp, self.zeta, self.alphas, self.mus[0] * f[0], self.muks[0] * f[0])
                       for f in todo]
            rows = self.run.run(stacks + singles)
            for i, f in enumerate(todo):
                st, si = rows[i], rows[len(todo) + i]
                self.seen[self.key(f)] = {
                    "factors": list(f), "stack": np.array([r["peakUp"] for r in st]),
                    "single": np.array([r["peakUp"] for r in si]),
                    "slips": np.array([[r[f"peakSlip[{j}]"] for j in range(1, self.n + 1)] for r in st])}
            now = time.perf_counter()
            if self.progress and now - self.shown > 2.0:
                self.shown = now
                print(f"  friction box: {len(self.seen)} points x {len(self.run.records)} records so far, "
                      f"{self.run.runs} runs, {now - self.started:.0f} s", flush=True)
        return [self.seen[self.key(f)] for f in factors]

    def objectives(self, P: np.ndarray) -> dict:
        pts = self.points([tuple(p) for p in P])
        out = {"stack_drift": np.array([-np.mean(p["stack"]) for p in pts]),
               "single_ratio": np.array([np.mean(p["single"]) / np.mean(p["stack"]) for p in pts])}
        if self.allow:
            out["slip"] = np.array([-np.max(p["slips"] / np.array(self.allow)) for p in pts])
        return out

    def rigid_mean(self, fraction: float) -> float:
        return float(np.mean(self.run.drifts(rigid_params(self.tp, self.zeta, self.alphas, fraction))))


def search_box(scene: Scene, uncertainty: float, budget: int, objectives: list[str]) -> dict:
    n = scene.n
    if uncertainty == 0.0:
        p = scene.points([(1.0,) * n])[0]
        vals = scene.objectives(np.ones((1, n)))
        return {"objectives": {o: {"value": float(vals[o][0]), "point": [1.0] * n, "margin": 0.0,
                                   "bound": float(vals[o][0])} for o in objectives},
                "grid_per_axis": 1, "grid_step": 0.0, "final_step": 0.0, "evaluations": 1,
                "guarantee": "no friction uncertainty: the nominal friction only", "_p": p}
    return box_search.search(scene.objectives, n, 1.0 - uncertainty, 1.0 + uncertainty, objectives,
                             nominal=[1.0] * n, budget=budget)


def advise(records: list[Path], tp: float, zeta: float, alphas: list[float], mus: list[float],
           muks: list[float], cost_tol: float = 0.25, unconservative_tol: float = 0.0,
           mu_uncertainty: float = 0.3, mu_points: int = 5, max_slip: list[float] | None = None,
           scale: float = 1.0, occupancy: str = "storage", imposed_load: float | None = None,
           budget: int = box_search.BUDGET, progress: bool = False) -> dict:
    n = len(alphas)
    run = Runner(records, scale)
    names = [Path(r).stem for r in records]
    allow = None if not max_slip else (list(max_slip) * n if len(max_slip) == 1 else list(max_slip))
    scene = Scene(run, tp, zeta, alphas, mus, muks, allow, progress)
    started = time.perf_counter()

    objectives = ["stack_drift", "single_ratio"] + (["slip"] if allow else [])
    box = search_box(scene, mu_uncertainty, budget, objectives)
    named = sweep_factors(n, mu_uncertainty, mu_points)
    scene.points(named)
    nominal = scene.points([(1.0,) * n])[0]
    drifts = {"stack": nominal["stack"], "single": nominal["single"],
              "rigid": run.drifts(rigid_params(tp, zeta, alphas)),
              "bare": run.drifts(rigid_params(tp, zeta, alphas, 0.0))}
    for name, d in zip(names, nominal["stack"]):
        if not d > 0.0:
            raise ValueError(f"record {name}: the stack's peak drift is {d}: an empty record? Every record must "
                             "move the structure")
    u = {k: float(np.mean(v)) for k, v in drifts.items()}
    ob = box["objectives"]
    top = ob["stack_drift"]  # the box point where the stack drifts most: the linear models' worst
    u_max, u_max_margin = -top["value"], top["margin"]
    worst_drift_point = scene.points([tuple(top["point"])])[0]

    models = {}
    for m in SIMPLER:
        ratio = u[m] / u["stack"]
        per_record = drifts[m] / drifts["stack"]
        if m == "single":
            worst, bound, margin = ob["single_ratio"]["value"], ob["single_ratio"]["bound"], ob["single_ratio"]["margin"]
            at = scene.points([tuple(ob["single_ratio"]["point"])])[0]
            worst_records = at["single"] / at["stack"]
        else:
            at = worst_drift_point
            worst, bound = u[m] / u_max, u[m] / (u_max + u_max_margin)
            margin = worst - bound
            worst_records = drifts[m] / at["stack"]
        below, below_w = per_record < 1.0 - FLOOR, worst_records < 1.0 - FLOOR
        named_ratios = [float(np.mean(p[m] if m == "single" else drifts[m]) / np.mean(p["stack"]))
                        for p in scene.points(named)]
        accepted, why = judge(ratio, worst, at["factors"], cost_tol, unconservative_tol, mu_uncertainty, margin)
        models[m] = {
            "mean_peak_drift": u[m], "ratio_to_stack": ratio, "direction": direction(ratio),
            "per_record": {"ratios": per_record.tolist(), **spread(per_record),
                           "unconservative_records": int(np.sum(below)),
                           "largest_shortfall": float(max(0.0, 1.0 - np.min(per_record)))},
            "friction_sweep": {"worst_ratio": worst, "worst_at_factors": at["factors"], "search_margin": margin,
                               "worst_bound": bound, "named_points": [list(f) for f in named],
                               "ratios": named_ratios},
            "at_worst_friction": {"factors": at["factors"], "ratios": worst_records.tolist(), **spread(worst_records),
                                  "unconservative_records": int(np.sum(below_w)),
                                  "largest_shortfall": float(max(0.0, 1.0 - np.min(worst_records)))},
            "accepted": accepted, "reason": why,
        }
    linear = [m for m in LINEAR if models[m]["accepted"]]
    if linear:
        model_verdict = min(linear, key=lambda m: (abs(models[m]["ratio_to_stack"] - 1.0), m != "rigid"))
    elif models["single"]["accepted"]:
        model_verdict = "single"
    else:
        model_verdict = "stack"

    # The effective seismic-mass fraction: nominal mean, per record, over the box.
    run.run([rigid_params(tp, zeta, alphas, f) for f in FRACTION_GRID])  # one batch for the grid
    frac = fraction_roots(scene.rigid_mean, u["stack"])
    per_rec = [fraction_roots(lambda f, rec=rec: run.peak(rec, rigid_params(tp, zeta, alphas, f))["peakUp"],
                              float(drifts["stack"][i])) for i, rec in enumerate(run.records)]
    values = np.array([r["fraction"] for r in per_rec])
    u_min = min(float(np.mean(p["stack"])) for p in scene.seen.values())
    f_low = fraction_roots(scene.rigid_mean, u_min)["fraction"]
    f_high = fraction_roots(scene.rigid_mean, u_max + u_max_margin)["fraction"]
    fraction = {
        "mean": frac["fraction"], "status": frac["status"], "roots": frac["roots"],
        "rigid_drift_increasing": frac["increasing"],
        "per_record": {"values": values.tolist(), **spread(values),
                       "below_zero": sum(r["status"] == "below" for r in per_rec),
                       "above_max": sum(r["status"] == "above" for r in per_rec)},
        # Lowest and highest over the friction box (the highest with the search's margin).
        "friction_sweep": {"min": min(f_low, frac["fraction"]), "max": max(f_high, frac["fraction"]),
                           "at_factors_of_max": top["point"],
                           "values": [fraction_roots(scene.rigid_mean, float(np.mean(p["stack"])))["fraction"]
                                      for p in scene.points(named)]},  # at the named points (friction_sweep)
        # With the rigid model's mean drift rising with the attached share, the box's
        # largest fraction is not unconservative anywhere in the box.
        "design_value": max(f_high, frac["fraction"]) if frac["increasing"] else None,
    }

    code_rows = code_comparison(scene, occupancy, imposed_load, u["stack"], u_max + u_max_margin, top["point"],
                                fraction)
    slips = slip_check(scene, box, nominal, names, allow)
    warnings = list(slips["warnings"])
    if not allow and any(b["max_over_friction_sweep"] > 0.0 for b in slips["blocks"]):
        warnings.append("sliding off not checked (no --max-slip): the blocks slide up to "
                        + ", ".join(f"{b['max_over_friction_sweep']:.3f} m (block {b['block']})"
                                    for b in slips["blocks"] if b["max_over_friction_sweep"] > 0.0)
                        + " on the body below over the friction box; give each block's edge distance as --max-slip")
    verdict = model_verdict
    sliding = None
    if slips["slides_off"]:
        sliding = sliding_off(scene, slips, u, u_max + u_max_margin, mu_uncertainty, names)
        verdict = "slides-off"
    chosen = models.get(model_verdict)
    if chosen and verdict != "slides-off":
        for where, x in (("at the nominal friction", chosen["per_record"]),
                         (f"at the worst friction (mu x {fmt_factors(chosen['at_worst_friction']['factors'])})",
                          chosen["at_worst_friction"])):
            if x["unconservative_records"]:
                warnings.append(
                    f"{model_verdict}: below the stack's peak drift on {x['unconservative_records']} of {len(records)} "
                    f"records {where} (by up to {100 * x['largest_shortfall']:.1f} %); the rule judges the mean over "
                    "the suite, as design codes do")
    if frac["status"] == "found" and len(frac["roots"]) > 1:
        warnings.append("the rigid model's mean drift is not monotonic in the attached fraction: several fractions "
                        f"give the stack's drift ({', '.join(f'{r:.3f}' for r in frac['roots'])}); the one nearest "
                        "the linear interpolation between bare and fully attached is reported")
    for c in code_rows:
        if c["unconservative"]:
            nominal_too = (f", {100 * c['shortfall_nominal']:.1f} % at the nominal friction"
                           if c["shortfall_nominal"] > 0 else "")
            warnings.append(f"{c['code']} ({c['clause']}) counts {100 * c['share']:.0f} % of the live load: "
                            f"unconservative for this scene by {100 * c['shortfall_worst']:.1f} % of the drift "
                            f"(worst friction){nominal_too}")
    box_out = {k: v for k, v in box.items() if k not in ("points", "values", "_p")}
    seen = list(scene.seen.values())
    return {
        "scene": {"Tp": tp, "zeta": zeta, "alphas": alphas, "mus": mus, "muks": muks, "blocks": n},
        "records": [str(r) for r in records], "record_scale": scale,
        "rule": {"cost_tolerance": cost_tol, "unconservative_tolerance": unconservative_tol,
                 "equal_below": FLOOR, "mu_uncertainty": mu_uncertainty, "mu_points": mu_points,
                 "text": "a simpler model is accepted if its mean peak drift is at most "
                         f"{100 * unconservative_tol:g} % below the stack's everywhere in the friction box (mu x "
                         f"1 -+ {mu_uncertainty:g}, each interface on its own) and at most {100 * cost_tol:g} % above "
                         "it at the nominal friction"},
        "mean_peak_drift": u, "DRR1": u["stack"] / u["rigid"], "DRR2": u["single"] / u["rigid"],
        "error_against_stack": {m: models[m]["ratio_to_stack"] - 1.0 for m in SIMPLER},
        "models": models, "verdict": verdict, "model_verdict": model_verdict, "advice": advice_text(
            verdict, model_verdict, sliding),
        "effective_mass_fraction": fraction, "codes": code_rows, "peak_slips": slips, "sliding_off": sliding,
        "friction_box": {**box_out, "uncertainty": mu_uncertainty, "points_evaluated": len(seen),
                         "stack_drift_max": u_max, "stack_drift_max_margin": u_max_margin,
                         "stack_drift_max_at": top["point"], "stack_drift_min": u_min,
                         "points": {"factors": [p["factors"] for p in seen],
                                    "u_stack": [float(np.mean(p["stack"])) for p in seen],
                                    "u_single": [float(np.mean(p["single"])) for p in seen],
                                    "max_peak_slips": [p["slips"].max(axis=0).tolist() for p in seen]}},
        "friction_sweep": [{"factors": p["factors"], "u_stack": float(np.mean(p["stack"])),
                            "u_single": float(np.mean(p["single"])), "max_peak_slips": p["slips"].max(axis=0).tolist()}
                           for p in scene.points(named)],
        "per_record": {"names": names, **{k: v.tolist() for k, v in drifts.items()},
                       "peak_slips": nominal["slips"].tolist()},
        "warnings": warnings, "runs": run.runs, "seconds": round(time.perf_counter() - started, 2),
    }


def judge(ratio: float, worst: float, where, cost_tol: float, unc_tol: float, uncertainty: float,
          margin: float = 0.0) -> tuple[bool, str]:
    """The rule for one simpler model, from its mean drift over the stack's at the
    nominal friction (`ratio`) and at its worst point of the friction box (`worst`,
    at factors `where`, with the search's `margin`): accepted if the worst minus the
    margin is never more than `unc_tol` below the stack and, at the nominal
    friction, at most `cost_tol` above it. Returns the decision and a message
    saying which way and by how much."""
    safe_found = worst >= 1.0 - unc_tol - FLOOR
    safe = worst - margin >= 1.0 - unc_tol - FLOOR
    cheap = ratio - 1.0 <= cost_tol + FLOOR
    text = f"{how(ratio)} at the nominal friction"
    if uncertainty:
        text += f"; worst over mu x (1 -+ {uncertainty:g}): {how(worst)} (mu factors {fmt_factors(where)})"
        if margin > FLOOR:
            text += f", search margin {100 * margin:.2f} %"
    if not safe_found:
        return False, f"rejected: {text}; allowed below the stack: {100 * unc_tol:g} %"
    if not safe:
        return False, (f"rejected: {text}; the search cannot rule out {100 * (1 - worst + margin):.2f} % below the "
                       f"stack (allowed: {100 * unc_tol:g} %)")
    if not cheap:
        return False, f"rejected: {text}; cost tolerance {100 * cost_tol:g} %"
    return True, f"accepted: {text}"


def fmt_factors(factors) -> str:
    return " ".join(f"{f:.3g}" for f in factors)


def code_comparison(scene: Scene, occupancy: str, imposed_load, u_nominal: float, u_worst: float, worst_at,
                    fraction: dict) -> list[dict]:
    """Each code's live-load share, rigidly attached, against the stack: its mean
    drift over the stack's at the nominal friction and at the box's worst (largest
    stack drift, with the search's margin), and the share against the effective
    fraction. A code is unconservative for the scene when its drift is below the
    stack's somewhere in the box."""
    rows = []
    for c in codes.shares(occupancy, imposed_load):
        u_c = scene.rigid_mean(c["share"])
        nom, worst = u_c / u_nominal, u_c / u_worst
        rows.append({**c, "occupancy": occupancy, "mean_peak_drift": u_c, "ratio_to_stack": nom,
                     "ratio_to_stack_worst": worst, "worst_at_factors": worst_at,
                     "shortfall_nominal": max(0.0, 1.0 - nom), "shortfall_worst": max(0.0, 1.0 - worst),
                     "unconservative": worst < 1.0 - FLOOR,
                     "share_minus_effective": (c["share"] - fraction["design_value"]
                                               if fraction["design_value"] is not None else None)})
    return rows


def slip_check(scene: Scene, box: dict, nominal: dict, names, allow) -> dict:
    """Peak slip of each block relative to the body below, per record, at the nominal
    friction and over the friction box, against the allowable displacement (the edge
    distance; one value for every block, or one per block)."""
    n = scene.n
    seen = list(scene.seen.values())
    margin = box["objectives"]["slip"]["margin"] if allow and "slip" in box["objectives"] else 0.0
    blocks, warnings = [], []
    for j in range(n):
        s = nominal["slips"][:, j]
        worst_point = max(seen, key=lambda p: p["slips"][:, j].max())
        w = worst_point["slips"][:, j]
        entry = {"block": j + 1, "mean": float(np.mean(s)), "max": float(np.max(s)),
                 "record_of_max": names[int(np.argmax(s))] if np.max(s) > 0 else None,
                 "max_over_friction_sweep": float(w.max()), "at_factors": worst_point["factors"],
                 "record_of_max_over_sweep": names[int(np.argmax(w))] if w.max() > 0 else None}
        if allow:
            a = allow[j]
            entry.update({"allowable": a, "records_beyond": int(np.sum(s > a)),
                          "records_beyond_at_worst": int(np.sum(w > a)),
                          "beyond_by": float(max(0.0, w.max() - a)),
                          "search_margin": margin * a,
                          "may_slide_off": bool(w.max() <= a < w.max() + margin * a)})
            entry["slides_off"] = bool(entry["records_beyond"] or entry["records_beyond_at_worst"]
                                       or entry["may_slide_off"])
            if entry["slides_off"]:
                where = (f"on {entry['records_beyond']} of {len(s)} records at the nominal friction"
                         if entry["records_beyond"] else "at no record at the nominal friction")
                warnings.append(
                    f"block {j + 1} slides off: peak slip on the body below up to {w.max():.3f} m "
                    f"({entry['record_of_max_over_sweep']}, mu x {fmt_factors(worst_point['factors'])}) against the "
                    f"allowable {a:g} m, beyond it on {entry['records_beyond_at_worst']} of {len(s)} records there, "
                    f"{where}" + (" (within the search's margin)" if entry["may_slide_off"] else ""))
        blocks.append(entry)
    return {"allowable": allow, "blocks": blocks, "slides_off": any(b.get("slides_off") for b in blocks),
            "warnings": warnings}


def sliding_off(scene: Scene, slips: dict, u: dict, u_stack_worst: float, uncertainty: float, names) -> dict:
    """What happens when blocks slide off: the lowest block that does takes every block
    above it with it; the structure then carries the blocks below it only. Its drift
    is computed by runs of that reduced stack (the bare structure if block 1 goes),
    over the same friction box. Design for the envelope of the stack with its blocks
    on and the reduced stack."""
    off = [b for b in slips["blocks"] if b.get("slides_off")]
    lowest = off[0]["block"]
    keep = lowest - 1
    tp, zeta = scene.tp, scene.zeta
    if keep == 0:
        d = scene.run.drifts(rigid_params(tp, zeta, scene.alphas, 0.0))
        u_nom, u_worst, margin, at = float(np.mean(d)), float(np.mean(d)), 0.0, []
        per_record = d
    else:
        reduced = Scene(scene.run, tp, zeta, scene.alphas[:keep], scene.mus[:keep], scene.muks[:keep])
        box = search_box(reduced, uncertainty, REDUCED_BUDGET, ["stack_drift"])
        o = box["objectives"]["stack_drift"]
        per_record = reduced.points([(1.0,) * keep])[0]["stack"]
        u_nom, u_worst, margin, at = float(np.mean(per_record)), -o["value"], o["margin"], o["point"]
    edge = {b["block"]: b["max_over_friction_sweep"] + b.get("search_margin", 0.0) for b in off}
    envelope = max(u_stack_worst, u_worst + margin)
    return {"blocks": [{k: b[k] for k in ("block", "allowable", "records_beyond", "records_beyond_at_worst",
                                          "max_over_friction_sweep", "beyond_by", "at_factors")} for b in off],
            "lost_blocks": list(range(lowest, scene.n + 1)), "blocks_left": keep,
            "edge_distance_needed": edge,
            "reduced": {"mean_peak_drift": u_nom, "worst_over_box": u_worst, "search_margin": margin,
                        "worst_at_factors": at, "per_record": dict(zip(names, np.asarray(per_record).tolist())),
                        "ratio_to_stack": u_nom / u["stack"]},
            "design_drift": envelope, "stack_drift_worst": u_stack_worst}


def advice_text(verdict: str, model_verdict: str, sliding: dict | None) -> str:
    if verdict != "slides-off":
        return WORDS[verdict]
    b = sliding["blocks"][0]
    lost = sliding["lost_blocks"]
    lost_words = f"block {lost[0]}" if len(lost) == 1 else f"blocks {lost[0]}-{lost[-1]}"
    red = sliding["reduced"]
    others = "".join(f"; block {x['block']} too, on {x['records_beyond_at_worst']} records at the worst friction"
                     for x in sliding["blocks"][1:])
    return (f"block {b['block']} slides off its support (beyond the allowable {b['allowable']:g} m on "
            f"{b['records_beyond']} records at the nominal friction, {b['records_beyond_at_worst']} at the worst, "
            f"by up to {b['beyond_by']:.3f} m{others}). Either restrain it, or give it more edge distance ("
            + ", ".join(f"block {j}: at least {d:.3f} m" for j, d in sliding["edge_distance_needed"].items())
            + f"; then: {model_verdict} — {WORDS[model_verdict]}), "
            f"or design for the loss of {lost_words}: the structure then drifts {red['mean_peak_drift']:.4g} m "
            f"(mean; {red['worst_over_box']:.4g} m at the worst friction), {versus(red['ratio_to_stack'])} "
            f"the stack's drift with it on; design for the envelope, {sliding['design_drift']:.4g} m")


def suite_check(zone: str, quick: bool, tp: float, alphas: list[float]) -> dict:
    """ASCE 7-16 16.2: the suite's mean spectrum over 0.2 x the shortest period in play
    (the bare structure, Tp) to 2 x the longest (the loaded structure, Tp sqrt(1 +
    sum alpha)), from the spectra stored with the matched suite."""
    folder = study.suite(zone, quick)[0].parent
    spec = json.loads((folder / "suite.json").read_text())["spectrum"]
    t_loaded = tp * math.sqrt(1.0 + sum(alphas))
    c = ground_motions.check(spec["periods_s"], spec["mean_psa_g"], spec["target_psa_g"],
                             (0.2 * tp, 2.0 * t_loaded))
    return {**c, "periods_in_play_s": [tp, t_loaded],
            "rule": "ASCE 7-16 16.2.1 and 16.2.3.3: mean of the matched spectra >= 90 % of the target from 0.2 x "
                    "the shortest to 2 x the longest period in play (here the bare and the loaded structure)"}


def print_report(r: dict, suite_name: str):
    s = r["scene"]
    print(f"Scene: Tp {s['Tp']:g} s, zeta {s['zeta']:g}; {s['blocks']} block(s), bottom first: alpha "
          f"{' '.join(f'{a:g}' for a in s['alphas'])}, mus {' '.join(f'{m:g}' for m in s['mus'])}, "
          f"muk {' '.join(f'{m:g}' for m in s['muks'])}")
    print(f"Suite: {suite_name}; {len(r['records'])} records")
    if r.get("suite_check"):
        c = r["suite_check"]
        print(f"Suite check ({c['rule']}): {c['range_s'][0]:.3g}-{c['range_s'][1]:.3g} s, lowest mean/target "
              f"{c['min_mean_over_target']:.3f} at {c['at_period_s']:.2f} s: {'PASS' if c['passed'] else 'FAIL'}")
    b = r["friction_box"]
    print(f"Friction box: every mu x (1 -+ {b['uncertainty']:g}), each interface on its own: {b['points_evaluated']} "
          f"points ({b['grid_per_axis']} per axis on the grid, then refined); {r['runs']} runs in {r['seconds']:.1f} s")
    u = r["mean_peak_drift"]
    print(f"Mean peak drift of the stack: {u['stack']:.5g} m at the nominal friction, up to "
          f"{b['stack_drift_max']:.5g} m at mu x ({fmt_factors(b['stack_drift_max_at'])}) "
          f"(DRR1 {r['DRR1']:.3f}, DRR2 {r['DRR2']:.3f})")
    n = len(r["records"])
    print(f"{'model':7s} {'drift / stack':>13s}  records: {'min':>5s} {'p50':>5s} {'max':>5s} {'below':>6s}  "
          f"{'worst':>6s} {'below':>6s}  verdict")
    for m in SIMPLER:
        x = r["models"][m]
        pr, sw, aw = x["per_record"], x["friction_sweep"], x["at_worst_friction"]
        print(f"{m:7s} {x['ratio_to_stack']:13.3f}  {'':8s} {pr['min']:5.2f} {pr['p50']:5.2f} {pr['max']:5.2f} "
              f"{pr['unconservative_records']:>2d}/{n:<3d}  {sw['worst_ratio']:6.3f} {aw['unconservative_records']:>2d}/{n:<3d}"
              f"  {x['reason']}")
    if r["verdict"] == "slides-off":
        print(f"Advice: SLIDES OFF — {r['advice']}.")
    else:
        print(f"Advice ({r['rule']['text']}): {r['verdict']} — {r['advice']}.")
    f = r["effective_mass_fraction"]
    pr, sw = f["per_record"], f["friction_sweep"]
    status = {"found": "", "below": " (the stack drifts less than the bare structure: 0 is conservative)",
              "above": f" (the stack drifts more than with {FRACTION_MAX:g} x the load attached)"}[f["status"]]
    print(f"Effective seismic-mass fraction: {f['mean']:.3f} of the live load{status}; records: min {pr['min']:.2f}, "
          f"p10 {pr['p10']:.2f}, median {pr['p50']:.2f}, p90 {pr['p90']:.2f}, max {pr['max']:.2f}; over the "
          f"friction box {sw['min']:.3f}-{sw['max']:.3f}"
          + (f"; design value {f['design_value']:.3f}" if f["design_value"] is not None else ""))
    print("The codes (live-load share counted as seismic mass; clauses and factors must be checked by the engineer):")
    for c in r["codes"]:
        verdict = (f"UNCONSERVATIVE by {100 * c['shortfall_worst']:.1f} % of the drift at the worst friction"
                   if c["unconservative"] else f"conservative ({how(c['ratio_to_stack_worst'])} at the worst friction)")
        print(f"  {c['code']:22s} {100 * c['share']:5.1f} %  ({c['clause']}; {c['factors']})"
              f"{'' if c['confirmed'] else ' [unconfirmed]'}: drift / stack {c['ratio_to_stack']:.3f}, {verdict}")
    for bl in r["peak_slips"]["blocks"]:
        allow = f" (allowable {bl['allowable']:g} m)" if "allowable" in bl else ""
        where = f" ({bl['record_of_max']})" if bl["record_of_max"] else ""
        print(f"Block {bl['block']}: peak slip on the body below mean {bl['mean']:.4f} m, max {bl['max']:.4f} m{where}, "
              f"{bl['max_over_friction_sweep']:.4f} m over the friction box{allow}")
    for w in r["warnings"]:
        print(f"WARNING: {w}")


def plot(r: dict, path: Path, title: str):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rule = r["rule"]
    fig, axes = plt.subplots(2, 2, figsize=(13, 9))
    ax = axes[0, 0]
    names = r["per_record"]["names"]
    for k, m in enumerate(SIMPLER):
        x = r["models"][m]
        ratios = x["per_record"]["ratios"]
        jitter = np.linspace(-0.2, 0.2, len(ratios))
        ax.scatter(k + jitter, ratios, s=14, color=f"C{k}", label="nominal friction" if k == 0 else None)
        ax.scatter(k + jitter, x["at_worst_friction"]["ratios"], s=16, facecolors="none", edgecolors=f"C{k}",
                   label="its worst friction" if k == 0 else None)
        ax.plot([k - 0.3, k + 0.3], [x["ratio_to_stack"]] * 2, color="k", lw=2)
        ax.plot([k - 0.3, k + 0.3], [x["friction_sweep"]["worst_ratio"]] * 2, color="k", lw=1, ls="--")
    ax.axhspan(1 - rule["unconservative_tolerance"], 1 + rule["cost_tolerance"], color="tab:green", alpha=0.12,
               label="accepted band (mean)")
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xticks(range(len(SIMPLER)), [f"{m}\n{'accepted' if r['models'][m]['accepted'] else 'rejected'}"
                                        for m in SIMPLER])
    ax.set_ylabel("peak drift / stack's, per record")
    ax.set_title(f"per record (bars: means; dashed: at the worst friction); advice: {r['verdict']}"
                 + (f" (else {r['model_verdict']})" if r["verdict"] == "slides-off" else ""), fontsize=10)
    ax.legend(fontsize=7)
    ax = axes[0, 1]
    box = r["friction_box"]["points"]
    us = np.array(box["u_stack"])
    for k, m in enumerate(SIMPLER):
        if m == "single":
            y = np.array(box["u_single"]) / us
        else:
            y = r["models"][m]["mean_peak_drift"] / us
        ax.plot(np.arange(len(us)), np.sort(y), color=f"C{k}", label=f"{m}: worst {r['models'][m]['friction_sweep']['worst_ratio']:.3f}")
    ax.axhspan(1 - rule["unconservative_tolerance"], 1 + rule["cost_tolerance"], color="tab:green", alpha=0.12)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel(f"{len(us)} points of the friction box, each model's ratios sorted")
    ax.set_ylabel("mean drift / stack's")
    ax.set_title(f"friction box: every mu x (1 -+ {rule['mu_uncertainty']:g}), each interface on its own", fontsize=10)
    ax.legend(fontsize=8)
    ax = axes[1, 0]
    f = r["effective_mass_fraction"]
    ax.hist(f["per_record"]["values"], bins=10, color="0.75", label="per record (nominal friction)")
    ax.axvline(f["mean"], color="tab:red", lw=2, label=f"effective fraction: {f['mean']:.3f}")
    ax.axvspan(f["friction_sweep"]["min"], f["friction_sweep"]["max"], color="tab:red", alpha=0.15,
               label=f"over the friction box: {f['friction_sweep']['min']:.2f}-{f['friction_sweep']['max']:.2f}")
    for k, c in enumerate(r["codes"]):
        ax.axvline(c["share"] + 0.004 * k, color=f"C{k + 3}", lw=2, ls="--",
                   label=f"{c['code']}: {100 * c['share']:.0f} %"
                         + (f", unconservative by {100 * c['shortfall_worst']:.1f} %" if c["unconservative"] else ""))
    ax.set_xlabel("share of the live load counted as seismic mass")
    ax.set_ylabel("records")
    ax.set_title(f"effective fraction and the codes' shares ({r['codes'][0]['occupancy']}; engineer to check the "
                 "clauses)", fontsize=10)
    ax.legend(fontsize=7)
    ax = axes[1, 1]
    slips = np.array(r["per_record"]["peak_slips"])
    for j in range(slips.shape[1]):
        ax.scatter(np.full(len(slips), j + 1) + np.linspace(-0.2, 0.2, len(slips)), slips[:, j], s=14, color=f"C{j}")
        b = r["peak_slips"]["blocks"][j]
        ax.scatter([j + 1], [b["max_over_friction_sweep"]], marker="^", s=40, color="k",
                   label="max over the friction box" if j == 0 else None)
        if "allowable" in b:
            ax.plot([j + 0.6, j + 1.4], [b["allowable"]] * 2, color="tab:red", lw=2,
                    label="allowable (edge distance)" if j == 0 else None)
    ax.set_xticks(range(1, slips.shape[1] + 1))
    ax.set_xlabel("block (bottom first)")
    ax.set_ylabel("peak slip on the body below (m)")
    t = "sliding-off check, per record at the nominal friction"
    if r.get("sliding_off"):
        s = r["sliding_off"]
        t = (f"SLIDES OFF: blocks {s['lost_blocks']} lost; drift then {s['reduced']['mean_peak_drift']:.3g} m "
             f"({versus(s['reduced']['ratio_to_stack'])} the stack's)")
    ax.set_title(t, fontsize=10)
    ax.legend(fontsize=7)
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
    ap.add_argument("--mu-points", type=int, default=5,
                    help="common friction factors listed in the report besides the box search (default 5)")
    ap.add_argument("--box-budget", type=int, default=box_search.BUDGET,
                    help=f"grid points of the friction box at most (default {box_search.BUDGET}; never fewer than 3 "
                         "per axis)")
    ap.add_argument("--max-slip", type=float, nargs="+",
                    help="allowable slip of a block on the body below (m), its edge distance: one value, or one "
                         "per block")
    ap.add_argument("--occupancy", choices=codes.OCCUPANCIES, default="storage",
                    help="for the codes' live-load shares (default storage)")
    ap.add_argument("--imposed-load", type=float,
                    help="design imposed floor load (kN/m2), for IS 1893's Table 10 (default by occupancy)")
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
        (args.box_budget >= 1, f"--box-budget {args.box_budget}: must be >= 1"),
        (not args.max_slip or (len(args.max_slip) in (1, n) and all(x > 0 for x in args.max_slip)),
         f"--max-slip {args.max_slip}: one value or one per block, each > 0 (m)"),
        (args.imposed_load is None or (math.isfinite(args.imposed_load) and args.imposed_load > 0),
         f"--imposed-load {args.imposed_load}: must be finite and > 0 (kN/m2)"),
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
    check = None
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
        check = suite_check(args.zone, False, args.Tp, args.alpha)
    r = advise(records, args.Tp, args.zeta, args.alpha, args.mu, muks, args.cost_tol, args.unconservative_tol,
               args.mu_uncertainty, args.mu_points, args.max_slip, scale, args.occupancy, args.imposed_load,
               args.box_budget, progress=True)
    r["suite"] = suite_name
    r["zone"], r["level"] = (None, None) if args.records else (args.zone, label)
    r["suite_check"] = check
    if check and not check["passed"]:
        r["warnings"].append(f"the suite's mean spectrum is {check['min_mean_over_target']:.3f} of the target at "
                             f"{check['at_period_s']:.2f} s, below ASCE 7-16's 0.9 over the scene's periods "
                             f"{check['range_s'][0]:.3g}-{check['range_s'][1]:.3g} s"
                             + ("" if check["covered"] else " (beyond the periods the suite was matched over)"))
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
