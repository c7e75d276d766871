"""Partners of a co-simulation: anything a master can set inputs on, read
outputs from and step (docs/stack-on-a-floor.md).

The protocol (class `Partner`; a partner overrides what it can do):
- `start(t0, stop)`: initialize (parameters were given to the constructor);
- `set(port, value, slope=0.0)`: an input at the current time and its slope over
  the coming step (a partner that cannot interpolate inputs holds the value:
  `takes_slopes` False);
- `get(port)`: an output now;
- `step(t, h)`: from t to at most t + h; returns the time reached (a partner that
  may return early, `returns_early` True, can stop short, at an event);
- optional rollback (`can_rollback`): `save()` -> state, `restore(state)`, `free(state)`;
- optional interface Jacobian (`can_add_mass`): `add_mass(port, kg)` sets the mass
  added at a force port (the total, replacing the previous one), `mobility(port)`
  is d acceleration / d force at that port (1/kg) without the added mass;
- `close()`.
A method a partner does not provide raises `NotSupported` saying which partner and
why; masters check the capability flags first and refuse a configuration they
cannot run (`ConfigurationError`).
"""

from __future__ import annotations

import math
import shutil
import tempfile
from pathlib import Path

import numpy as np


class ConfigurationError(ValueError):
    """A master cannot run this configuration (the message says why)."""


class NotSupported(ConfigurationError):
    """A partner cannot do what was asked of it."""


class Partner:
    """Base class: the protocol with every optional capability switched off."""

    takes_slopes = False     # set() uses the slope (inputs linear over a step)
    returns_early = False    # step() may stop short of t + h
    can_rollback = False     # save / restore / free
    can_add_mass = False     # add_mass / mobility

    def __init__(self, name: str):
        if not name or "." in name:
            raise ConfigurationError(f"partner name {name!r}: it must be non-empty and have no '.'")
        self.name = name

    def start(self, t0: float, stop: float) -> None:
        pass

    def set(self, port: str, value: float, slope: float = 0.0) -> None:
        raise NotSupported(f"{self.name}: no input {port!r}")

    def get(self, port: str) -> float:
        raise NotSupported(f"{self.name}: no output {port!r}")

    def step(self, t: float, h: float) -> float:
        raise NotImplementedError

    def save(self):
        raise NotSupported(f"{self.name}: cannot save and restore its state (no rollback)")

    def restore(self, state) -> None:
        raise NotSupported(f"{self.name}: cannot save and restore its state (no rollback)")

    def free(self, state) -> None:
        pass

    def output_derivative(self, port: str, order: int = 1) -> float:
        raise NotSupported(f"{self.name}: gives no derivative of {port!r}")

    def add_mass(self, port: str, kg: float) -> None:
        raise NotSupported(f"{self.name}: cannot add mass at {port!r} (no add_mass)")

    def mobility(self, port: str) -> float:
        raise NotSupported(f"{self.name}: gives no mobility at {port!r}")

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# ---------------------------------------------------------------------- FMUs

class FMUPartner(Partner):
    """Any Co-Simulation FMU (FMI 2.0 or 3.0) through fmpy: the storey FMU
    (StackedLiveLoad.fmu), StackOnFloor.fmu, others. Ports are the FMU's
    variable names. `parameters` are start values set in initialization
    (Real, Integer, Boolean, String). Input slopes go to
    fmi2SetRealInputDerivatives when the FMU can interpolate inputs (FMI 2.0,
    canInterpolateInputs); FMI 3.0 has no input derivatives in Co-Simulation,
    so there inputs are held. Rollback through the FMU state when
    canGetAndSetFMUstate. `early_return=True` (FMI 3.0 with
    mightReturnEarlyFromDoStep) lets the FMU stop at its events."""

    def __init__(self, name: str, fmu: str | Path, parameters: dict | None = None,
                 early_return: bool = False):
        super().__init__(name)
        from fmpy import extract, read_model_description

        self.fmu = Path(fmu)
        if not self.fmu.exists():
            raise ConfigurationError(f"{name}: no FMU at {self.fmu}")
        self.md = read_model_description(str(self.fmu))
        self.v3 = self.md.fmiVersion.startswith("3")
        cs = self.md.coSimulation
        if cs is None:
            raise ConfigurationError(f"{name}: {self.fmu.name} has no Co-Simulation interface")
        self.parameters = dict(parameters or {})
        self.vars = {v.name: v for v in self.md.modelVariables}
        for p in self.parameters:
            if p not in self.vars:
                raise ConfigurationError(f"{name}: {self.fmu.name} has no variable {p!r}")
        self.can_rollback = bool(cs.canGetAndSetFMUstate)
        self.takes_slopes = (not self.v3) and bool(cs.canInterpolateInputs)
        if early_return and not (self.v3 and getattr(cs, "mightReturnEarlyFromDoStep", False)):
            raise ConfigurationError(f"{name}: early return needs an FMI 3.0 FMU that declares "
                                     f"mightReturnEarlyFromDoStep ({self.fmu.name} is FMI "
                                     f"{self.md.fmiVersion})")
        self.returns_early = bool(early_return)
        self.messages: list[str] = []
        self.unzipdir = extract(str(self.fmu), tempfile.mkdtemp(prefix=f"sll_{name}_"))
        self._instantiate(cs.modelIdentifier)
        self.started = False
        self.with_slope: set[str] = set()

    def _instantiate(self, identifier: str):
        from ctypes import byref

        def keep(text):
            self.messages.append(text.decode() if isinstance(text, bytes) else str(text))

        if self.v3:
            from fmpy.fmi3 import FMU3Slave

            self.slave = FMU3Slave(guid=self.md.instantiationToken, unzipDirectory=self.unzipdir,
                                   modelIdentifier=identifier, instanceName=self.name)
            self.slave.instantiate(earlyReturnAllowed=self.returns_early,
                                   logMessage=lambda env, status, category, message: keep(message))
        else:
            from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE
            from fmpy.logging import addLoggerProxy

            self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                                   modelIdentifier=identifier, instanceName=self.name)
            self.callbacks = fmi2CallbackFunctions()
            self.callbacks.logger = fmi2CallbackLoggerTYPE(
                lambda component, instance, status, category, message: keep(message))
            addLoggerProxy(byref(self.callbacks))
            self.slave.instantiate(callbacks=self.callbacks, loggingOn=False)

    # -- values by type
    def _var(self, port: str):
        try:
            return self.vars[port]
        except KeyError:
            raise ConfigurationError(f"{self.name}: {self.fmu.name} has no variable {port!r}") from None

    def _write(self, port: str, value):
        v = self._var(port)
        vr, s, t = [v.valueReference], self.slave, v.type
        if t in ("Real", "Float64", "Float32"):
            (s.setFloat64 if self.v3 else s.setReal)(vr, [float(value)])
        elif t in ("Integer", "Int32", "Int64", "UInt32", "UInt64", "Enumeration"):
            (s.setInt32 if self.v3 and t == "Int32" else s.setInt64 if self.v3 else s.setInteger)(vr, [int(value)])
        elif t == "Boolean":
            s.setBoolean(vr, [bool(value)])
        else:
            s.setString(vr, [str(value)])

    def get(self, port: str) -> float:
        v = self._var(port)
        vr, s, t = [v.valueReference], self.slave, v.type
        if t in ("Real", "Float64", "Float32"):
            return (s.getFloat64 if self.v3 else s.getReal)(vr)[0]
        if t == "Boolean":
            return float(s.getBoolean(vr)[0])
        if self.v3:
            return float((s.getInt32 if t == "Int32" else s.getInt64)(vr)[0])
        return float(s.getInteger(vr)[0])

    def said(self, error: Exception) -> str:
        return "; ".join(self.messages[-3:]) or str(error)

    def start(self, t0: float = 0.0, stop: float | None = None) -> None:
        s = self.slave
        if self.started:
            s.reset()
        self.started = True
        self.messages.clear()
        self.with_slope.clear()
        try:
            if self.v3:
                s.enterInitializationMode(startTime=t0, stopTime=stop)
            else:
                s.setupExperiment(startTime=t0, stopTime=stop)
                s.enterInitializationMode()
            for name, value in self.parameters.items():
                self._write(name, value)
            s.exitInitializationMode()
        except Exception as e:  # a parameter the FMU refused: its message names it
            raise ConfigurationError(f"{self.name}: {self.said(e)}") from None

    def set(self, port: str, value: float, slope: float = 0.0) -> None:
        self._write(port, value)
        if self.takes_slopes and (slope != 0.0 or port in self.with_slope):
            self.slave.setRealInputDerivatives([self._var(port).valueReference], [1], [float(slope)])
            (self.with_slope.add if slope != 0.0 else self.with_slope.discard)(port)

    def output_derivative(self, port: str, order: int = 1) -> float:
        vr = [self._var(port).valueReference]
        if self.v3:
            return self.slave.getOutputDerivatives(vr, [order])[0]
        return self.slave.getRealOutputDerivatives(vr, [order])[0]

    def step(self, t: float, h: float) -> float:
        try:
            if self.v3:
                _event, terminate, early, last = self.slave.doStep(t, h)
                if terminate:
                    raise RuntimeError("the FMU asked to terminate")
                return float(last) if early else t + h
            self.slave.doStep(t, h)
            return t + h
        except Exception as e:
            raise RuntimeError(f"{self.name}: doStep({t:.9g}, {h:.6g}) failed: {self.said(e)}") from None

    def save(self):
        if not self.can_rollback:
            return super().save()
        return self.slave.getFMUState() if self.v3 else self.slave.getFMUstate()

    def restore(self, state) -> None:
        if not self.can_rollback:
            return super().restore(state)
        (self.slave.setFMUState if self.v3 else self.slave.setFMUstate)(state)

    def free(self, state) -> None:
        if self.can_rollback:
            (self.slave.freeFMUState if self.v3 else self.slave.freeFMUstate)(state)

    def close(self) -> None:
        try:
            if self.started:
                try:
                    self.slave.terminate()
                except Exception:
                    pass
            self.slave.freeInstance()
        finally:
            shutil.rmtree(self.unzipdir, ignore_errors=True)


# ------------------------------------------------------------------ OpenSees

class OpenSeesPartner(Partner):
    """A structural model in openseespy, built by `build()` (called after
    ops.wipe(); it creates nodes with masses, boundary conditions, materials and
    elements in the basic model of its choice). `floors` names the nodes where
    a stack can stand: {"floor2": node_tag}. For each floor, ports:
    - `<floor>.force` (input, N, along +x in `dof`): a force applied through a
      load pattern rebuilt whenever the input changes (value and slope: linear
      over the step);
    - `<floor>.accel` (output, m/s2): absolute acceleration, nodeAccel + ag(t);
    - `<floor>.disp`, `<floor>.vel` (outputs): relative to the ground.
    `ground` = (t, ag in m/s2) drives the supports (UniformExcitation, linear
    between samples). Newmark average acceleration with Newton iterations;
    step(t, h) takes ceil(h / dt_max) equal analysis steps, so any h works
    (variable steps). `add_mass(port, kg)` sets the node's mass to its own plus
    kg (ops.mass); `mobility(port)` = 1 / the node's own mass.

    After an input or a mass jumps, the partner takes one analysis step of
    `settle` seconds (1e-9 s) before its acceleration is read or it steps on,
    and sets the clock back: that makes the node's acceleration consistent
    with the new load and mass (Newmark keeps the acceleration of the last
    converged step, and a jump of the load left there would cost (dt/2)·jump
    of velocity at every switch).

    No rollback: OpenSees keeps its state in its domain, and openseespy has no
    call that copies it to memory and back; its `database`/`save`/`restore`
    commands go through files and were not tried here. `can_rollback` is
    False."""

    takes_slopes = True
    can_add_mass = True

    def __init__(self, name: str, build, floors: dict[str, int], ground=None, dt_max: float = 0.001,
                 dof: int = 1, settle: float = 1e-9, tol: float = 1e-10):
        super().__init__(name)
        self.build, self.floors, self.dof = build, dict(floors), dof
        self.ground = None if ground is None else tuple(np.asarray(g, float) for g in ground)
        self.dt_max, self.settle, self.tol = dt_max, settle, tol
        self.forces = {f: (0.0, 0.0, 0.0) for f in self.floors}  # value, slope, at time
        self.added = {f: 0.0 for f in self.floors}
        self.analysis_steps = 0

    def _floor(self, port: str) -> tuple[str, str]:
        floor, _, what = port.partition(".")
        if floor not in self.floors:
            raise ConfigurationError(f"{self.name}: no floor {floor!r} (floors: {sorted(self.floors)})")
        return floor, what

    def start(self, t0: float = 0.0, stop: float | None = None) -> None:
        import openseespy.opensees as ops

        self.ops = ops
        if t0 != 0.0:
            raise ConfigurationError(f"{self.name}: an OpenSees model starts at t = 0")
        ops.wipe()
        self.build()
        self.own_mass = {f: ops.nodeMass(n, self.dof) for f, n in self.floors.items()}
        for f, m in self.own_mass.items():
            if not m > 0:
                raise ConfigurationError(f"{self.name}: floor {f!r} (node {self.floors[f]}) has no mass")
        self.ndf = len(ops.nodeDisp(next(iter(self.floors.values()))))
        if self.ground is not None:
            t, a = self.ground
            ops.timeSeries("Path", 90001, "-time", *map(float, t), "-values", *map(float, a))
            ops.pattern("UniformExcitation", 90001, self.dof, "-accel", 90001)
        ops.timeSeries("Constant", 90002)
        ops.timeSeries("Linear", 90003)
        ops.constraints("Plain")
        ops.numberer("RCM")
        ops.system("BandGeneral")
        ops.test("NormDispIncr", self.tol, 50)
        ops.algorithm("Newton")
        ops.integrator("Newmark", 0.5, 0.25)
        ops.analysis("Transient")
        self.forces = {f: (0.0, 0.0, 0.0) for f in self.floors}
        self.added = {f: 0.0 for f in self.floors}
        self.dirty = True  # patterns to (re)build before the next step
        self.unsettled = False
        self.analysis_steps = 0

    def ag(self, t: float) -> float:
        if self.ground is None:
            return 0.0
        tg, ag = self.ground
        return float(np.interp(t, tg, ag, left=0.0, right=0.0))

    def set(self, port: str, value: float, slope: float = 0.0) -> None:
        floor, what = self._floor(port)
        if what != "force":
            raise ConfigurationError(f"{self.name}: {port!r} is not an input (inputs: <floor>.force)")
        now = self.ops.getTime()
        v0, s0, t0 = self.forces[floor]
        if (value, slope) != (v0 + s0 * (now - t0), s0):
            # A value other than where the last ramp ended is a jump: settle.
            if abs(value - (v0 + s0 * (now - t0))) > 1e-12 * max(1.0, abs(value)) and now > 0.0:
                self.unsettled = True
            self.forces[floor] = (float(value), float(slope), now)
            self.dirty = True

    def get(self, port: str) -> float:
        floor, what = self._floor(port)
        node, ops = self.floors[floor], self.ops
        if what == "accel":
            self._settle()
            return ops.nodeAccel(node, self.dof) + self.ag(ops.getTime())
        if what == "disp":
            return ops.nodeDisp(node, self.dof)
        if what == "vel":
            return ops.nodeVel(node, self.dof)
        raise ConfigurationError(f"{self.name}: no output {port!r} (outputs: <floor>.accel, .disp, .vel)")

    def add_mass(self, port: str, kg: float) -> None:
        floor, _ = self._floor(port)
        if kg != self.added[floor]:
            self.added[floor] = float(kg)
            values = [0.0] * self.ndf
            for d in range(1, self.ndf + 1):
                values[d - 1] = self.ops.nodeMass(self.floors[floor], d)
            values[self.dof - 1] = self.own_mass[floor] + kg
            self.ops.mass(self.floors[floor], *values)
            self.unsettled = self.ops.getTime() > 0.0 or self.unsettled

    def mobility(self, port: str) -> float:
        floor, _ = self._floor(port)
        return 1.0 / self.own_mass[floor]

    def _patterns(self, t: float):
        """One pattern per floor: F(t') = value + slope (t' - t), as a Constant
        series carrying value - slope t plus a Linear one (factor = time)
        carrying slope."""
        ops = self.ops
        for i, (floor, node) in enumerate(self.floors.items()):
            value, slope, base = self.forces[floor]
            value += slope * (t - base)
            for tag in (91000 + 2 * i, 91001 + 2 * i):
                ops.remove("loadPattern", tag)
            load = [0.0] * self.ndf
            load[self.dof - 1] = value - slope * t
            ops.pattern("Plain", 91000 + 2 * i, 90002)
            ops.load(node, *load)
            if slope != 0.0:
                load[self.dof - 1] = slope
                ops.pattern("Plain", 91001 + 2 * i, 90003)
                ops.load(node, *load)
        self.dirty = False

    def _settle(self):
        """After a jump of a load or a mass: one analysis step of `settle`
        seconds, so that the node's acceleration is that of the new load and
        mass; the domain's time is then set back (ops.setTime)."""
        if self.dirty:
            self._patterns(self.ops.getTime())
        if self.unsettled:
            self.unsettled = False
            now = self.ops.getTime()
            self._analyze(self.settle)
            self.ops.setTime(now)  # an instantaneous re-equilibration: the clock stays

    def step(self, t: float, h: float) -> float:
        ops = self.ops
        now = ops.getTime()
        if abs(now - t) > 1e-9 * max(1.0, abs(t)):
            raise ConfigurationError(f"{self.name}: asked to step from t = {t:.9g} but the model "
                                     f"is at {now:.9g} (OpenSees cannot roll back)")
        end = t + h
        self._settle()
        if self.dirty:
            self._patterns(ops.getTime())
        left = end - ops.getTime()
        if left <= 0.0:
            return end
        n = max(1, math.ceil(left / self.dt_max - 1e-9))
        for _ in range(n):
            self._analyze(left / n)
        return end

    def _analyze(self, dt: float):
        if self.ops.analyze(1, dt) != 0:
            raise RuntimeError(f"{self.name}: OpenSees did not converge in the step of {dt:.3g} s "
                               f"from t = {self.ops.getTime():.9g}")
        self.analysis_steps += 1

    def close(self) -> None:
        try:
            self.ops.wipe()
        except AttributeError:
            pass
