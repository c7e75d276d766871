"""Couples instances of the FMU as a shear building, one instance per storey,
and solves the same building exactly when it is linear (docs/coupling.md).

    from sll.coupling import Building, exact_building
    storeys = [{"nBlocks": 0, "Tp": 0.4},                  # FMU parameters, bottom up
               {"nBlocks": 1, "Tp": 0.3, "mus[1]": 9, "muk[1]": 9}]
    with Building(2) as b:
        run = b.couple(storeys, (t, ag), H=0.01, master="jacobi", extrapolation="derivative")
    exact = exact_building(storeys, (t, ag), run["time"])  # exact["never_slips"]: it applies
    run["up"][i], exact["up"][i]            # drift of storey i+1 (relative to the floor below)

Ports. Storey i (1 = bottom) is one FMU instance; its structure is floor i.
- storey 1's support is the ground: the record goes in through `recordFile`
  (exact between samples), its input `ag` stays 0;
- storey i > 1: `ag` <- `apAbs` of storey i-1 (the absolute acceleration of
  the floor it stands on);
- storey i < n: `Fext` <- +`baseShear` of storey i+1 (the force the upper
  storey's spring and damper put on floor i); the roof's `Fext` stays 0.
`up` of a storey is its inter-storey drift; `baseShear` depends on the state
only, `apAbs` on `Fext` at the same instant, so at a communication point the
master reads every `baseShear`, sets every `Fext`, then reads every `apAbs`
and sets every `ag`: consistent values with no iteration.

Masters (the macro step H is the communication step):
- "jacobi": every storey steps from the values at t;
- "gauss-seidel": bottom up; storey i steps after storey i-1 has reached
  t + H and takes its `ag` from that step (the newest value held with
  extrapolation "hold", otherwise the chord between t and t + H).
Extrapolation of the inputs over the step (given to the FMU by
fmi2SetRealInputDerivatives, order 1):
- "hold": zero order;
- "history": the slope through the last two communication points;
- "derivative": the slope from fmi2GetRealOutputDerivatives at t.
`event_aware=True` reads each storey's `tSwitch` after a step; when a
stick/slip switch fell inside, every storey is restored to its state at t
(fmi2SetFMUstate) and the step is redone to just past the earliest switch,
so the next extrapolation starts from the values after the switch.
The masters themselves are sll.cosim's (CoSimulation over FMUPartner
instances): this module names the storeys' links and adds the exact reference.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np
from scipy.linalg import expm

from sll import Model, fmu_path, read_record

MASTERS = ("jacobi", "gauss-seidel")
EXTRAPOLATIONS = ("hold", "history", "derivative")


# ---------------------------------------------------------------- records

def broadband_record(seed: int, duration: float = 8.0, dt: float = 0.005, pga: float = 3.0):
    """A seeded broadband ground acceleration (m/s2): white noise band-passed
    to 0.3-15 Hz, under a build-up / strong / decay envelope, scaled to `pga`,
    starting and ending at 0. Returns (t, ag)."""
    rng = np.random.default_rng(seed)
    n = int(round(duration / dt)) + 1
    t = np.arange(n) * dt
    spectrum = np.fft.rfft(rng.standard_normal(n))
    f = np.fft.rfftfreq(n, dt)
    spectrum[(f < 0.3) | (f > 15.0)] = 0.0
    a = np.fft.irfft(spectrum, n)
    envelope = np.minimum(1.0, t / (0.15 * duration)) * np.minimum(1.0, (duration - t) / (0.3 * duration))
    a *= np.clip(envelope, 0.0, 1.0)
    return t, a * pga / np.max(np.abs(a))


def load_record(record, g: float = 9.81) -> tuple[np.ndarray, np.ndarray]:
    """(t, ag in m/s2) from a pair of arrays or a record file (sll.read_record:
    PEER .AT2 in g, CSV time,accel in m/s2)."""
    if isinstance(record, (str, Path)):
        return read_record(record, g)
    t, ag = (np.asarray(v, float) for v in record)
    return t, ag


def write_record_csv(t: np.ndarray, ag: np.ndarray, path: Path) -> Path:
    """The record as the FMU's `recordFile` CSV (time, m/s2), to the last bit."""
    np.savetxt(path, np.c_[t, ag], delimiter=",", header="time,accel", comments="", fmt="%.17g")
    return path


# -------------------------------------------------------- exact reference

def check_storeys(storeys: list[dict]) -> None:
    """The building's record is the ground motion of every storey: a storey's
    own recordFile or recordScale would drive it differently from the exact
    reference, so they are refused (scale the record instead)."""
    for i, p in enumerate(storeys, 1):
        own = sorted({"recordFile", "recordScale"} & set(p))
        if own:
            raise ValueError(f"storey {i}: {', '.join(own)} cannot be set per storey: the "
                             "building's record drives the ground (scale the record itself)")


def storey_constants(params: dict, defaults: dict) -> dict:
    """Mass (structure plus every block, rigidly attached), stiffness and
    damping of one storey, from its FMU parameters and the FMU's defaults."""
    p = {**defaults, **params}
    n_blocks = int(p["nBlocks"])
    alphas = [float(p[f"alpha[{j}]"]) for j in range(1, n_blocks + 1)]
    mp, tp, zeta = float(p["mp"]), float(p["Tp"]), float(p["zeta"])
    k = mp * (2 * math.pi / tp) ** 2
    mus = [float(p[f"mus[{j}]"]) for j in range(1, n_blocks + 1)]
    return {"m": mp * (1 + sum(alphas)), "k": k, "c": 2 * zeta * math.sqrt(k * mp),
            "nBlocks": n_blocks, "mus_min": min(mus) if mus else math.inf, "g": float(p["g"])}


def fmu_defaults(model: Model) -> dict:
    names = ["nBlocks", "mp", "Tp", "zeta", "g"] + [f"{q}[{j}]" for q in ("alpha", "mus", "muk")
                                                     for j in range(1, 9)]
    return {n: model.vars[n].start for n in names}


def shear_building(constants: list[dict]):
    """M, C, K of the shear building in floor displacements relative to the
    ground (floor i is storey i's structure)."""
    n = len(constants)
    m = np.diag([s["m"] for s in constants])
    k, c = np.zeros((n, n)), np.zeros((n, n))
    for i, s in enumerate(constants):  # storey i joins floor i-1 (ground for i = 0) and floor i
        for mat, val in ((k, s["k"]), (c, s["c"])):
            mat[i, i] += val
            if i > 0:
                mat[i - 1, i - 1] += val
                mat[i, i - 1] -= val
                mat[i - 1, i] -= val
    return m, c, k


def exact_building(storeys: list[dict], record, times, defaults: dict | None = None) -> dict:
    """The linear shear building M x'' + C x' + K x = -M 1 ag solved exactly:
    over each linear piece of ag (record samples and output times) the first
    order system, augmented with the piece's ag and slope, is advanced by its
    matrix exponential. Blocks count as rigidly attached; `never_slips` says
    whether that holds (every floor's absolute acceleration stays within
    min mus g of the blocks on it, checked at the piece ends).
    Returns up[i] (drift of storey i+1), x[i] (floor displacement), apAbs[i]."""
    if defaults is None:
        with Model() as probe:
            defaults = fmu_defaults(probe)
    check_storeys(storeys)
    t_rec, a_rec = load_record(record)
    times = np.asarray(times, float)
    consts = [storey_constants(p, defaults) for p in storeys]
    m, c, k = shear_building(consts)
    n = len(consts)
    minv = np.linalg.inv(m)
    size = 2 * n + 2  # x, v, ag, slope
    f = np.zeros((size, size))
    f[:n, n:2 * n] = np.eye(n)
    f[n:2 * n, :n] = -minv @ k
    f[n:2 * n, n:2 * n] = -minv @ c
    f[n:2 * n, 2 * n] = -1.0
    f[2 * n, 2 * n + 1] = 1.0
    grid = np.union1d(times, t_rec[(t_rec > times[0]) & (t_rec < times[-1])])
    grid = grid[np.concatenate(([True], np.diff(grid) > 1e-12))]
    segment = np.clip(np.searchsorted(t_rec, grid, "right") - 1, 0, len(t_rec) - 2)
    inside = (grid >= t_rec[0]) & (grid < t_rec[-1])
    slopes = np.where(inside, np.diff(a_rec)[segment] / np.diff(t_rec)[segment], 0.0)
    values = np.where(inside | (grid == t_rec[-1]), np.interp(grid, t_rec, a_rec), 0.0)
    cache: dict = {}
    state = np.zeros(size)
    xs = np.zeros((len(grid), n))
    vs = np.zeros((len(grid), n))
    for i in range(len(grid) - 1):
        h = grid[i + 1] - grid[i]
        key = round(h, 13)
        if key not in cache:
            cache[key] = expm(f * h)
        state[2 * n], state[2 * n + 1] = values[i], slopes[i]
        state = cache[key] @ state
        xs[i + 1], vs[i + 1] = state[:n], state[n:2 * n]
    pick = np.searchsorted(grid, times - 1e-12)
    x, v = xs[pick].T, vs[pick].T
    ap_abs = -minv @ (c @ v + k @ x)
    up = x - np.vstack([np.zeros(len(times)), x[:-1]])
    slips = [s["nBlocks"] > 0 and np.max(np.abs(ap_abs[i])) > s["mus_min"] * s["g"]
             for i, s in enumerate(consts)]
    return {"time": times, "x": x, "up": up, "apAbs": ap_abs, "never_slips": not any(slips)}


# ---------------------------------------------------------------- masters

PEAKS = ["peakUp", "peakApAbs", "Einput", "Ekinetic", "Estrain", "Eviscous", "Efriction"]
EXTRAPOLATION_OF = {"hold": "constant", "history": "linear", "derivative": "derivative"}


class Building:
    """`n` loaded FMU instances (sll.cosim.FMUPartner, named storey1..storeyn),
    reused from run to run (fmi2Reset between); `couple` runs them with the
    masters of sll.cosim (one rule, one place: docs/stack-on-a-floor.md)."""

    def __init__(self, n: int, fmu: str | Path | None = None):
        from sll.cosim import FMUPartner

        path = Path(fmu) if fmu else fmu_path()
        self.models = [FMUPartner(f"storey{i + 1}", path) for i in range(n)]
        self.defaults = fmu_defaults(self.models[0])
        self.tmp = tempfile.TemporaryDirectory(prefix="sll_coupling_")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        for m in self.models:
            m.close()
        self.tmp.cleanup()

    def couple(self, storeys: list[dict], record, H: float, stop: float | None = None,
               master: str = "jacobi", extrapolation: str = "derivative",
               event_aware: bool = False, outputs: tuple[str, ...] = ("up",),
               consistent: bool = True, shear_sign: float = 1.0) -> dict:
        """Runs the coupled building over `record` ((t, ag in m/s2) or a record
        file) with macro step H up to `stop` (default: the record's end; the
        last step is shorter when H does not divide it). Returns time (every
        communication point, switch landings included), on_grid (which are
        not landings), each of `outputs` as an array per storey
        (run["up"][i]), the FMUs' peaks (peakUp, peakSlip[j]) per storey, and
        the cost: fmu_steps (fmi2DoStep calls over all storeys), rollbacks,
        seconds. `consistent=False` exchanges as a plain importer does
        (fmucontainer, for one): every output read right after the step,
        before any input is set. `shear_sign` is the gain of the link
        Fext <- baseShear (+1 is the physics; -1 only to show it diverges)."""
        from sll.cosim import CoSimulation, ConfigurationError

        if master not in MASTERS:
            raise ValueError(f"master = {master!r}: it must be one of {MASTERS}")
        if extrapolation not in EXTRAPOLATIONS:
            raise ValueError(f"extrapolation = {extrapolation!r}: it must be one of {EXTRAPOLATIONS}")
        if not 1 <= len(storeys) <= len(self.models):
            raise ValueError(f"{len(storeys)} storeys: this Building holds 1..{len(self.models)}")
        check_storeys(storeys)
        t_rec, a_rec = load_record(record)
        stop = float(t_rec[-1] if stop is None else stop)
        if not (math.isfinite(H) and 0 < H <= stop):
            raise ValueError(f"H = {H}: it must be > 0 and at most the stop time {stop}")
        csv = write_record_csv(t_rec, a_rec, Path(self.tmp.name) / "ground.csv")
        units = self.models[:len(storeys)]
        if event_aware and "tSwitch" not in units[0].vars:
            raise ValueError("event_aware needs the FMU's tSwitch output (issue 12, item 3)")
        for i, (u, p) in enumerate(zip(units, storeys)):
            u.parameters = {"recordFile": str(csv) if i == 0 else "", **p}
        links = []
        for i in range(1, len(units)):  # storey i+1 stands on floor i
            links.append((f"storey{i}.apAbs", f"storey{i + 1}.ag", 1.0, "m/s2"))
            links.append((f"storey{i + 1}.baseShear", f"storey{i}.Fext", shear_sign, "N"))
        sim = CoSimulation(units, links)
        for m in self.models:
            m.messages.clear()
        try:
            run = sim.run(stop, H, master=master, extrapolation=EXTRAPOLATION_OF[extrapolation],
                          consistent=consistent, event_aware=event_aware,
                          record=[f"{u.name}.{o}" for u in units for o in outputs])
        except ConfigurationError as e:  # a parameter the FMU refused: name the storey, quote the FMU
            raise ValueError(f"{self._storey(e)}: {self._said(e)}") from None
        except RuntimeError as e:
            raise RuntimeError(f"{self._storey(e)}: {self._said(e)}") from None
        result = {"time": run["time"], "on_grid": run["on_grid"], "rollbacks": run["rollbacks"],
                  "fmu_steps": sum(run["steps"].values()), "seconds": run["seconds"]}
        for o in outputs:
            result[o] = np.array([run[f"{u.name}.{o}"] for u in units])
        result["peaks"] = [self._peaks(u) for u in units]
        return result

    @staticmethod
    def _storey(error: Exception) -> str:
        name = str(error).split(":", 1)[0]
        return f"storey {name[len('storey'):]}" if name.startswith("storey") else "building"

    def _said(self, error: Exception) -> str:
        # fmpy's logger proxy is process-wide: a message may land in the list
        # of whichever instance registered last, so look in all of them.
        said = "; ".join(msg for m in self.models for msg in m.messages[-3:])
        text = str(error).split(":", 1)[-1].strip()
        return f"{text} ({said})" if said and said not in text else text

    @staticmethod
    def _peaks(u) -> dict:
        n_blocks = int(u.get("nBlocks"))
        names = PEAKS + [f"peakSlip[{j}]" for j in range(1, n_blocks + 1)]
        out = {n: u.get(n) for n in names}
        out.update({n: int(u.get(n)) for n in ("nEvents", "nAmbiguous")})
        return out


# ------------------------------------------------------------------ errors

def drift_error(run: dict, exact: dict) -> float:
    """Largest drift error over storeys and grid points, relative to the
    largest exact drift."""
    grid = run["on_grid"]
    ref = exact["up"][:, grid] if exact["up"].shape[1] == len(grid) else exact["up"]
    return float(np.max(np.abs(run["up"][:, grid] - ref)) / np.max(np.abs(ref)))


def observed_order(steps, errors) -> float:
    """Least-squares slope of log(error) against log(H)."""
    return float(np.polyfit(np.log(steps), np.log(errors), 1)[0])
