"""Issue #6: the parametric study, the advisor and the section-4 validation.
Expected values: identities of ../shared/MODEL.md (a stack whose upper interface
cannot slip is the single block; mu -> infinity is the rigid attachment) and
RESEARCH.md §3 (DRR at mu = 0 is a ratio of exact spectral displacements)."""

from __future__ import annotations

import csv
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
import advise  # noqa: E402
import seismic  # noqa: E402
import sll  # noqa: E402
import study  # noqa: E402
import study_tasks  # noqa: E402
import validate  # noqa: E402


@pytest.fixture(scope="module")
def quick(tmp_path_factory) -> Path:
    sll.build_fmu()
    out = tmp_path_factory.mktemp("study_local")
    assert study.main(["--out", str(out), "--quick", "--workers", "2"]) == 0
    return out


def read(path: Path) -> list[dict]:
    with open(path) as f:
        return list(csv.DictReader(f))


def test_quick_study_writes_everything_and_dask_gives_identical_runs(quick, tmp_path):
    from distributed import LocalCluster

    runs = read(quick / "runs.csv")
    # 2 zones x 2 records x 2 periods x (1 rigid + 2 single + 4 stacks)
    assert len(runs) == 2 * 2 * 2 * 7
    assert list(runs[0]) == study.RUN_COLUMNS
    drr = read(quick / "drr.csv")
    assert list(drr[0])[:8] == ["zone", "Tp", "alpha1", "alpha2", "mu1", "mu2", "DRR1", "DRR2"]
    assert len(drr) == 2 * 2 * 4
    for name in ("fig5.png", "fig6_zoneIII.png", "fig7_zoneV.png"):
        assert (quick / name).stat().st_size > 10_000, name
    assert "holds" in (quick / "conclusions.md").read_text()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        assert study.main(["--out", str(tmp_path), "--quick", "--scheduler", cluster.scheduler_address]) == 0
    assert (tmp_path / "runs.csv").read_bytes() == (quick / "runs.csv").read_bytes()


def test_drr1_equals_drr2_when_the_upper_interface_cannot_slip(quick):
    # mu2 >= mu1 with mus = muk: the lower block slides at mu1 g < mu2 g, so the
    # upper one rides on it and the stack is the single block (MODEL.md).
    rows = [r for r in read(quick / "drr.csv") if float(r["mu2"]) >= float(r["mu1"])]
    assert rows
    for r in rows:
        assert abs(float(r["DRR1"]) - float(r["DRR2"])) <= 1e-9 * float(r["DRR2"]), r
    # And where it can slip, it does: the two differ somewhere.
    others = [r for r in read(quick / "drr.csv") if float(r["mu2"]) < float(r["mu1"])]
    assert max(abs(float(r["DRR1"]) / float(r["DRR2"]) - 1) for r in others) > 1e-3


def drr(records, tp, alphas, mus):
    a = sum(alphas)
    u = lambda p: np.mean([study_tasks.peaks(str(r), p)["peakUp"] for r in records])  # noqa: E731
    rigid = u(study_tasks.rigid_params(tp, a))
    return (u(study_tasks.stack_params(tp, alphas, mus)) / rigid,
            u(study_tasks.single_params(tp, a, mus[0])) / rigid)


def test_drr_tends_to_one_as_friction_grows(quick):
    records = study.suite("V", quick=True)
    gaps = [abs(drr(records, 0.4, [0.25, 0.25], [mu, mu])[0] - 1) for mu in (0.1, 0.3, 1.0, 50.0)]
    assert gaps[0] > 0.05, "the stack slides at mu = 0.1"
    assert all(b <= a for a, b in zip(gaps, gaps[1:])), gaps
    # Never sliding, the stack is the rigid SDOF; both are integrated to ~1e-9.
    assert gaps[-1] < 1e-7, gaps


def test_drr_at_zero_friction_is_the_ratio_of_spectral_displacements(quick):
    # RESEARCH.md §3: free blocks leave the bare structure (Tp, zeta); the rigid
    # configuration is (Tp sqrt(1 + a), zeta / sqrt(1 + a)). Exact spectra:
    # seismic.response_spectrum (Nigam-Jennings, continuous peak).
    records = study.suite("III", quick=True)
    tp, alphas = 0.7, [0.25, 0.5]
    f = math.sqrt(1 + sum(alphas))
    sd_bare, sd_rigid = [], []
    for r in records:
        t, a = sll.read_record(r)
        sd_bare.append(seismic.response_spectrum(a, t[1] - t[0], [tp], 0.05)[1][0])
        sd_rigid.append(seismic.response_spectrum(a, t[1] - t[0], [tp * f], 0.05 / f)[1][0])
    expected = np.mean(sd_bare) / np.mean(sd_rigid)
    got1, got2 = drr(records, tp, alphas, [0.0, 0.0])
    # Tolerance 1e-5: the FMU's RK4 peaks agree with the exact spectra to ~5e-6.
    assert abs(got1 / expected - 1) < 1e-5, (got1, expected)
    assert abs(got2 / expected - 1) < 1e-5, (got2, expected)


def test_advisor_names_the_simplest_sufficient_model(quick, capsys):
    folder = study.suite("V", quick=True)[0].parent
    stiff_friction = advise.advise(study.suite("V", quick=True), 2.5, 0.05, [0.25, 0.25], [0.5, 0.5],
                                   [0.5, 0.5], 0.05)
    assert stiff_friction["verdict"] == "rigid", stiff_friction
    out = ROOT / "target" / "advise_test.json"
    assert advise.main(["--Tp", "0.3", "--alpha", "0.5", "0.5", "--mu", "0.1", "0.3",
                        "--records", str(folder), "--json", str(out)]) == 0
    r = json.loads(out.read_text())
    # mu2 > mu1: the stack is exactly the single block, and far from rigid at 0.3 s.
    assert r["verdict"] == "single", r
    assert abs(r["error_against_stack"]["single"]) < 1e-9
    assert abs(r["error_against_stack"]["rigid"]) > 0.05
    assert abs(r["DRR1"] - r["mean_peak_drift"]["stack"] / r["mean_peak_drift"]["rigid"]) < 1e-15
    assert "Advice" in capsys.readouterr().out


def test_section_4_validation_matches_the_closed_forms(tmp_path):
    assert validate.main(["--out", str(tmp_path)]) == 0
    numbers = json.loads((tmp_path / "validation.json").read_text())
    assert numbers["stick-stick"]["peak_slip_m"] == 0.0
    assert 0 <= numbers["stick-slip"]["breakaway_error_s"] <= 1e-4
    assert abs(numbers["slip-slip"]["peak_to_peak_rel_error"]) < 1e-4
    assert (tmp_path / "validation.png").stat().st_size > 10_000
