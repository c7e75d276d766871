"""A linear shear building as a co-simulation partner, solved exactly (the
tests' partner: tests/python/test_cosim.py). Floors 1..n, storey i joins floor
i-1 (the ground for i = 1) and floor i with stiffness k_i and damping c_i;
floor i has mass m_i plus what add_mass puts there. The ground acceleration is
linear between its samples, the floor forces linear over a step (value and
slope), so over each piece between record samples the state is advanced
exactly by the matrix exponential of the system augmented with the inputs and
their slopes (Nigam-Jennings in matrix form)."""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm

from sll.cosim import ConfigurationError, Partner
from sll.coupling import shear_building


class LinearFloors(Partner):
    takes_slopes = True
    can_rollback = True
    can_add_mass = True

    def __init__(self, name: str, masses, stiffnesses, dampings, ground):
        super().__init__(name)
        self.m0 = np.asarray(masses, float)
        self.k = np.asarray(stiffnesses, float)
        self.c = np.asarray(dampings, float)
        self.n = len(self.m0)
        self.tg, self.ag_rec = (np.asarray(v, float) for v in ground)
        # The shear building's matrices, as the storey chain's exact reference builds them.
        _, self.C, self.K = shear_building(
            [{"m": m, "k": k, "c": c} for m, k, c in zip(self.m0, self.k, self.c)])
        self.cache: dict = {}
        self.start()

    def start(self, t0: float = 0.0, stop: float | None = None):
        self.t = t0
        self.x, self.v = np.zeros(self.n), np.zeros(self.n)
        self.f, self.fdot = np.zeros(self.n), np.zeros(self.n)
        self.added = np.zeros(self.n)

    def _floor(self, port):
        name, _, what = port.partition(".")
        if not name.startswith("floor") or not name[5:].isdigit() or not 1 <= int(name[5:]) <= self.n:
            raise ConfigurationError(f"{self.name}: no port {port!r}")
        return int(name[5:]) - 1, what

    def ag(self, t):
        return float(np.interp(t, self.tg, self.ag_rec, left=0.0, right=0.0))

    def mass(self):
        return self.m0 + self.added

    def set(self, port, value, slope=0.0):
        i, what = self._floor(port)
        if what != "force":
            raise ConfigurationError(f"{self.name}: {port!r} is not an input")
        self.f[i], self.fdot[i] = value, slope

    def get(self, port):
        i, what = self._floor(port)
        if what == "accel":  # absolute: the ground drops out
            return float(((self.f - self.K @ self.x - self.C @ self.v) / self.mass())[i])
        if what == "disp":
            return float(self.x[i])
        if what == "vel":
            return float(self.v[i])
        if what == "drift":
            return float(self.x[i] - (self.x[i - 1] if i else 0.0))
        raise ConfigurationError(f"{self.name}: no output {port!r}")

    def add_mass(self, port, kg):
        i, _ = self._floor(port)
        self.added[i] = kg

    def mobility(self, port):
        i, _ = self._floor(port)
        return 1.0 / self.m0[i]

    def save(self):
        return (self.t, self.x.copy(), self.v.copy(), self.f.copy(), self.fdot.copy(), self.added.copy())

    def restore(self, state):
        self.t, x, v, f, fd, a = state
        self.x, self.v, self.f, self.fdot, self.added = x.copy(), v.copy(), f.copy(), fd.copy(), a.copy()

    def _propagator(self, h):
        key = (round(h, 14), tuple(self.mass()))
        if key not in self.cache:
            n = self.n
            minv = np.diag(1.0 / self.mass())
            a = np.zeros((4 * n + 2, 4 * n + 2))
            a[:n, n:2 * n] = np.eye(n)
            a[n:2 * n, :n] = -minv @ self.K
            a[n:2 * n, n:2 * n] = -minv @ self.C
            a[n:2 * n, 2 * n] = -1.0                 # - ag
            a[n:2 * n, 2 * n + 2:3 * n + 2] = minv   # + F / m
            a[2 * n, 2 * n + 1] = 1.0                # ag' = agdot
            a[2 * n + 2:3 * n + 2, 3 * n + 2:] = np.eye(n)  # F' = Fdot
            self.cache[key] = expm(a * h)
        return self.cache[key]

    def step(self, t, h):
        if abs(t - self.t) > 1e-9:
            raise ConfigurationError(f"{self.name}: at {self.t}, asked to step from {t}")
        end = t + h
        cuts = self.tg[(self.tg > t + 1e-12) & (self.tg < end - 1e-12)]
        points = [t, *cuts, end]
        n = self.n
        for a, b in zip(points[:-1], points[1:]):
            mid = 0.5 * (a + b)
            seg = np.clip(np.searchsorted(self.tg, mid) - 1, 0, len(self.tg) - 2)
            inside = self.tg[0] <= mid < self.tg[-1]
            slope = (self.ag_rec[seg + 1] - self.ag_rec[seg]) / (self.tg[seg + 1] - self.tg[seg]) if inside else 0.0
            z = np.concatenate([self.x, self.v, [self.ag(a), slope], self.f, self.fdot])
            z = self._propagator(b - a) @ z
            self.x, self.v = z[:n], z[n:2 * n]
            self.f = z[2 * n + 2:3 * n + 2]
        self.t = end
        return end
