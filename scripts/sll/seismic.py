"""Design and response spectra.

- IS 1893 (Part 1):2016 design spectra, clause 6.4.2 (b) "for use in response
  spectrum method": Sa/g for soil types I (rock / hard), II (medium), III (soft),
  zone factors II-V, DBE (Z/2) or MCE (Z), and the multiplying factors for
  damping other than 5 %.
- Pseudo-acceleration response spectra of a record, exact for a record that is
  linear between samples (Nigam & Jennings 1969), vectorized over periods.
"""

from __future__ import annotations

import numpy as np

ZONE_FACTORS = {"II": 0.10, "III": 0.16, "IV": 0.24, "V": 0.36}
# Intensity level: the share of the zone factor Z that the spectrum is scaled by
# (IS 1893 (Part 1):2016, clause 6.4.2: DBE is half the MCE).
LEVELS = {"DBE": 0.5, "MCE": 1.0}
# Soil type: (end of the 2.5 plateau (s), constant of the 1/T branch)
SOIL = {"I": (0.40, 1.00), "II": (0.55, 1.36), "III": (0.67, 1.67)}
# Damping (%) -> multiplying factor on Sa/g (IS 1893 (Part 1):2016, clause 6.4.2)
DAMPING_FACTORS = [(0.0, 3.20), (2.0, 1.40), (5.0, 1.00), (7.0, 0.90), (10.0, 0.80),
                   (15.0, 0.70), (20.0, 0.60), (25.0, 0.55), (30.0, 0.50)]


def sa_over_g(T, soil: str = "I") -> np.ndarray:
    """Sa/g of IS 1893 (Part 1):2016 for the response spectrum method, 5 % damping:
    1 + 15 T below 0.1 s, 2.5 up to the soil's corner, c/T up to 4 s, c/4 beyond."""
    if soil not in SOIL:
        raise ValueError(f"soil = {soil!r}: must be one of I, II, III")
    corner, c = SOIL[soil]
    T = np.asarray(T, dtype=float)
    if np.any(T < 0):
        raise ValueError("periods must be >= 0")
    return np.where(T < 0.10, 1.0 + 15.0 * T,
                    np.where(T <= corner, 2.5,
                             np.where(T <= 4.0, c / np.maximum(T, 1e-12), c / 4.0)))


def damping_factor(zeta: float) -> float:
    """Multiplying factor for damping ratio `zeta` (linear between the table's values)."""
    pct = 100.0 * zeta
    xs, ys = zip(*DAMPING_FACTORS)
    if not xs[0] <= pct <= xs[-1]:
        raise ValueError(f"damping = {pct} %: the code's table covers 0 to 30 %")
    return float(np.interp(pct, xs, ys))


def design_spectrum(T, zone: str = "V", soil: str = "I", level: str = "DBE",
                    zeta: float = 0.05) -> np.ndarray:
    """Design pseudo-acceleration (in g): (Z/2 for DBE, Z for MCE) x Sa/g x damping factor."""
    if zone not in ZONE_FACTORS:
        raise ValueError(f"zone = {zone!r}: must be one of II, III, IV, V")
    if level not in LEVELS:
        raise ValueError(f"level = {level!r}: must be DBE or MCE")
    z = ZONE_FACTORS[zone] * LEVELS[level]
    return z * sa_over_g(T, soil) * damping_factor(zeta)


def _cubic_peak(u0, v0, u1, v1, h):
    """Largest |p| on each step of the cubic Hermite through (u, v) at both ends
    (vectorized; the same rule as the engine's peaks between steps)."""
    b = h * v0
    c = 3.0 * (u1 - u0) - h * (2.0 * v0 + v1)
    d = 2.0 * (u0 - u1) + h * (v0 + v1)
    best = np.maximum(np.abs(u0), np.abs(u1))
    qa, qb, qc = 3.0 * d, 2.0 * c, b
    disc = qb * qb - 4.0 * qa * qc
    ok = disc >= 0.0
    root = np.sqrt(np.where(ok, disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        for r in ((-qb + root) / (2.0 * qa), (-qb - root) / (2.0 * qa), -qc / qb):
            inside = ok & np.isfinite(r) & (r > 0.0) & (r < 1.0)
            x = np.where(inside, r, 0.0)
            val = np.abs(u0 + x * (b + x * (c + x * d)))
            best = np.where(inside, np.maximum(best, val), best)
    return best


def response_spectrum(acc: np.ndarray, dt: float, periods, zeta: float = 0.05,
                      between_samples: bool = True):
    """(PSA, SD) of a record `acc` sampled every `dt` (linear between samples),
    from rest: SD = max |u| of u'' + 2 zeta w u' + w^2 u = -acc, PSA = w^2 SD
    (same units as `acc`). Exact recurrence (Nigam & Jennings), all periods at
    once.

    With `between_samples` (the default) the peak is the continuous one: each
    record step is split so that the shortest period has at least 10 sub-steps
    (the record stays linear, the recurrence exact), and the peak is sought on
    the cubic through each sub-step (the FMU's rule). Otherwise the peak is read
    at the record's samples only, which underestimates short periods."""
    if between_samples:
        split = max(1, int(np.ceil(10.0 * dt / float(np.min(periods)))))
        if split > 1:
            acc = np.asarray(acc, dtype=float)
            fine = np.interp(np.arange((len(acc) - 1) * split + 1) / split, np.arange(len(acc)), acc)
            return _spectrum(fine, dt / split, periods, zeta, True)
    return _spectrum(acc, dt, periods, zeta, between_samples)


def _spectrum(acc, dt, periods, zeta, between_samples):
    T = np.asarray(periods, dtype=float)
    w = 2.0 * np.pi / T
    wd = w * np.sqrt(1.0 - zeta * zeta)
    sq = np.sqrt(1.0 - zeta * zeta)
    e = np.exp(-zeta * w * dt)
    s, c = np.sin(wd * dt), np.cos(wd * dt)
    k = w * w
    A = e * (zeta / sq * s + c)
    B = e * s / wd
    C = (2 * zeta / (w * dt) + e * (((1 - 2 * zeta ** 2) / (wd * dt) - zeta / sq) * s
                                      - (1 + 2 * zeta / (w * dt)) * c)) / k
    D = (1 - 2 * zeta / (w * dt) + e * ((2 * zeta ** 2 - 1) / (wd * dt) * s + 2 * zeta / (w * dt) * c)) / k
    A1 = -e * (w / sq * s)
    B1 = e * (c - zeta / sq * s)
    C1 = (-1 / dt + e * ((w / sq + zeta / (dt * sq)) * s + c / dt)) / k
    D1 = (1 - e * (zeta / sq * s + c)) / (k * dt)
    u = np.zeros_like(T)
    v = np.zeros_like(T)
    peak = np.zeros_like(T)
    p = -np.asarray(acc, dtype=float)
    for i in range(len(p) - 1):
        u1 = A * u + B * v + C * p[i] + D * p[i + 1]
        v1 = A1 * u + B1 * v + C1 * p[i] + D1 * p[i + 1]
        if between_samples:
            np.maximum(peak, _cubic_peak(u, v, u1, v1, dt), out=peak)
        else:
            np.maximum(peak, np.abs(u1), out=peak)
        u, v = u1, v1
    return k * peak, peak
