"""Issue #15: the advisor (asymmetric rule, per-record spread, friction sweep, slips,
effective seismic-mass fraction) and the physics of intensity levels.

Records are fresh seeded broadband synthetics (random-phase sinusoids 0.3-8 Hz
under a trapezoid envelope), written per test session. Expected values come from
identities of ../shared/MODEL.md (mu -> infinity is the rigid attachment, mu = 0
leaves the bare structure, a stack whose upper interface cannot slip is the
single block), from the homogeneity of the equations of motion (records x F
with every mu x F give every displacement x F: exactly, since F = 2 is a power
of two), and from independent FMU runs of the models the advisor reports on."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
import advise  # noqa: E402
import sll  # noqa: E402
import study  # noqa: E402
from sll import study_tasks  # noqa: E402

G = 9.81


def broadband(path: Path, seed: int, pga_g: float, duration: float = 12.0, dt: float = 0.01) -> Path:
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, dt)
    freqs = rng.uniform(0.3, 8.0, 80)
    phases = rng.uniform(0.0, 2 * np.pi, 80)
    a = np.sum(np.sin(2 * np.pi * freqs[:, None] * t + phases[:, None]) / np.sqrt(freqs[:, None]), axis=0)
    a *= np.clip(t / 1.5, 0, 1) * np.clip((duration - t) / 4.0, 0, 1)
    a *= pga_g * G / np.max(np.abs(a))
    np.savetxt(path, np.c_[t, a], delimiter=",", header="time,accel", comments="", fmt="%.10g")
    return path


@pytest.fixture(scope="module")
def records(tmp_path_factory) -> list[Path]:
    sll.fmu_path()
    folder = tmp_path_factory.mktemp("advise_records")
    return [broadband(folder / f"rec{seed}.csv", seed, pga) for seed, pga in ((11, 0.35), (12, 0.25), (13, 0.45),
                                                                             (14, 0.3), (15, 0.4))]


def run(records, tp, alphas, mus, **kw):
    return advise.advise(records, tp, 0.05, alphas, mus, kw.pop("muks", mus), **kw)


def test_the_rule_is_asymmetric_and_says_which_way_and_by_how_much():
    one = (1.0, 1.0)
    # 4 % below the stack: rejected by default, accepted with a 5 % allowance.
    ok, why = advise.judge(0.96, 0.96, one, 0.25, 0.0, 0.0)
    assert not ok and "unconservative by 4.0 %" in why and "allowed below the stack: 0 %" in why
    ok, why = advise.judge(0.96, 0.96, one, 0.25, 0.05, 0.0)
    assert ok and "unconservative by 4.0 %" in why
    # 24 % above: accepted within a 25 % cost tolerance, rejected within 20 %.
    ok, why = advise.judge(1.24, 1.24, one, 0.25, 0.0, 0.0)
    assert ok and "conservative by 24.0 %" in why
    ok, why = advise.judge(1.24, 1.24, one, 0.20, 0.0, 0.0)
    assert not ok and "cost tolerance 20 %" in why
    # Conservative at the nominal friction, 2 % below the stack at its worst point of the box: rejected,
    # and it says where.
    ok, why = advise.judge(1.10, 0.98, (0.7, 1.3), 0.25, 0.0, 0.3)
    assert not ok and "unconservative by 2.0 % (mu factors 0.7 1.3)" in why
    # Differences within the engine's accuracy (1e-6) count as equal.
    ok, why = advise.judge(1 - 1e-9, 1 - 1e-9, one, 0.0, 0.0, 0.0)
    assert ok and "equal to the stack" in why
    # 0.5 % above the stack at the worst point found, but the search cannot rule out 0.7 % more
    # (its margin): rejected, and it says so.
    ok, why = advise.judge(1.10, 1.005, (0.85, 0.7), 0.25, 0.0, 0.3, margin=0.012)
    assert not ok and "cannot rule out 0.70 % below the stack" in why, why
    ok, why = advise.judge(1.10, 1.005, (0.85, 0.7), 0.25, 0.0, 0.3, margin=0.004)
    assert ok and "search margin 0.40 %" in why, why


def test_friction_sweep_points():
    assert advise.sweep_factors(1, 0.3, 5) == [(0.7,), (0.85,), (1.0,), (1.15,), (1.3,)]
    two = advise.sweep_factors(2, 0.3, 3)
    assert two == [(0.7, 0.7), (1.0, 1.0), (1.3, 1.3), (1.3, 0.7), (0.7, 1.3)]
    assert len(advise.sweep_factors(8, 0.3, 5)) == 5 + 2 * 7
    assert advise.sweep_factors(3, 0.0, 5) == [(1.0, 1.0, 1.0)]
    assert (1.0, 1.0) in advise.sweep_factors(2, 0.2, 4)  # nominal always included


def test_a_rigidly_attached_load_is_linear_mce_drift_is_twice_dbe(records):
    # Linear SDOF under records x 2: every displacement x 2, exactly (x 2 is exact in floating point).
    for tp in (0.2, 0.9, 2.5):
        p = study_tasks.rigid_params(tp, 0.6)
        for r in records[:2]:
            dbe = study_tasks.peaks(str(r), p)["peakUp"]
            mce = study_tasks.peaks(str(r), {**p, "recordScale": 2.0})["peakUp"]
            assert mce == pytest.approx(2 * dbe, rel=1e-12), (tp, r.name)
    assert study.intensity("MCE") == ("MCE", 2.0)
    assert study.intensity("DBE", 1.5) == ("DBE x 1.5", 1.5)
    assert study.level_factor("MCE x 0.5") == 1.0
    with pytest.raises(ValueError, match="level"):
        study.intensity("SLE")


def test_a_sliding_stack_at_twice_the_records_and_twice_the_friction_drifts_exactly_twice(records):
    # The equations are homogeneous in (ground motion, friction): the dimensionless
    # axis mu g / Sa on which zones and levels collapse.
    for tp in (0.3, 1.2):
        p1 = study_tasks.stack_params(tp, [0.3, 0.2], [0.1, 0.05])
        p2 = study_tasks.stack_params(tp, [0.3, 0.2], [0.2, 0.1])
        for r in records[:2]:
            a = study_tasks.peaks(str(r), p1)
            b = study_tasks.peaks(str(r), {**p2, "recordScale": 2.0})
            assert a["peakSlip2"] > 0.01, "the upper block slides"
            for k in ("peakUp", "peakSlip1", "peakSlip2"):
                assert b[k] == pytest.approx(2 * a[k], rel=1e-12), (tp, k)


def test_huge_friction_the_rigid_attachment_wins_and_the_fraction_is_one(records):
    r = run(records, 0.6, [0.3, 0.2], [50.0, 50.0])
    # Never sliding, the stack is the rigid SDOF (integrated to ~1e-9).
    assert r["models"]["rigid"]["direction"] == "equal"
    assert r["verdict"] == "rigid", r["models"]["rigid"]["reason"]
    f = r["effective_mass_fraction"]
    assert f["mean"] == pytest.approx(1.0, abs=1e-3)
    assert np.allclose(f["per_record"]["values"], 1.0, atol=1e-3)


def test_zero_friction_the_bare_structure_wins_and_the_fraction_is_zero(records):
    r = run(records, 0.6, [0.3, 0.2], [0.0, 0.0])
    # Free blocks leave the bare structure (MODEL.md); single is the same.
    for m in ("bare", "single"):
        assert r["models"][m]["direction"] == "equal", r["models"][m]
    assert r["verdict"] == "bare"
    assert r["effective_mass_fraction"]["mean"] == pytest.approx(0.0, abs=1e-3)
    # The rigid model is far above the stack (more mass, longer period on these records),
    # so with no cost allowed it is rejected and says so.
    strict = run(records, 0.6, [0.3, 0.2], [0.0, 0.0], cost_tol=0.0)
    rigid = strict["models"]["rigid"]
    assert rigid["direction"] != "equal" and not rigid["accepted"]
    assert strict["verdict"] == "bare"


def test_an_upper_interface_that_cannot_slip_makes_the_single_block_exact(records):
    # mu2 > mu1 at every sweep point (0.13 < 0.21 at the worst split): the upper
    # block rides on the lower one, the stack is the single block.
    r = run(records, 0.4, [0.5, 0.5], [0.1, 0.3], cost_tol=0.02)
    single = r["models"]["single"]
    assert all(abs(x - 1) < 1e-9 for x in single["friction_sweep"]["ratios"]), single
    assert single["accepted"]
    assert not r["models"]["rigid"]["accepted"] and not r["models"]["bare"]["accepted"], r["models"]
    assert r["verdict"] == "single"


def test_equal_friction_is_probed_by_the_sweep_and_the_stack_wins_when_every_simpler_model_fails(records):
    # mu2 = mu1: the single block is exact at the nominal friction; at the split (mu1 x 1.3,
    # mu2 x 0.7) the upper block slides and its dissipation lowers the stack's drift (single
    # above it); but where mu2 is only a little below mu1 (found by the box search near mu x
    # (0.74, 0.73)) the stack drifts a little more than the single block: rejected with no
    # allowance, accepted with 1 % (issue #25: the whole box, not named points).
    r = run(records, 0.4, [0.5, 0.5], [0.2, 0.2], cost_tol=0.0)
    single = r["models"]["single"]
    assert abs(single["ratio_to_stack"] - 1) < 1e-9
    split = [p["factors"] for p in r["friction_sweep"]].index([1.3, 0.7])
    assert single["friction_sweep"]["ratios"][split] > 1 + 1e-3
    worst = single["friction_sweep"]["worst_ratio"]
    assert 0.99 < worst < 1 - 1e-6 and not single["accepted"], single["reason"]
    f = single["friction_sweep"]["worst_at_factors"]
    m = [0.2 * f[0], 0.2 * f[1]]
    u = [np.mean([study_tasks.peaks(str(rec), p)["peakUp"] for rec in records])
         for p in (study_tasks.single_params(0.4, 1.0, m[0]), study_tasks.stack_params(0.4, [0.5, 0.5], m))]
    assert worst == pytest.approx(u[0] / u[1], rel=1e-12)  # independent runs at the reported point
    assert r["verdict"] == "stack"
    loose = run(records, 0.4, [0.5, 0.5], [0.2, 0.2], cost_tol=0.0, unconservative_tol=0.01)
    assert loose["verdict"] == "single" and "equal to the stack at the nominal friction" in loose["models"]["single"]["reason"]
    # A stack whose upper block slides at every point: nothing simpler is equal.
    r = run(records, 0.5, [0.3, 0.3], [0.3, 0.05], cost_tol=0.0)
    assert r["verdict"] == "stack", {m: r["models"][m]["reason"] for m in advise.SIMPLER}
    assert all(not r["models"][m]["accepted"] for m in advise.SIMPLER)


def test_spread_sweep_slips_and_fraction_agree_with_independent_runs(records):
    alphas, mus, tp = [0.3, 0.2], [0.3, 0.1], 1.0
    r = run(records, tp, alphas, mus, max_slip=[1.0, 0.01])
    per = r["per_record"]
    for m in advise.SIMPLER:
        x = r["models"][m]
        ratios = np.array(per[m]) / np.array(per["stack"])
        assert np.allclose(x["per_record"]["ratios"], ratios, rtol=1e-15)
        assert x["per_record"]["unconservative_records"] == int(np.sum(ratios < 1 - 1e-6))
        pr = x["per_record"]
        assert pr["min"] <= pr["p10"] <= pr["p50"] <= pr["p90"] <= pr["max"]
        assert x["ratio_to_stack"] == pytest.approx(np.mean(per[m]) / np.mean(per["stack"]), rel=1e-15)
        # The box's worst is at or below every named point of the box (they are in it).
        assert x["friction_sweep"]["worst_ratio"] <= min(x["friction_sweep"]["ratios"]) + 1e-15
    # The sweep point mu x 1.3 against a direct run.
    k = [p["factors"] for p in r["friction_sweep"]].index([1.3, 1.3])
    direct = [study_tasks.peaks(str(rec), study_tasks.stack_params(tp, alphas, [1.3 * m for m in mus]))
              for rec in records]
    assert r["friction_sweep"][k]["u_stack"] == pytest.approx(np.mean([d["peakUp"] for d in direct]), rel=1e-12)
    # Slips: the FMU's peak slips per record; block 2 beyond 1 cm slides off, block 1 within 1 m does not.
    nominal = [study_tasks.peaks(str(rec), study_tasks.stack_params(tp, alphas, mus)) for rec in records]
    assert np.allclose(per["peak_slips"], [[d["peakSlip1"], d["peakSlip2"]] for d in nominal], rtol=1e-15)
    b1, b2 = r["peak_slips"]["blocks"]
    assert not b1["slides_off"] and b2["slides_off"] and b2["records_beyond"] >= 1
    assert any("block 2 slides off" in w for w in r["warnings"])
    assert not any("block 1" in w for w in r["warnings"])
    # Effective fraction: the rigid model with that share of the live load gives the
    # stack's mean drift (root tolerance 1e-4 on the fraction -> 1e-3 on the drift).
    f = r["effective_mass_fraction"]
    assert f["status"] == "found" and 0.0 <= f["mean"] <= 1.0
    u = np.mean([study_tasks.peaks(str(rec), study_tasks.rigid_params(tp, f["mean"] * 0.5))["peakUp"]
                 for rec in records])
    assert u == pytest.approx(r["mean_peak_drift"]["stack"], rel=1e-3)
    for rec, value, stack in zip(records, f["per_record"]["values"], per["stack"]):
        if 0.0 < value < advise.FRACTION_MAX:
            got = study_tasks.peaks(str(rec), study_tasks.rigid_params(tp, value * 0.5))["peakUp"]
            assert got == pytest.approx(stack, rel=1e-3), rec.name
    assert f["friction_sweep"]["min"] <= f["mean"] <= f["friction_sweep"]["max"]


def test_the_command_line_writes_json_report_and_png_and_rejects_bad_input(records, tmp_path, capsys):
    folder = records[0].parent
    out, png = tmp_path / "advice.json", tmp_path / "advice.png"
    assert advise.main(["--Tp", "0.5", "--alpha", "0.2", "0.1", "0.1", "--mu", "0.2", "0.15", "0.1",
                        "--muk", "0.15", "0.1", "0.1", "--records", str(folder), "--scale", "1.5",
                        "--max-slip", "0.05", "--json", str(out), "--png", str(png)]) == 0
    text = capsys.readouterr().out
    for phrase in ("Advice", "Effective seismic-mass fraction", "Block 3", "x 1.5"):
        assert phrase in text, phrase
    r = json.loads(out.read_text(), parse_constant=lambda c: pytest.fail(f"{c} in the JSON"))
    assert r["verdict"] in ("bare", "rigid", "single", "stack", "slides-off") and r["record_scale"] == 1.5
    assert r["model_verdict"] in ("bare", "rigid", "single", "stack") and len(r["codes"]) == 3
    assert len(r["friction_sweep"]) == 5 + 2 * 2
    assert png.stat().st_size > 20_000
    for args, message in ((["--max-slip", "-1"], "--max-slip"), (["--level", "MCE"], "--level applies"),
                          (["--mu", "0.1", "0.1"], "one --alpha"), (["--muk", "0.5", "0.5", "0.5"], "--muk"),
                          (["--Tp", "0"], "--Tp")):
        base = {"--Tp": ["0.5"], "--alpha": ["0.2", "0.1", "0.1"], "--mu": ["0.2", "0.15", "0.1"]}
        base.update({args[0]: args[1:]})
        argv = [x for k, v in base.items() for x in (k, *v)] + ["--records", str(folder)]
        with pytest.raises(SystemExit):
            advise.main(argv)
        assert message in capsys.readouterr().err, args
    assert math.isfinite(r["effective_mass_fraction"]["mean"])
    # --tol, the old symmetric tolerance's name, now sets the cost tolerance.
    assert advise.main(["--Tp", "0.5", "--alpha", "0.3", "--mu", "0.2", "--records", str(folder), "--tol", "0.1",
                        "--mu-uncertainty", "0", "--json", str(out)]) == 0
    r = json.loads(out.read_text())
    assert r["rule"]["cost_tolerance"] == 0.1 and len(r["friction_sweep"]) == 1


def test_a_bad_record_in_the_folder_is_named_with_its_line(tmp_path, capsys):
    # Expected: an argparse error naming the file, the line and the bad text, not a traceback.
    (tmp_path / "ok.csv").write_text("time,accel\n0,0\n0.01,0.5\n0.02,0\n")
    (tmp_path / "bad.csv").write_text("time,accel\n0,0\n0.01,abc\n")
    with pytest.raises(SystemExit):
        advise.main(["--Tp", "0.5", "--alpha", "0.3", "--mu", "0.2", "--records", str(tmp_path)])
    err = capsys.readouterr().err
    assert "--records:" in err and "bad.csv:3" in err and "0.01,abc" in err, err
