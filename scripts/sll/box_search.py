"""The worst case of a function over a box, for the advisor's friction range.

The advisor's friction range is a box: every interface's mu (static and kinetic
alike) times a factor in [1 - u, 1 + u], independently. A ratio of peak drifts is
not monotone in friction, and its minimum can lie inside the box, not at a corner
(a block that starts sliding at one friction and not at another), so corners are
not enough. `search` finds the lowest value of each objective:

1. a grid of k points per axis (corners included), k as large as a budget of
   evaluations allows (`grid_size`);
2. on every grid cell, a lower bound: the lowest vertex value minus the largest
   slope seen on the cell's edges times the distance from the cell's centre to a
   vertex (a Lipschitz bound with the slope estimated from the cell itself);
3. compass (pattern) search from the lowest vertex of each of the `starts` cells
   with the lowest bounds, the steps halving from half a grid step down to
   `min_step` (in factor units), all objectives and starts in lockstep so that each
   round is one batch of runs;
4. a `margin`: how far below the lowest value found the function could still be,
   by the cells' bounds, in the cells that were not refined (and, around each
   refined point, the last step times the slope seen there). A caller that must
   not be unconservative judges `value - margin`.

What it guarantees: every evaluated point is exact (the engine's accuracy); between
them it relies on the slope estimated from neighbouring points (a function that
dips and recovers within one cell without showing it on the cell's edges can hide
a lower value: no sampling method can exclude that).
"""

from __future__ import annotations

import itertools
import math

import numpy as np

BUDGET = 800        # grid points at most (each: one run per record)
MAX_PER_AXIS = 13   # the grid's k never above this (1-D and 2-D boxes)
STARTS = 4          # compass searches per objective
MIN_STEP = 1.0 / 256  # of the box's width: the compass search's last step


def grid_size(n: int, budget: int = BUDGET, cap: int = MAX_PER_AXIS) -> int:
    """Points per axis: the largest k with k^n <= budget (at most `cap`), and never fewer
    than 3 (corners and mid-points: 3^8 = 6561 points for 8 blocks, beyond the budget,
    since corners alone say nothing about the inside of the box)."""
    k = 3
    while k < cap and (k + 1) ** n <= budget:
        k += 1
    return k


class _Cache:
    """Evaluated points and their objective values; new points evaluated in batches."""

    def __init__(self, evaluate, objectives):
        self.evaluate, self.objectives = evaluate, objectives
        self.index: dict[tuple, int] = {}
        self.points: list[np.ndarray] = []
        self.values = {o: [] for o in objectives}

    @staticmethod
    def key(x) -> tuple:
        return tuple(round(float(v), 10) for v in x)

    def get(self, xs) -> list[int]:
        xs = [np.asarray(x, dtype=float) for x in xs]
        new, seen = [], set()
        for x in xs:
            k = self.key(x)
            if k not in self.index and k not in seen:
                seen.add(k)
                new.append(x)
        if new:
            got = self.evaluate(np.array(new))
            for i, x in enumerate(new):
                self.index[self.key(x)] = len(self.points)
                self.points.append(x)
                for o in self.objectives:
                    self.values[o].append(float(got[o][i]))
        return [self.index[self.key(x)] for x in xs]

    def value(self, o, i) -> float:
        return self.values[o][i]


def search(evaluate, n: int, lo: float, hi: float, objectives: list[str], nominal=None,
           budget: int = BUDGET, starts: int = STARTS, min_step: float = MIN_STEP) -> dict:
    """Lowest value of each objective over the box [lo, hi]^n.

    evaluate(points) -> {objective: values} for an (m, n) array of points (to be
    minimised; pass -f to maximise f). `nominal`: a point always evaluated (e.g.
    all factors 1). Returns per objective: value, point, margin, bound (value -
    margin), refined (starts), evaluations; and grid (k, step), points evaluated
    and the guarantee in words."""
    cache = _Cache(evaluate, objectives)
    k = grid_size(n, budget)
    axis = np.linspace(lo, hi, k)
    h = (hi - lo) / (k - 1)
    grid = np.array(list(itertools.product(axis, repeat=n))) if n else np.zeros((1, 0))
    extra = [np.asarray(nominal, dtype=float)] if nominal is not None else []
    ids = cache.get(list(grid) + extra)
    gid = np.array(ids[:len(grid)]).reshape((k,) * n)
    reach = h * math.sqrt(n) / 2.0  # centre of a cell to its vertices
    out = {}
    states = []  # [objective, point index, step]
    cells_info = {}
    for o in objectives:
        v = np.array([cache.value(o, i) for i in ids[:len(grid)]]).reshape((k,) * n)
        # Largest slope on each axis-aligned edge of the grid, then per cell.
        cell_shape = (k - 1,) * n
        slope = np.zeros(cell_shape)
        low = np.full(cell_shape, np.inf)
        low_at = np.zeros(cell_shape + (n,), dtype=int)
        for corner in itertools.product((0, 1), repeat=n):
            sl = tuple(slice(c, c + k - 1) for c in corner)
            vc = v[sl]
            better = vc < low
            low = np.where(better, vc, low)
            low_at[better] = np.array(corner)
            for ax in range(n):
                if corner[ax] == 0:
                    sl2 = tuple(slice(c + (1 if a == ax else 0), c + (1 if a == ax else 0) + k - 1)
                                for a, c in enumerate(corner))
                    slope = np.maximum(slope, np.abs(v[sl2] - vc) / h)
        bound = low - slope * reach
        order = np.argsort(bound, axis=None)
        chosen, starts_at = [], set()
        for flat in order:
            cell = np.unravel_index(flat, cell_shape)
            vertex = tuple(int(c) + int(d) for c, d in zip(cell, low_at[cell]))
            chosen.append(cell)
            if vertex not in starts_at:
                starts_at.add(vertex)
                states.append([o, int(gid[vertex]), h / 2.0])
            if len(starts_at) >= starts:
                break
        cells_info[o] = (bound, slope, chosen)
    # Compass search, every (objective, start) in lockstep: one batch per round.
    final = {o: [] for o in objectives}
    while states:
        polls = []
        for o, i, s in states:
            x = cache.points[i]
            for ax in range(n):
                for sign in (1.0, -1.0):
                    y = x.copy()
                    y[ax] = min(hi, max(lo, y[ax] + sign * s))
                    polls.append(y)
        cache.get(polls)
        nxt = []
        for o, i, s in states:
            x = cache.points[i]
            here = cache.value(o, i)
            near = []
            for ax in range(n):
                for sign in (1.0, -1.0):
                    y = x.copy()
                    y[ax] = min(hi, max(lo, y[ax] + sign * s))
                    j = cache.get([y])[0]
                    if j != i:
                        near.append(j)
            best = min(near, key=lambda j: cache.value(o, j), default=i)
            if near and cache.value(o, best) < here - 1e-12:
                nxt.append([o, best, s])
            elif s / 2.0 >= min_step * (hi - lo):
                nxt.append([o, i, s / 2.0])
            else:
                slope = max((abs(cache.value(o, j) - here) / s for j in near), default=0.0)
                final[o].append((i, s, slope))
        states = nxt
    for o in objectives:
        values = np.array(cache.values[o])
        best = int(np.argmin(values))
        bound, slope, chosen = cells_info[o]
        refined = np.zeros(bound.shape, dtype=bool)
        for cell in chosen:
            refined[cell] = True
        unrefined = bound[~refined]
        value = float(values[best])
        local = max((sl * s * math.sqrt(n) / 2.0 for (_, s, sl) in final[o]), default=0.0)
        margin = max(0.0, value - float(unrefined.min()) if unrefined.size else 0.0, local)
        out[o] = {"value": value, "point": cache.points[best].tolist(), "margin": margin, "bound": value - margin,
                  "refined_from": len(final[o]), "largest_cell_slope": float(slope.max()) if slope.size else 0.0}
    return {"objectives": out, "grid_per_axis": k, "grid_step": h, "final_step": min_step * (hi - lo),
            "points": np.array(cache.points), "values": {o: np.array(cache.values[o]) for o in objectives},
            "evaluations": len(cache.points),
            "guarantee": (f"every point of a {k}-per-axis grid over the box (step {h:.3g}) and compass searches down to "
                          f"step {min_step * (hi - lo):.2g} from the {starts} cells whose slope-based lower bounds are "
                          "lowest are exact; elsewhere the value may be lower than found by at most the margin, if it "
                          "changes no faster inside a cell than along the cell's edges")}
