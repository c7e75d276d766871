"""The single sliding block as a structural engineer would model it in OpenSees
(openseespy): the structure is a zeroLength spring + dashpot to the ground, the
block sits on it through a zeroLength element with an elastic-perfectly-plastic
material whose yield force is mu m1 g (../shared/RESEARCH.md §4). Sticking is
regularized by the elastic stiffness `k_stick`; there is one friction
coefficient (mus = muk). Newmark average acceleration with Newton iterations.
"""

from __future__ import annotations

import math
import time

import numpy as np


def available() -> str | None:
    """None if openseespy imports, else the reason it does not."""
    try:
        import openseespy.opensees  # noqa: F401
    except Exception as e:  # ImportError or openseespy's RuntimeError (missing BLAS)
        return f"{type(e).__name__}: {e}"
    return None


def run(accel: np.ndarray, record_dt: float, dt: float, mp: float, tp: float, zeta: float,
        alpha: float, mu: float, g: float, k_stick: float) -> dict:
    """Runs the scene under `accel` (m/s2, sampled every `record_dt`, linear in
    between) with analysis step `dt`. Returns the drift and slip histories at
    every analysis step, their peaks, the wall time of the analysis alone, and
    whether it converged to the end."""
    import openseespy.opensees as ops

    k = mp * (2 * math.pi / tp) ** 2
    c = 2 * zeta * math.sqrt(k * mp)
    m1 = alpha * mp
    f_slip = mu * m1 * g
    ops.wipe()
    ops.model("basic", "-ndm", 1, "-ndf", 1)
    ops.node(1, 0.0)
    ops.fix(1, 1)
    ops.node(2, 0.0, "-mass", mp)
    ops.node(3, 0.0, "-mass", m1)
    ops.uniaxialMaterial("Elastic", 1, k)
    ops.uniaxialMaterial("Viscous", 2, c, 1.0)
    ops.uniaxialMaterial("ElasticPP", 3, k_stick, f_slip / k_stick)
    ops.element("zeroLength", 1, 1, 2, "-mat", 1, 2, "-dir", 1, 1)
    ops.element("zeroLength", 2, 2, 3, "-mat", 3, "-dir", 1)
    ops.timeSeries("Path", 1, "-dt", record_dt, "-values", *map(float, accel))
    ops.pattern("UniformExcitation", 1, 1, "-accel", 1)
    ops.constraints("Plain")
    ops.numberer("Plain")
    ops.system("BandGeneral")
    ops.test("NormDispIncr", 1e-10, 50)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    n = int(round((len(accel) - 1) * record_dt / dt))
    drift = np.zeros(n + 1)
    slip = np.zeros(n + 1)
    converged = True
    started = time.perf_counter()
    for i in range(n):
        if ops.analyze(1, dt) != 0:
            converged = False
            break
        u2 = ops.nodeDisp(2, 1)
        drift[i + 1] = u2
        slip[i + 1] = ops.nodeDisp(3, 1) - u2
    seconds = time.perf_counter() - started
    ops.wipe()
    return {
        "time": np.arange(n + 1) * dt,
        "up": drift,
        "slip": slip,
        "peakUp": float(np.max(np.abs(drift))),
        "peakSlip": float(np.max(np.abs(slip))),
        "seconds": seconds,
        "converged": converged,
    }
