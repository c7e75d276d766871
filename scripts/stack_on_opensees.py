"""A stack of two blocks on floor 2 of a three-storey shear frame in OpenSees
(openseespy), under El Centro, coupled by each master of sll.cosim
(docs/stack-on-a-floor.md). Writes into --out:
- coupling_error.csv / coupling_error.md: error against the macro step H for
  each master (Jacobi, Gauss-Seidel, interface-Jacobian), linear frame and
  frame with a yielding first storey;
- checks.md: the interface-Jacobian master against exact references (blocks
  that cannot slip: the monolithic frame; one storey: the storey FMU);
- drifts_slips.png: storey drifts and block slips, and the error against H.

    python scripts/stack_on_opensees.py [--out out/stack_on_opensees] [--quick]

The frame: three floors of 100 t, storey stiffness for a first period of
0.5 s, storey dashpots giving 5 % damping in the first mode (stiffness
proportional); the yielding variant's first storey is Steel01 (Fy = 25 % of
the frame's weight, 2 % hardening). The stack: 15 t + 10 t (25 % of the floor's
mass) on floor 2, mus/muk 0.30/0.25 below block 1, 0.20/0.15 between the
blocks. El Centro 1940 (RSN6, ELC180, PGA 0.31 g), unscaled, its first 15 s
(--duration). OpenSees integrates with Newmark (average acceleration) in
steps of 0.1 ms (H split evenly) in every run, and the reference of the error
table is the interface-Jacobian master at H = 0.1 ms (self-convergence): the
reference and the runs take the same analysis steps except around switch
landings, so that Newmark's own error (a phase error of (w dt)^2/12 per
radian, 2e-6 for the third mode at 0.1 ms) largely cancels and the table
shows the coupling's.
"""

from __future__ import annotations

import argparse
import csv
import math
import time
from pathlib import Path

import use_venv  # noqa: F401  (re-runs this script under the repository's .venv if needed)
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import sll  # noqa: E402
from sll import ROOT, opensees_block, read_record  # noqa: E402
from sll.cosim import CoSimulation, FMUPartner, OpenSeesPartner  # noqa: E402
from sll.coupling import observed_order, write_record_csv  # noqa: E402

RECORD = ROOT.parent / "shared" / "ground_motions" / "RSN6_IMPVALL.I_I-ELC180.AT2"
STACK_FMU = ROOT / "target" / "fmu" / "StackOnFloor.fmu"
FLOOR_MASS = 1.0e5  # kg
T1, ZETA = 0.5, 0.05
FY_RATIO, HARDENING = 0.25, 0.02  # yielding first storey: Fy / weight of the frame, Steel01 b
STACK = {"nBlocks": 2, "m[1]": 15000.0, "m[2]": 10000.0,
         "mus[1]": 0.30, "muk[1]": 0.25, "mus[2]": 0.20, "muk[2]": 0.15}
DT_FRAME = 0.0001  # OpenSees' analysis step (at most)
H_REF = 0.0001  # = DT_FRAME: the reference and the runs share OpenSees' analysis steps (but near landings)
STEPS = [0.0005, 0.001, 0.002, 0.005, 0.01, 0.02]
MASTERS = [  # label, master, extrapolation
    ("Jacobi, hold", "jacobi", "constant"),
    ("Jacobi, linear", "jacobi", "linear"),
    ("Gauss-Seidel (frame first), linear", "gauss-seidel", "linear"),
    ("interface-Jacobian", "interface-jacobian", "linear"),
]
FLOOR = "floor2"
RECORDED = ["frame.floor1.disp", "frame.floor2.disp", "frame.floor3.disp", "stack.slip[1]", "stack.slip[2]"]


def shear_frame(n: int, mass: float, t1: float, zeta: float):
    """Storey stiffness k (the same in every storey) for a first period t1, and
    stiffness-proportional storey dashpots c = 2 zeta k / w1."""
    a = 2 * np.eye(n) - np.eye(n, k=1) - np.eye(n, k=-1)
    a[-1, -1] = 1.0
    lam = float(np.min(np.linalg.eigvalsh(a)))
    w1 = 2 * math.pi / t1
    k = mass * w1 ** 2 / lam
    return k, 2 * zeta * k / w1


def builder(n: int, masses, k: float, c: float, fy: float | None = None):
    """The openseespy model: node 0 fixed, nodes 1..n with masses, storey i a
    zeroLength element (spring, Elastic or Steel01, and Viscous dashpot)."""
    def build():
        import openseespy.opensees as ops

        ops.model("basic", "-ndm", 1, "-ndf", 1)
        ops.node(0, 0.0)
        ops.fix(0, 1)
        for i in range(n):
            ops.node(i + 1, 0.0, "-mass", float(masses[i]))
            if fy is not None and i == 0:
                ops.uniaxialMaterial("Steel01", 10 + i, fy, k, HARDENING)
            else:
                ops.uniaxialMaterial("Elastic", 10 + i, k)
            ops.uniaxialMaterial("Viscous", 20 + i, c, 1.0)
            ops.element("zeroLength", i + 1, i, i + 1, "-mat", 10 + i, 20 + i, "-dir", 1, 1)
    return build


def frame_partner(ground, yielding: bool, n: int = 3, added: float = 0.0):
    k, c = shear_frame(n, FLOOR_MASS, T1, ZETA)
    masses = [FLOOR_MASS] * n
    if added:
        masses[1 if n > 1 else 0] += added
    fy = FY_RATIO * n * FLOOR_MASS * 9.81 if yielding else None
    floors = {f"floor{i + 1}": i + 1 for i in range(n)}
    return OpenSeesPartner("frame", builder(n, masses, k, c, fy), floors, ground=ground, dt_max=DT_FRAME)


def couple(ground, yielding: bool, master: str, extrapolation: str, H: float, stack_params=STACK,
           n: int = 3, floor: str = FLOOR) -> dict:
    frame = frame_partner(ground, yielding, n)
    stack = FMUPartner("stack", STACK_FMU, stack_params)
    links = [("stack.floorForce", f"frame.{floor}.force", +1, "N"), (f"frame.{floor}.accel", "stack.ag", +1, "m/s2")]
    sim = CoSimulation([frame, stack], links)
    record = [r for r in RECORDED if int(r[11]) <= n] if n < 3 else RECORDED
    try:
        run = sim.run(float(ground[0][-1]), H, master=master, extrapolation=extrapolation,
                      order=["frame", "stack"], record=record, consistent=False)
        run["peakSlip"] = [stack.get(f"peakSlip[{j}]") for j in (1, 2)]
        run["failed"] = ""
    except RuntimeError as e:
        run = {"failed": str(e)}
    finally:
        stack.close()
        frame.close()
    return run


def drifts(run: dict, n: int = 3) -> np.ndarray:
    x = np.array([run[f"frame.floor{i}.disp"][run["on_grid"]] for i in range(1, n + 1)])
    return x - np.vstack([np.zeros(x.shape[1]), x[:-1]])


def errors(run: dict, ref: dict) -> dict:
    """Drift history error (largest over storeys and grid points, relative to
    the largest reference drift), peak drift error (largest over storeys,
    relative to each storey's peak) and peak slip error (largest over blocks,
    relative to the largest peak slip: a block may not slip at all), against
    `ref` on the run's grid."""
    if run["failed"]:
        return {"drift": math.inf, "peak_drift": math.inf, "peak_slip": math.inf}
    d = drifts(run)
    tr = ref["time"][ref["on_grid"]]
    dr = np.array([np.interp(run["time"][run["on_grid"]], tr, row) for row in drifts(ref)])
    if not np.all(np.isfinite(d)):
        return {"drift": math.inf, "peak_drift": math.inf, "peak_slip": math.inf}
    peak_ref = np.max(np.abs(drifts(ref)), axis=1)
    return {"drift": float(np.max(np.abs(d - dr)) / np.max(peak_ref)),
            "peak_drift": float(np.max(np.abs(np.max(np.abs(d), axis=1) - peak_ref) / peak_ref)),
            "peak_slip": float(max(abs(p - q) for p, q in zip(run["peakSlip"], ref["peakSlip"]))
                               / max(ref["peakSlip"]))}


def fmt(x: float) -> str:
    return "diverged" if not math.isfinite(x) else f"{x:.2g}"


def checks(ground, out: Path) -> list[str]:
    """The interface-Jacobian master against exact references."""
    lines = ["# Checks of the interface-Jacobian master against exact references", ""]
    # 1. Blocks that cannot slip: the monolithic frame with their mass on floor 2.
    rigid = {**STACK, **{f"{q}[{j}]": 50.0 for q in ("mus", "muk") for j in (1, 2)}}
    mono = frame_partner(ground, False, added=rigid["m[1]"] + rigid["m[2]"])
    ref = CoSimulation([mono], []).run(float(ground[0][-1]), 0.005, record=RECORDED[:3])
    mono.close()
    ref["peakSlip"] = [1.0, 1.0]
    run = couple(ground, False, "interface-jacobian", "linear", 0.005, rigid)
    err = errors(run, ref)
    lines.append(f"- Blocks that cannot slip (mu = 50), linear frame, H = 5 ms: drift error "
                 f"{err['drift']:.2g} of the peak against the monolithic OpenSees frame with the blocks' "
                 f"25 t on floor 2 (same analysis steps); largest slip {np.max(np.abs(run['stack.slip[1]'])):.2g} m.")
    # 2. One storey: the exact SDOF + stack, the storey FMU.
    k, c = shear_frame(1, FLOOR_MASS, T1, ZETA)
    csv_path = write_record_csv(*ground, out / "ground.csv")
    storey = FMUPartner("storey", sll.FMU_PATH, {
        "recordFile": str(csv_path.resolve()), "nBlocks": 2, "mp": FLOOR_MASS, "Tp": T1, "zeta": ZETA,
        "alpha[1]": STACK["m[1]"] / FLOOR_MASS, "alpha[2]": STACK["m[2]"] / FLOOR_MASS,
        **{f"{q}[{j}]": STACK[f"{q}[{j}]"] for q in ("mus", "muk") for j in (1, 2)}})
    exact = CoSimulation([storey], []).run(float(ground[0][-1]), 0.0005, record=["storey.up"])
    exact_slips = [storey.get(f"peakSlip[{j}]") for j in (1, 2)]
    storey.close()
    peak_up = np.max(np.abs(exact["storey.up"]))
    lines.append(f"- One storey (100 t, T = 0.5 s, 5 %; c = 2 zeta sqrt(k m) as the storey FMU), the "
                 "same stack on it, against the storey FMU StackedLiveLoad.fmu carrying it (exact "
                 f"switches; peak drift {peak_up * 1000:.2f} mm, peak slips "
                 f"{exact_slips[0] * 1000:.1f} / {exact_slips[1] * 1000:.1f} mm). OpenSees' Newmark at "
                 f"{DT_FRAME * 1000} ms has an error of its own, (w dt)^2 / 12 = "
                 f"{(2 * math.pi / T1 * DT_FRAME) ** 2 / 12:.1g} in phase per radian:")
    lines.append("")
    lines.append("| H (ms) | drift error (of peak) | peak drift error | peak slip error (worst block) |")
    lines.append("| --- | --- | --- | --- |")
    one = []
    for H in (0.005, 0.002, 0.001, 0.0005):
        frame = OpenSeesPartner("frame", builder(1, [FLOOR_MASS], k, 2 * ZETA * math.sqrt(k * FLOOR_MASS)),
                                {"floor1": 1}, ground=ground, dt_max=DT_FRAME)
        stack = FMUPartner("stack", STACK_FMU, STACK)
        sim = CoSimulation([frame, stack], [("stack.floorForce", "frame.floor1.force", +1, "N"),
                                            ("frame.floor1.accel", "stack.ag", +1, "m/s2")])
        r = sim.run(float(ground[0][-1]), H, master="interface-jacobian", record=["frame.floor1.disp"])
        g = r["on_grid"]
        d = r["frame.floor1.disp"][g]
        want = np.interp(r["time"][g], exact["time"], exact["storey.up"])
        slips = [stack.get(f"peakSlip[{j}]") for j in (1, 2)]
        e = (float(np.max(np.abs(d - want)) / peak_up), abs(np.max(np.abs(d)) / peak_up - 1),
             max(abs(p - q) / q for p, q in zip(slips, exact_slips)))
        one.append(e)
        lines.append(f"| {H * 1000:g} | {e[0]:.2g} | {e[1]:.2g} | {e[2]:.2g} |")
        stack.close()
        frame.close()
    lines.append("")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="out/stack_on_opensees")
    ap.add_argument("--duration", type=float, default=15.0, help="seconds of the record (default 15)")
    ap.add_argument("--quick", action="store_true", help="5 s, three steps, linear frame only")
    args = ap.parse_args()
    if opensees_block.available() is not None:
        raise SystemExit(f"openseespy does not import: {opensees_block.available()}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t, ag = read_record(RECORD)
    duration = 5.0 if args.quick else args.duration
    keep = t <= duration + 1e-9
    ground = (t[keep], ag[keep])
    steps = [0.001, 0.002, 0.005] if args.quick else STEPS
    frames = [("linear", False)] if args.quick else [("linear", False), ("yielding", True)]
    started = time.perf_counter()
    rows, refs, samples = [], {}, {}
    for name, yielding in frames:
        ref = couple(ground, yielding, "interface-jacobian", "linear", H_REF)
        if ref["failed"]:
            raise SystemExit(f"the reference run failed: {ref['failed']}")
        refs[name] = ref
        print(f"{name} frame: reference (interface-Jacobian, H = {H_REF * 1000} ms): peak drifts "
              f"{np.max(np.abs(drifts(ref)), axis=1) * 1000} mm, peak slips {np.array(ref['peakSlip']) * 1000} mm, "
              f"{ref['landings']} landings", flush=True)
        for label, master, extrapolation in MASTERS:
            for H in steps:
                run = couple(ground, yielding, master, extrapolation, H)
                err = errors(run, ref)
                rows.append({"frame": name, "master": label, "H_ms": H * 1000, **err,
                             "landings": run.get("landings", ""), "seconds": round(run.get("seconds", 0.0), 2),
                             "failed": run["failed"][:120]})
                if master == "interface-jacobian" and abs(H - 0.005) < 1e-12:
                    samples[name] = run
                print(f"  {label:36s} H = {H * 1000:5.2f} ms: drift {fmt(err['drift'])}, peak drift "
                      f"{fmt(err['peak_drift'])}, peak slip {fmt(err['peak_slip'])}", flush=True)
    with open(out / "coupling_error.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    md = ["# Coupling error against H: a two-block stack on floor 2 of a 3-storey OpenSees frame, El Centro",
          "", f"Reference: interface-Jacobian master at H = {H_REF * 1000} ms; OpenSees at {DT_FRAME * 1000} ms "
          f"in every run; first {duration:g} s of RSN6 ELC180, unscaled. Errors: drift history (largest over "
          "storeys and time, of the largest drift) / peak drift (worst storey) / peak slip (worst block).", ""]
    md.append("| frame | master | " + " | ".join(f"H = {H * 1000:g} ms" for H in steps) + " | order (drift) |")
    md.append("| --- | --- | " + " | ".join("---" for _ in steps) + " | --- |")
    orders = {}
    for name, _ in frames:
        for label, master, _ in MASTERS:
            sel = [r for r in rows if r["frame"] == name and r["master"] == label]
            cells = [f"{fmt(r['drift'])} / {fmt(r['peak_drift'])} / {fmt(r['peak_slip'])}" for r in sel]
            small = [(r["H_ms"] / 1000, r["drift"]) for r in sel if r["H_ms"] <= 5.0 and math.isfinite(r["drift"]) and r["drift"] > 0]
            order = observed_order(*zip(*small)) if len(small) >= 3 else math.nan
            orders[(name, label)] = order
            md.append(f"| {name} | {label} | " + " | ".join(cells) + f" | {order:.2f} |")
    md += ["", f"Order: least-squares slope of log(drift error) against log(H) over H <= 5 ms. "
           f"Wall time of the whole script: {time.perf_counter() - started:.0f} s.", ""]
    (out / "coupling_error.md").write_text("\n".join(md))
    if not args.quick:
        (out / "checks.md").write_text("\n".join(checks(ground, out)))
    plot(out, frames, refs, samples, rows, steps)
    print((out / "coupling_error.md").read_text())
    if (out / "checks.md").exists():
        print((out / "checks.md").read_text())
    print(f"wrote {out}/coupling_error.csv, coupling_error.md, drifts_slips.png"
          + (", checks.md" if not args.quick else ""))


def plot(out: Path, frames, refs, samples, rows, steps):
    name = frames[-1][0]
    ref, run = refs[name], samples.get(name)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    tr = ref["time"][ref["on_grid"]]
    for i, d in enumerate(drifts(ref)):
        axes[0].plot(tr, d * 1000, lw=0.8, label=f"storey {i + 1}")
    if run is not None:
        axes[0].plot(run["time"][run["on_grid"]], drifts(run)[0] * 1000, "k:", lw=0.8, label="storey 1, H = 5 ms")
    axes[0].set(xlabel="time (s)", ylabel="drift (mm)", title=f"{name} frame: storey drifts")
    axes[0].legend(fontsize=7)
    for j in (1, 2):
        axes[1].plot(ref["time"], ref[f"stack.slip[{j}]"] * 1000, lw=0.8, label=f"block {j}")
    if run is not None:
        axes[1].plot(run["time"], run["stack.slip[1]"] * 1000, "k:", lw=0.8, label="block 1, H = 5 ms")
    axes[1].set(xlabel="time (s)", ylabel="slip (mm)", title="slips on floor 2 (interface-Jacobian)")
    axes[1].legend(fontsize=7)
    for fname, style in zip([f[0] for f in frames], ["-", "--"]):
        for (label, _, _), color in zip(MASTERS, ["C3", "C1", "C2", "C0"]):
            sel = [r for r in rows if r["frame"] == fname and r["master"] == label]
            e = [min(r["drift"], 10.0) if math.isfinite(r["drift"]) else 10.0 for r in sel]
            axes[2].loglog([r["H_ms"] for r in sel], e, style, color=color, marker="o", ms=3,
                           label=f"{label} ({fname})")
    axes[2].set(xlabel="H (ms)", ylabel="drift error / peak drift", title="coupling error against H")
    axes[2].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(out / "drifts_slips.png", dpi=120)


if __name__ == "__main__":
    main()
