"""The unit of work of the parametric study, shared by study.py (local process
pool or Dask workers) and advise.py: the three configurations of
../shared/MODEL.md for one record and one structure period.

- stack:  the N-block stack (nBlocks = N, alpha[j], mus[j] = muk[j] = mu_j);
- single: all blocks merged into one of mass sum(alpha) mp, interface-1 friction;
- rigid:  blocks rigidly attached, a linear SDOF of mass mp (1 + sum(alpha)) with the
          same k and c: run as nBlocks = 0 with mp, Tp and zeta of that SDOF (one
          degree of freedom, not a stack that never slips).

A worker process loads the FMU once (the first task) and calls fmi2Reset between
runs; each run covers the whole record in one fmi2DoStep.
"""

from __future__ import annotations

import math

MP = 1000.0  # kg; DRR does not depend on it
ZETA = 0.05


def model(fmu: str | None = None):
    """This process's loaded FMU (sll keeps it, so that it outlives a task
    function that Dask shipped by value)."""
    import sll

    return sll.shared_model(fmu)


def rigid_params(tp: float, alpha_total: float, zeta: float = ZETA) -> dict:
    """The bare SDOF equivalent to the structure with its blocks attached."""
    f = math.sqrt(1.0 + alpha_total)
    return {"nBlocks": 0, "mp": MP * (1.0 + alpha_total), "Tp": tp * f, "zeta": zeta / f}


def single_params(tp: float, alpha_total: float, mu1: float, zeta: float = ZETA) -> dict:
    return {"nBlocks": 1, "mp": MP, "Tp": tp, "zeta": zeta, "alpha[1]": alpha_total,
            "mus[1]": mu1, "muk[1]": mu1}


def stack_params(tp: float, alphas, mus, zeta: float = ZETA) -> dict:
    p = {"nBlocks": len(alphas), "mp": MP, "Tp": tp, "zeta": zeta}
    for j, (a, mu) in enumerate(zip(alphas, mus), 1):
        p.update({f"alpha[{j}]": a, f"mus[{j}]": mu, f"muk[{j}]": mu})
    return p


def peaks(record: str, params: dict, fmu: str | None = None) -> dict:
    r = model(fmu).run(record, params)
    n = int(params["nBlocks"])
    p = r["peaks"]
    return {"peakUp": p["peakUp"], "nEvents": p["nEvents"],
            **{f"peakSlip{j}": p[f"peakSlip[{j}]"] for j in range(1, n + 1)}}


def run_task(task: dict) -> list[dict]:
    """All configurations of the study grid for one (zone, record, Tp).

    task: zone, record (path), Tp, alpha (values for alpha1 and alpha2), mu1, mu2
    (lists), fmu (path or None), scripts (this folder; unused: workers import
    the installed sll package, pyproject.toml), optional scale (factor on the record: the intensity
    level, study.py --level / --scale). Rows: zone, record, Tp, alpha1, alpha2, mu1, mu2,
    configuration and peaks; single and rigid rows carry alpha1 = alpha1 + alpha2
    of the stacks they stand for, alpha2 = 0, and blank frictions they do not use.
    Every run of the task goes to the library in one call (`Model.run_batch`)."""
    zone, record, tp, fmu = task["zone"], task["record"], task["Tp"], task.get("fmu")
    name = record.rsplit("/", 1)[-1].rsplit(".", 1)[0]
    key = {"zone": zone, "record": name, "Tp": tp}
    rows, params = [], []
    totals = sorted({round(a1 + a2, 12) for a1 in task["alpha"] for a2 in task["alpha"]})
    for a in totals:
        rows.append({**key, "alpha1": a, "alpha2": 0.0, "mu1": "", "mu2": "", "configuration": "rigid"})
        params.append(rigid_params(tp, a))
        for mu1 in task["mu1"]:
            rows.append({**key, "alpha1": a, "alpha2": 0.0, "mu1": mu1, "mu2": "",
                         "configuration": "single"})
            params.append(single_params(tp, a, mu1))
    for a1 in task["alpha"]:
        for a2 in task["alpha"]:
            for mu1 in task["mu1"]:
                for mu2 in task["mu2"]:
                    rows.append({**key, "alpha1": a1, "alpha2": a2, "mu1": mu1, "mu2": mu2,
                                 "configuration": "stack"})
                    params.append(stack_params(tp, [a1, a2], [mu1, mu2]))
    results = model(fmu).run_batch(record, params, scale=task.get("scale", 1.0))
    for row, p, r in zip(rows, params, results):
        n = int(p["nBlocks"])
        row.update({"peakUp": r["peakUp"], "nEvents": r["nEvents"],
                    **{f"peakSlip{j}": r[f"peakSlip[{j}]"] for j in range(1, n + 1)}})
    return rows
