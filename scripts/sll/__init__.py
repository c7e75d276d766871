"""The library the command scripts and the tests share (scripts/sll/). This
module: build or find the FMU, load it once with fmpy, run a record through
it, read records. Beside it: seismic (spectra), coupling (FMUs coupled as a
shear building), building_container (the same as one fmucontainer FMU),
study_tasks (the study's unit of work, shipped to Dask workers) and
opensees_block (the OpenSees reference).

    from sll import Model
    with Model() as m:
        result = m.run(record="../shared/ground_motions/RSN6_IMPVALL.I_I-ELC180.AT2",
                       params={"alpha[1]": 0.3}, dt=0.01)
    result["peaks"]["peakUp"], result["time"], result["up"]
"""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
from fmpy.logging import addLoggerProxy
from ctypes import POINTER, byref, c_char_p, c_double, c_int, c_size_t, create_string_buffer

ROOT = Path(__file__).resolve().parents[2]
FMU_PATH = ROOT / "target" / "fmu" / "StackedLiveLoad.fmu"
DEFAULT_RECORD = "default_record.csv"  # in the FMU's resources folder
MAX_BLOCKS = 8


def build_fmu() -> Path:
    """Builds target/fmu/StackedLiveLoad.fmu (cargo, release) and returns its path."""
    subprocess.run(["bash", str(ROOT / "scripts" / "build_fmu.sh")], check=True,
                   stdout=subprocess.DEVNULL)
    return FMU_PATH


def fmu_path() -> Path:
    return FMU_PATH if FMU_PATH.exists() else build_fmu()


def read_record(path: str | Path, g: float = 9.81, dt: float | None = None,
                single_column_units: str = "g") -> tuple[np.ndarray, np.ndarray]:
    """(time, accel in m/s2) of a record, read by the same rules as the Rust reader:
    - PEER .AT2 (units of g): header line 4 gives NPTS and DT in either PEER form,
      the value count must equal NPTS, the first value is at t = 0;
    - CSV `time,accel` (m/s2), header line optional;
    - with `dt`: a single column, one value per line, sampled every `dt`, in units
      of g (or `single_column_units="m/s2"`)."""
    path = Path(path)
    text = path.read_bytes().decode("latin-1").replace("\r", " ")
    lines = text.split("\n")
    if dt is not None:
        factor = g if single_column_units == "g" else 1.0
        values = []
        for no, line in enumerate(lines, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            try:
                values.append(float(line))
            except ValueError:
                raise ValueError(f"{path}:{no}: expected one number per line, found `{line}`") from None
        if len(values) < 2:
            raise ValueError(f"{path}: a record needs at least two samples")
        return np.arange(len(values)) * dt, np.array(values) * factor
    if path.suffix.lower() == ".at2":
        header = lines[3] if len(lines) > 3 else ""
        m = re.search(r"NPTS\s*=\s*([0-9.]+)\s*,?\s*DT\s*=\s*([0-9.Ee+-]+)", header, re.I)
        if m:
            npts, dt = int(float(m.group(1))), float(m.group(2))
        else:
            nums = re.findall(r"[-+]?[0-9]*\.?[0-9]+(?:[Ee][-+]?[0-9]+)?", header)
            if len(nums) < 2:
                raise ValueError(f"{path}:4: expected NPTS and DT in header line 4")
            npts, dt = int(float(nums[0])), float(nums[1])
        values = np.array([float(x) for line in lines[4:] for x in line.split()])
        if len(values) != npts:
            raise ValueError(f"{path}: header line 4 says NPTS = {npts} but the file holds {len(values)} values")
        return np.arange(npts) * dt, values * g
    rows = []
    for no, line in enumerate(lines, 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = [f.strip() for f in line.split(",")]
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            if not rows and len(fields) == 2:
                continue  # header
            raise ValueError(f"{path}:{no}: expected two numbers `time,accel`, found `{line}`")
        if len(rows[-1]) != 2:
            raise ValueError(f"{path}:{no}: expected two numbers `time,accel`, found `{line}`")
    data = np.array(rows)
    return data[:, 0], data[:, 1]


_SHARED: dict = {}


def shared_model(fmu: str | Path | None = None) -> "Model":
    """One loaded FMU per process and FMU path, created on first use: what a
    worker of a process pool or a Dask cluster reuses from run to run."""
    key = str(fmu)
    if key not in _SHARED:
        import multiprocessing.util

        m = Model(fmu)
        # Pool workers leave through os._exit, which skips atexit: a finalizer
        # with a priority still runs and removes the extracted FMU.
        multiprocessing.util.Finalize(m, m.close, exitpriority=10)
        _SHARED[key] = m
    return _SHARED[key]


class Model:
    """The FMU, extracted and loaded once; `run` resets it between runs."""

    def __init__(self, fmu: str | Path | None = None, logger=None):
        self.fmu = Path(fmu) if fmu else fmu_path()
        self.md = read_model_description(str(self.fmu))
        self.unzipdir = extract(str(self.fmu), tempfile.mkdtemp(prefix="sll_fmu_"))
        self.vars = {v.name: v for v in self.md.modelVariables}
        self.messages: list[str] = []

        def log(component, instance, status, category, message):
            text = message.decode() if isinstance(message, bytes) else str(message)
            self.messages.append(text)
            if logger:
                logger(status, text)

        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName="sll")
        # fmpy's native proxy formats the variadic message ("%s", text) for us.
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(log)
        addLoggerProxy(byref(self.callbacks))
        self.slave.instantiate(callbacks=self.callbacks, loggingOn=False)
        self.fresh = True
        self._durations: dict = {}

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        try:
            self.slave.freeInstance()
        finally:
            shutil.rmtree(self.unzipdir, ignore_errors=True)

    def vr(self, name: str) -> int:
        return self.vars[name].valueReference

    def set(self, name: str, value):
        v = self.vars[name]
        if v.type == "Real":
            self.slave.setReal([v.valueReference], [float(value)])
        elif v.type == "Integer":
            self.slave.setInteger([v.valueReference], [int(value)])
        elif v.type == "Boolean":
            self.slave.setBoolean([v.valueReference], [bool(value)])
        else:
            self.slave.setString([v.valueReference], [str(value)])

    def output_names(self, n_blocks: int) -> list[str]:
        names = ["up", "vp", "apAbs", "baseShear"]
        for q in ("ub", "vb", "slip", "abAbs", "F", "stuck"):
            names += [f"{q}[{j}]" for j in range(1, n_blocks + 1)]
        return names + ["Einput", "Ekinetic", "Estrain", "Eviscous", "Efriction", "nEvents"]

    def peaks(self, n_blocks: int) -> dict:
        names = ["peakUp", "peakApAbs", "Einput", "Ekinetic", "Estrain", "Eviscous", "Efriction"]
        names += [f"peakSlip[{j}]" for j in range(1, n_blocks + 1)]
        out = dict(zip(names, self.slave.getReal([self.vr(n) for n in names])))
        counts = ["nEvents", "nAmbiguous"]
        out.update(zip(counts, self.slave.getInteger([self.vr(n) for n in counts])))
        return out

    def record_duration(self, record: str | Path | None, g: float = 9.81) -> float:
        """Last sample time of a record (None: the embedded default), cached
        while the file keeps its size and modification time."""
        path = Path(record) if record else Path(self.unzipdir) / "resources" / DEFAULT_RECORD
        stat = path.stat()
        key = (str(path.resolve()), stat.st_size, stat.st_mtime_ns, g)
        if key not in self._durations:
            self._durations[key] = float(read_record(path, g)[0][-1])
        return self._durations[key]

    def start(self, params: dict, stop: float, record_file: str = "") -> int:
        """Resets (unless fresh), sets the parameters, initializes; returns nBlocks."""
        if not self.fresh:
            self.slave.reset()
        self.fresh = False
        self.messages.clear()
        s = self.slave
        s.setupExperiment(startTime=0.0, stopTime=stop)
        s.enterInitializationMode()
        self.set("recordFile", record_file)
        for name, value in params.items():
            self.set(name, value)
        s.exitInitializationMode()
        return s.getInteger([self.vr("nBlocks")])[0]

    def run_input(self, ag: np.ndarray, h: float, params: dict | None = None,
                  outputs: tuple[str, ...] = ("up",)) -> dict:
        """Co-simulation with the ground acceleration as an input: ag[i] is set
        before the step from i h to (i + 1) h and held over it, as a master
        does. Returns the `outputs` at every communication point and the peaks.
        A failed step ends the run early with `failed` set."""
        params = dict(params or {})
        stop = len(ag) * h
        n_blocks = self.start(params, stop)
        s = self.slave
        ag_vr, out_vr = [self.vr("ag")], [self.vr(n) for n in outputs]
        rows = np.full((len(ag) + 1, len(outputs)), np.nan)
        rows[0] = s.getReal(out_vr)
        failed = False
        for i, a in enumerate(ag):
            s.setReal(ag_vr, [float(a)])
            try:
                s.doStep(i * h, h)
            except Exception:
                failed = True
                break
            rows[i + 1] = s.getReal(out_vr)
        result = {"time": np.arange(len(ag) + 1) * h, "failed": failed, "nBlocks": n_blocks}
        for k, name in enumerate(outputs):
            result[name] = rows[:, k]
        result["peaks"] = {} if failed else self.peaks(n_blocks)
        if not failed:
            s.terminate()
        return result

    BATCH_PARAMS = 28   # nBlocks, mp, Tp, zeta, alpha[1..8], mus[1..8], muk[1..8]
    BATCH_OUTPUTS = 13  # peakUp, peakApAbs, Einput, nEvents, nAmbiguous, peakSlip[1..8]

    def run_batch(self, record: str | Path, params_list: list[dict], g: float = 9.81,
                  scale: float = 1.0) -> list[dict]:
        """Peaks of many parameter sets over one record in one call of the
        library's `sllRunBatch` (beside the FMI API; the default solver, from
        rest, as `run` without `dt`). A parameter missing from a set takes
        the FMU's default. Returns per set: peakUp, peakApAbs, Einput,
        nEvents, nAmbiguous, peakSlip[j] for j up to nBlocks."""
        defaults = {v.name: float(v.start) for v in self.md.modelVariables
                    if v.start is not None and v.type in ("Real", "Integer")}
        names = (["nBlocks", "mp", "Tp", "zeta"] + [f"alpha[{j}]" for j in range(1, 9)]
                 + [f"mus[{j}]" for j in range(1, 9)] + [f"muk[{j}]" for j in range(1, 9)])
        table = np.array([[float(p.get(n, defaults[n])) for n in names] for p in params_list],
                         dtype=np.float64).reshape(len(params_list), self.BATCH_PARAMS)
        out = np.zeros((len(params_list), self.BATCH_OUTPUTS))
        fn = self.slave.dll.sllRunBatch
        fn.argtypes = [c_char_p, c_double, c_double, c_int, POINTER(c_double), POINTER(c_double),
                       c_char_p, c_size_t]
        fn.restype = c_int
        message = create_string_buffer(1024)
        status = fn(str(Path(record).resolve()).encode(), g, scale, len(params_list),
                    table.ctypes.data_as(POINTER(c_double)), out.ctypes.data_as(POINTER(c_double)),
                    message, len(message))
        if status != 0:
            raise RuntimeError(message.value.decode())
        rows = []
        for p, o in zip(table, out):
            n = int(p[0])
            # Plain floats, as Model.run gives (numpy's repr would reach CSV files).
            row = {"peakUp": float(o[0]), "peakApAbs": float(o[1]), "Einput": float(o[2]),
                   "nEvents": int(o[3]), "nAmbiguous": int(o[4])}
            row.update({f"peakSlip[{j}]": float(o[4 + j]) for j in range(1, n + 1)})
            rows.append(row)
        return rows

    def run(self, record: str | Path | None = None, params: dict | None = None,
            dt: float | None = None, stop: float | None = None) -> dict:
        """Runs `record` (a file path; None: the FMU's embedded default) with the
        given parameters. With `dt`, steps every `dt` and returns time histories;
        without, covers the whole record in one fmi2DoStep (peaks only, and
        `seconds`, the wall time of that one call)."""
        params = dict(params or {})
        record_file = str(Path(record).resolve()) if record else DEFAULT_RECORD
        if stop is None:
            stop = self.record_duration(record, float(params.get("g", 9.81)))
        n_blocks = self.start(params, stop, record_file)
        s = self.slave
        result = {"params": {"recordFile": record_file, **params}, "nBlocks": n_blocks}
        if dt is None:
            started = time.perf_counter()
            s.doStep(0.0, stop)
            result["seconds"] = time.perf_counter() - started
        else:
            names = self.output_names(n_blocks)
            kinds = {n: self.vars[n].type for n in names}
            real = [n for n in names if kinds[n] == "Real"]
            boolean = [n for n in names if kinds[n] == "Boolean"]
            real_vr = [self.vr(n) for n in real]
            bool_vr = [self.vr(n) for n in boolean]
            n = int(round(stop / dt))
            times = np.arange(n + 1) * dt
            rows = np.zeros((n + 1, len(real)))
            flags = np.zeros((n + 1, len(boolean)), dtype=bool)
            rows[0] = s.getReal(real_vr)
            flags[0] = s.getBoolean(bool_vr) if bool_vr else []
            for i in range(n):
                s.doStep(times[i], times[i + 1] - times[i])
                rows[i + 1] = s.getReal(real_vr)
                if bool_vr:
                    flags[i + 1] = s.getBoolean(bool_vr)
            result["time"] = times
            for k, name in enumerate(real):
                result[name] = rows[:, k]
            for k, name in enumerate(boolean):
                result[name] = flags[:, k]
        result["peaks"] = self.peaks(n_blocks)
        s.terminate()
        return result
