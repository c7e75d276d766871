"""The worst case of a function over a box, for the advisor's friction range.

The advisor's friction range is a box: every interface's mu (static and kinetic
alike) times a factor in [1 - u, 1 + u], independently. A ratio of peak drifts is
not monotone in friction, and its minimum can lie inside the box, not at a corner
(a block that starts sliding at one friction and not at another), so corners are
not enough. `search` finds the lowest value of each objective:

1. a grid of k points per axis (corners included), k as large as a budget of
   evaluations allows (`grid_size`, at least 3);
2. on every cell, a lower bound: the lowest vertex value minus the largest error of
   the cell's multilinear interpolant, sum over the axes of M size^2 / 8, with M the
   largest second difference seen on lines through the cell's edges (`_bound`): zero
   where the function is linear, large across a kink (a block starting to slide);
3. compass (pattern) search from the lowest vertices of the `starts` cells with the
   lowest bounds, steps halving from half a grid step to `min_step`, which finds the
   bottom of each basin fast;
4. branch and bound, for boxes of up to SPLIT_MAX_DIM dimensions: every cell whose
   bound lies below the lowest value found (by more than `rel_tol` of it) is split
   in two along every axis, its new points evaluated, its halves bounded again, until
   no such cell is left, the cells reach `min_step`, or `refine_budget` points are
   spent;
5. a `margin`: the lowest value found minus the lowest bound of any cell left. A
   caller that must not be unconservative judges `value - margin`.

All objectives and starts go in lockstep, so that each round is one batch of runs.

What it guarantees: every evaluated point is exact (the engine's accuracy); between
them the bounds rely on the curvature estimated from points around the cell (a
function that dips and recovers inside a cell without showing it on those points
can hide a lower value; no sampling method can exclude that). The margin is zero only
where the bounds of every cell are at or above the lowest value found.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

BUDGET = 800          # grid points at most (each: one run per record); at least 3 per axis
MAX_PER_AXIS = 13     # the grid's k never above this (1-D and 2-D boxes)
STARTS = 4            # compass searches per objective
MIN_STEP = 1.0 / 256  # of the box's width: the smallest step and cell
SPLIT_MAX_DIM = 4     # branch and bound up to this many dimensions (a split costs 3^n - 2^n points)
REL_TOL = 1e-4        # a cell whose bound is within this (relative) of the lowest value is not split


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


def _bound(cache: _Cache, o: str, corner: np.ndarray, size: float, n: int) -> tuple[float, int]:
    """A cell's lower bound and its lowest vertex. The multilinear interpolant of the
    vertices has its minimum at a vertex, and a function differs from it by at most
    sum_a M_a size^2 / 8 (M_a: the largest second derivative along axis a); M_a is
    estimated from the second differences of evaluated points on lines through the
    cell's edges (spacing = the cell's size). An axis with no such line falls back to
    the first-order bound, the edge slope times half the size."""
    bits = list(itertools.product((0, 1), repeat=n))
    ids = cache.get([corner + size * np.array(b) for b in bits])
    v = dict(zip(bits, (cache.value(o, i) for i in ids)))
    low = min(bits, key=lambda b: v[b])
    error = 0.0
    for ax in range(n):
        curvature, found, slope = 0.0, False, 0.0
        for b in bits:
            if b[ax]:
                continue
            base = corner + size * np.array(b)
            slope = max(slope, abs(v[b[:ax] + (1,) + b[ax + 1:]] - v[b]) / size)
            for shift in (-1, 0):
                keys = []
                for j in range(3):
                    x = base.copy()
                    x[ax] += (shift + j) * size
                    keys.append(cache.key(x))
                if all(k in cache.index for k in keys):
                    a, m, c = (cache.value(o, cache.index[k]) for k in keys)
                    curvature = max(curvature, abs(a - 2.0 * m + c) / size ** 2)
                    found = True
        error += curvature * size ** 2 / 8.0 if found else slope * size / 2.0
    return v[low] - error, ids[bits.index(low)]


def _compass(cache: _Cache, states: list, n: int, lo: float, hi: float, min_size: float):
    """Pattern search from each [objective, point index, step], all in lockstep."""
    while states:
        polls = []
        for o, i, s in states:
            x = cache.points[i]
            for ax in range(n):
                for sign in (1.0, -1.0):
                    y = x.copy()
                    y[ax] = min(hi, max(lo, y[ax] + sign * s))
                    polls.append(y)
        ids = cache.get(polls)
        nxt = []
        for k, (o, i, s) in enumerate(states):
            near = [j for j in ids[2 * n * k: 2 * n * (k + 1)] if j != i]
            best = min(near, key=lambda j: cache.value(o, j), default=i)
            if near and cache.value(o, best) < cache.value(o, i) - 1e-15:
                nxt.append([o, best, s])
            elif s / 2.0 >= min_size:
                nxt.append([o, i, s / 2.0])
        states = nxt


def search(evaluate, n: int, lo: float, hi: float, objectives: list[str], nominal=None,
           budget: int = BUDGET, starts: int = STARTS, min_step: float = MIN_STEP,
           refine_budget: int | None = None, rel_tol: float = REL_TOL) -> dict:
    """Lowest value of each objective over the box [lo, hi]^n.

    evaluate(points) -> {objective: values} for an (m, n) array of points (to be
    minimised; pass -f to maximise f). `nominal`: a point always evaluated (e.g.
    all factors 1). Returns per objective: value, point, margin, bound (value -
    margin), cells left; and the grid (k, step), the points evaluated and the
    guarantee in words."""
    cache = _Cache(evaluate, objectives)
    k = grid_size(n, budget)
    axis = np.linspace(lo, hi, k)
    h = (hi - lo) / (k - 1)
    min_size = min_step * (hi - lo)
    refine_budget = budget if refine_budget is None else refine_budget
    grid = [np.array(p) for p in itertools.product(axis, repeat=n)]
    cache.get(grid + ([np.asarray(nominal, dtype=float)] if nominal is not None else []))
    corners = [np.array(c) for c in itertools.product(axis[:-1], repeat=n)]
    cells = {o: [] for o in objectives}  # [bound, corner, size]
    states = []
    for o in objectives:
        for c in corners:
            b, low = _bound(cache, o, c, h, n)
            cells[o].append([b, c, h, low])
        cells[o].sort(key=lambda x: x[0])
        started = set()
        for b, c, size, low in cells[o]:
            if low not in started:
                started.add(low)
                states.append([o, low, h / 2.0])
            if len(started) >= starts:
                break
    _compass(cache, states, n, lo, hi, min_size)
    spent = len(cache.points)
    split = n <= SPLIT_MAX_DIM
    while split:
        todo = []
        for o in objectives:
            best = min(cache.values[o])
            cut = best - rel_tol * abs(best)
            todo += [(o, cell) for cell in cells[o] if cell[0] < cut and cell[2] / 2.0 >= min_size]
        if not todo or len(cache.points) - spent >= refine_budget:
            break
        todo.sort(key=lambda t: t[1][0] - min(cache.values[t[0]]))
        per_split = 3 ** n - 2 ** n
        todo = todo[:max(1, min(64, (refine_budget - (len(cache.points) - spent)) // per_split))]
        # Evaluate the new points of every cell to split in one batch, then bound the halves.
        fine = list(itertools.product((0, 1, 2), repeat=n))
        cache.get([cell[1] + cell[2] / 2.0 * np.array(b) for _, cell in todo for b in fine])
        gone = {id(cell) for _, cell in todo}
        for o in objectives:
            cells[o] = [cell for cell in cells[o] if id(cell) not in gone]
        for o, cell in todo:
            half = cell[2] / 2.0
            for b in itertools.product((0, 1), repeat=n):
                c = cell[1] + half * np.array(b)
                bound, low = _bound(cache, o, c, half, n)
                cells[o].append([bound, c, half, low])
    out = {}
    for o in objectives:
        values = np.array(cache.values[o])
        best = int(np.argmin(values))
        value = float(values[best])
        lowest = min(cell[0] for cell in cells[o])
        margin = max(0.0, value - lowest)
        out[o] = {"value": value, "point": cache.points[best].tolist(), "margin": margin, "bound": value - margin,
                  "cells": len(cells[o]), "smallest_cell": min(cell[2] for cell in cells[o])}
    how = (f"branch and bound on the cells down to {min_size:.2g}" if split else
           f"no cell splitting in {n} dimensions (a split costs 3^{n} - 2^{n} points)")
    return {"objectives": out, "grid_per_axis": k, "grid_step": h, "final_step": min_size,
            "points": np.array(cache.points), "values": {o: np.array(cache.values[o]) for o in objectives},
            "evaluations": len(cache.points),
            "guarantee": (f"exact at every point of a {k}-per-axis grid over the box (step {h:.3g}), of compass searches "
                          f"from the {starts} most suspect cells and of {how}; between the points the value may be "
                          "lower than found by at most the margin, if inside a cell it curves no more than on the lines "
                          "of points through the cell's edges")}
