"""Runs one ground motion through the FMU and writes, in --out:
response.csv (time histories), peaks.json and response.png (structure drift,
block slips, friction forces, a stick/slip timeline).

    python scripts/simulate.py [RECORD] [--set NAME=VALUE ...] [--out DIR] [--dt DT]

RECORD is a PEER .AT2 file (units of g) or a CSV `time,accel` (m/s2); without
it, the FMU's embedded default record is used. NAME is any FMU parameter, e.g.
--set nBlocks=3 --set "mus[2]=0.2".
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import use_venv  # noqa: E402,F401  (re-runs this script under the repository's .venv if needed)
import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from sll import DEFAULT_RECORD, Model, read_record  # noqa: E402


def parse_settings(items: list[str]) -> dict:
    params = {}
    for item in items:
        if "=" not in item:
            raise SystemExit(f"--set expects NAME=VALUE, got `{item}`")
        name, value = item.split("=", 1)
        params[name.strip()] = value.strip()
    return params


def typed(model: Model, params: dict) -> dict:
    out = {}
    for name, value in params.items():
        if name not in model.vars:
            raise SystemExit(f"unknown FMU variable `{name}`")
        kind = model.vars[name].type
        out[name] = float(value) if kind == "Real" else int(value) if kind == "Integer" else value
    return out


def scene_text(model: Model, params: dict, n_blocks: int) -> str:
    """The scene as the FMU ran it (its defaults and the --set values): period,
    damping, each block's mass ratio and friction."""
    def value(name):
        v = params.get(name, model.vars[name].start)
        return float(v)

    text = f"Tp {value('Tp'):g} s, zeta {value('zeta'):g}"
    if n_blocks:
        alphas = " + ".join(f"{value('alpha[%d]' % j):g}" for j in range(1, n_blocks + 1))
        mus = " / ".join(f"{value('mus[%d]' % j):g}" for j in range(1, n_blocks + 1))
        text += f"; {n_blocks} block(s), alpha {alphas}, mu {mus}"
    scale = value("recordScale") if "recordScale" in model.vars else 1.0
    return text + (f"; record x {scale:g}" if scale != 1.0 else "")


def plot(result: dict, title: str, path: Path, ground: tuple | None = None):
    """Ground motion (if given: time, accel in m/s2), drift, slips, friction forces and
    the stick/slip timeline, one panel each."""
    t, n = result["time"], result["nBlocks"]
    top = 1 if ground is not None else 0
    fig, axes = plt.subplots(4 + top, 1, figsize=(10, 12 if top else 10), sharex=True,
                             gridspec_kw={"height_ratios": [2] * top + [3, 3, 3, 1.2 + 0.3 * n]})
    if top:
        tg, ag = ground
        axes[0].plot(tg, ag / 9.81, color="tab:brown", lw=0.6)
        axes[0].set_ylabel("ground accel. (g)")
        k = int(np.argmax(np.abs(ag)))
        axes[0].set_title(f"ground motion: PGA {abs(ag[k]) / 9.81:.3f} g at {tg[k]:.2f} s", fontsize=9)
        axes = axes[1:]
    axes[0].plot(t, 1000 * result["up"], color="k", lw=0.8)
    axes[0].set_ylabel("structure drift up (mm)")
    for j in range(1, n + 1):
        axes[1].plot(t, 1000 * result[f"slip[{j}]"], lw=0.9, label=f"slip[{j}]")
        axes[2].plot(t, result[f"F[{j}]"] / 1000, lw=0.8, label=f"F[{j}]")
    axes[1].set_ylabel("slip on the body below (mm)")
    axes[2].set_ylabel("friction force (kN)")
    for ax in axes[1:3]:
        if n:
            ax.legend(loc="upper right", fontsize=8, ncol=min(n, 4))
    for j in range(1, n + 1):
        stuck = result[f"stuck[{j}]"]
        slipping = ~stuck
        # Bars where interface j slips.
        edges = np.flatnonzero(np.diff(np.r_[0, slipping.astype(int), 0]))
        spans = [(t[a], t[min(b, len(t) - 1)] - t[a]) for a, b in zip(edges[::2], edges[1::2])]
        axes[3].broken_barh(spans, (j - 0.4, 0.8), color="tab:red")
    axes[3].set_yticks(range(1, n + 1), [f"interface {j}" for j in range(1, n + 1)])
    axes[3].set_ylim(0.4, n + 0.6)
    axes[3].set_ylabel("slipping")
    axes[3].set_xlabel("time (s)")
    for ax in fig.axes:
        ax.grid(alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("record", nargs="?", help="AT2 or CSV file; default: the FMU's embedded record")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--out", default="out/simulate", help="output folder (default out/simulate)")
    ap.add_argument("--dt", type=float, help="output step (default: the record's sample step)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with Model() as model:
        params = typed(model, parse_settings(args.set))
        record_path = Path(args.record) if args.record else Path(model.unzipdir) / "resources" / DEFAULT_RECORD
        t, ag = read_record(record_path, float(params.get("g", 9.81)))
        dt = args.dt or float(t[1] - t[0])
        print(f"{record_path.name}: {len(t)} samples, {t[-1]:.2f} s; output every {dt} s", flush=True)
        result = model.run(args.record, params, dt=dt)
        scene = scene_text(model, params, result["nBlocks"])
        print(f"scene: {scene}", flush=True)
        ag = ag * float(params.get("recordScale", 1.0))
    names = ["time"] + [k for k in result if isinstance(result[k], np.ndarray) and k != "time"]
    with open(out / "response.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(names)
        cols = [result[k].astype(float) for k in names]
        for row in zip(*cols):
            w.writerow([f"{x:.9g}" for x in row])
    peaks = {"record": str(args.record or DEFAULT_RECORD), **result["peaks"], "params": params}
    (out / "peaks.json").write_text(json.dumps(peaks, indent=2) + "\n")
    plot(result, f"{scene}\nunder {record_path.name}: peak drift {1000 * peaks['peakUp']:.1f} mm",
         out / "response.png", ground=(t, ag))
    print(f"peak |up| {peaks['peakUp']:.5f} m, events {peaks['nEvents']}; wrote {out}/response.csv, "
          f"peaks.json, response.png")


if __name__ == "__main__":
    main()
