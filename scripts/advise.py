"""The scene advisor: which model of a stacked live load is enough for this structure?

    python scripts/advise.py --Tp 0.8 --alpha 0.25 0.25 --mu 0.1 0.05 [--zone V | --records DIR]
                             [--zeta 0.05] [--muk ...] [--tol 0.05] [--json FILE]

Runs the three configurations of ../shared/MODEL.md over every record of a suite —
the stack as given (1 to 8 blocks, bottom first), a single block of the total mass
with the bottom interface's friction, and the blocks rigidly attached — and
prints the mean peak drifts, DRR1 = u(stack) / u(rigid), DRR2 = u(single) / u(rigid),
the error each simpler model would make against the stack, and the simplest model
whose error is within --tol (default 5 %): rigid mass, single sliding block, or the
stack. Suites: --zone III or V (the paper's 11 records matched to IS 1893 hard
soil DBE; built on first use) or --records DIR (every .AT2 and .csv file in it,
used as they are).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import study  # noqa: E402
import study_tasks  # noqa: E402


def advise(records: list[Path], tp: float, zeta: float, alphas: list[float], mus: list[float],
           muks: list[float], tol: float) -> dict:
    a = sum(alphas)
    stack = study_tasks.stack_params(tp, alphas, mus, zeta)
    for j, mk in enumerate(muks, 1):
        stack[f"muk[{j}]"] = mk
    single = study_tasks.single_params(tp, a, mus[0], zeta)
    single["muk[1]"] = muks[0]
    rigid = study_tasks.rigid_params(tp, a, zeta)
    peaks = {name: [study_tasks.peaks(str(r), p)["peakUp"] for r in records]
             for name, p in (("stack", stack), ("single", single), ("rigid", rigid))}
    u = {k: float(np.mean(v)) for k, v in peaks.items()}
    drr1, drr2 = u["stack"] / u["rigid"], u["single"] / u["rigid"]
    err = {"rigid": u["rigid"] / u["stack"] - 1.0, "single": u["single"] / u["stack"] - 1.0}
    if abs(err["rigid"]) <= tol:
        verdict = "rigid"
    elif abs(err["single"]) <= tol:
        verdict = "single"
    else:
        verdict = "stack"
    return {"records": [str(r) for r in records], "mean_peak_drift": u, "DRR1": drr1, "DRR2": drr2,
            "error_against_stack": err, "tolerance": tol, "verdict": verdict,
            "per_record": {k: [float(x) for x in v] for k, v in peaks.items()}}


WORDS = {
    "rigid": "count the whole live load as mass rigidly attached to the structure",
    "single": "model the stack as one sliding block (total mass, bottom friction)",
    "stack": "model the stack: neither simpler model is within the tolerance",
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--Tp", type=float, required=True, help="period of the bare structure (s)")
    ap.add_argument("--zeta", type=float, default=0.05)
    ap.add_argument("--alpha", type=float, nargs="+", required=True, help="block masses / mp, bottom first")
    ap.add_argument("--mu", type=float, nargs="+", required=True, help="static friction of each interface")
    ap.add_argument("--muk", type=float, nargs="+", help="kinetic friction (default: = mu)")
    src = ap.add_mutually_exclusive_group()
    src.add_argument("--zone", choices=["III", "V"], default="V")
    src.add_argument("--records", type=Path, help="a folder of .AT2 / .csv records")
    ap.add_argument("--tol", type=float, default=0.05, help="acceptable error of a simpler model (fraction)")
    ap.add_argument("--json", type=Path, help="also write the result here")
    args = ap.parse_args(argv)
    muks = args.muk or args.mu
    if not (1 <= len(args.alpha) <= 8) or len(args.mu) != len(args.alpha) or len(muks) != len(args.alpha):
        ap.error("give one --alpha, --mu (and --muk) value per block, 1 to 8 blocks")
    if args.records:
        records = sorted(p for p in args.records.iterdir() if p.suffix.lower() in (".at2", ".csv"))
        if not records:
            ap.error(f"no .AT2 or .csv files in {args.records}")
        suite_name = str(args.records)
    else:
        records = study.suite(args.zone, quick=False)
        suite_name = f"Zone {args.zone} (11 records matched to IS 1893, hard soil, DBE)"
    r = advise(records, args.Tp, args.zeta, args.alpha, args.mu, muks, args.tol)
    u, e = r["mean_peak_drift"], r["error_against_stack"]
    print(f"Structure Tp {args.Tp:g} s, zeta {args.zeta:g}; stack alpha {args.alpha}, mus {args.mu}, "
          f"muk {muks}; suite {suite_name}")
    print(f"{'model':8s} {'mean peak drift (m)':>20s} {'DRR':>7s} {'error vs stack':>15s}")
    print(f"{'stack':8s} {u['stack']:20.5f} {r['DRR1']:7.3f} {'—':>15s}")
    print(f"{'single':8s} {u['single']:20.5f} {r['DRR2']:7.3f} {100 * e['single']:+14.1f}%")
    print(f"{'rigid':8s} {u['rigid']:20.5f} {1.0:7.3f} {100 * e['rigid']:+14.1f}%")
    print(f"Advice (tolerance {100 * args.tol:g} %): {r['verdict']} — {WORDS[r['verdict']]}.")
    if args.json:
        args.json.write_text(json.dumps(r, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
