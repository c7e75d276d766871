"""Ground-motion readers, IS 1893 spectra and response spectra (issue #4)."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
import sll  # noqa: E402
from sll import seismic  # noqa: E402

RECORDS = ROOT.parent / "shared" / "ground_motions"
FILES = sorted(p for p in RECORDS.iterdir() if p.suffix.lower() == ".at2")


def sources_table() -> dict:
    """NPTS, DT, PGA and Sa(0.2/0.5/1/2 s) per file, from SOURCES.md."""
    out = {}
    for line in (RECORDS / "SOURCES.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        for i, cell in enumerate(cells):
            if (RECORDS / cell).is_file() and len(cells) > i + 8:
                out[cell] = {"npts": int(cells[i + 4]), "dt": float(cells[i + 5]),
                             "pga": float(cells[i + 7]),
                             "sa": [float(x) for x in cells[i + 8].split("/")]}
    return out


def rust_info(path: Path) -> dict:
    exe = ROOT / "target" / "release" / "record_info"
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "--bin", "record_info"], cwd=ROOT, check=True)
    return json.loads(subprocess.run([str(exe), str(path)], check=True, capture_output=True,
                                     text=True).stdout)


def test_every_shared_record_parses_alike_in_rust_and_python():
    table = sources_table()
    assert len(FILES) == 20 and set(table) == {f.name for f in FILES}
    for f in FILES:
        t, a = sll.read_record(f, g=1.0)
        rust = rust_info(f)
        assert len(a) == rust["npts"] == table[f.name]["npts"], f.name
        assert t[1] - t[0] == pytest.approx(rust["dt"], rel=1e-12)
        assert t[1] - t[0] == pytest.approx(table[f.name]["dt"], rel=1e-9)
        assert np.max(np.abs(a)) == rust["pga"], f.name  # same decimal strings, same doubles
        assert rust["pga"] == pytest.approx(table[f.name]["pga"], abs=5e-5)  # SOURCES: 4 decimals


def test_single_column_files_read_alike_in_rust_and_python(tmp_path):
    # A single-column conversion (no header, units of g) of a PEER record.
    t, a = sll.read_record(RECORDS / "RSN6_IMPVALL.I_I-ELC180.AT2", g=1.0)
    one = tmp_path / "elcentro_1col.txt"
    one.write_text("\r\n".join(f"{x:.7E}" for x in a) + "\r\n")
    t1, a1 = sll.read_record(one, g=1.0, dt=0.01)
    rust = rust_info_single(one, 0.01)
    assert len(a1) == rust["npts"] == len(a)
    assert np.max(np.abs(a1)) == rust["pga"] == np.max(np.abs(a))
    assert np.array_equal(t1, t)
    t2, a2 = sll.read_record(one, dt=0.01)  # default: values in g -> m/s2
    assert np.allclose(a2, a * 9.81)
    one.write_text("0.1\n0.2 0.3\n")
    with pytest.raises(ValueError, match=r"1col.txt:2: expected one number per line"):
        sll.read_record(one, dt=0.01)


def rust_info_single(path: Path, dt: float) -> dict:
    exe = ROOT / "target" / "release" / "record_info"
    subprocess.run(["cargo", "build", "--release", "--bin", "record_info"], cwd=ROOT, check=True,
                   capture_output=True)
    return json.loads(subprocess.run([str(exe), str(path), str(dt)], check=True, capture_output=True,
                                     text=True).stdout)


def test_readers_report_file_line_and_what_was_expected(tmp_path):
    bad = tmp_path / "short.AT2"
    bad.write_text("a\nb\nc\nNPTS=    3, DT=   .0100 SEC\n 0.1 0.2\n")
    with pytest.raises(ValueError, match="NPTS = 3 but the file holds 2 values"):
        sll.read_record(bad)
    csv = tmp_path / "bad.csv"
    csv.write_text("time,accel\n0,0\n0.01,x\n")
    with pytest.raises(ValueError, match=r"bad.csv:3: expected two numbers"):
        sll.read_record(csv)


@pytest.mark.parametrize("soil,T,expected", [
    # Hand values of IS 1893 (Part 1):2016 cl. 6.4.2 (b), each branch:
    ("I", 0.0, 1.0), ("I", 0.05, 1.75), ("I", 0.1, 2.5), ("I", 0.4, 2.5), ("I", 0.5, 2.0),
    ("I", 2.0, 0.5), ("I", 4.0, 0.25), ("I", 6.0, 0.25),
    ("II", 0.08, 2.2), ("II", 0.55, 2.5), ("II", 1.0, 1.36), ("II", 5.0, 0.34),
    ("III", 0.67, 2.5), ("III", 2.0, 0.835), ("III", 10.0, 0.4175),
])
def test_is1893_sa_over_g(soil, T, expected):
    assert seismic.sa_over_g(T, soil) == pytest.approx(expected, rel=1e-12)


def test_is1893_zones_levels_and_damping():
    assert seismic.design_spectrum(0.3, "V", "I", "DBE") == pytest.approx(0.36 / 2 * 2.5)
    assert seismic.design_spectrum(1.0, "III", "II", "MCE") == pytest.approx(0.16 * 1.36)
    assert seismic.design_spectrum(0.0, "II", "III", "DBE") == pytest.approx(0.05)
    assert seismic.damping_factor(0.02) == pytest.approx(1.4)
    assert seismic.damping_factor(0.035) == pytest.approx(1.2)  # linear between 2 % and 5 %
    assert seismic.damping_factor(0.10) == pytest.approx(0.8)
    assert seismic.design_spectrum(0.3, "V", "I", "DBE", zeta=0.02) == pytest.approx(0.18 * 2.5 * 1.4)
    with pytest.raises(ValueError, match="zone"):
        seismic.design_spectrum(1.0, "VI")
    with pytest.raises(ValueError, match="30 %"):
        seismic.damping_factor(0.4)


def test_response_spectra_match_the_published_values_of_every_record():
    # SOURCES.md: 5 %-damped Sa at 0.2/0.5/1/2 s, exact piecewise-linear recurrence,
    # 3 decimals (values at the samples).
    table = sources_table()
    for f in FILES:
        t, a = sll.read_record(f, g=1.0)
        psa, _ = seismic.response_spectrum(a, t[1] - t[0], [0.2, 0.5, 1.0, 2.0], between_samples=False)
        for got, ref in zip(psa, table[f.name]["sa"]):
            assert got == pytest.approx(ref, abs=6e-4), f"{f.name}: {psa} vs {table[f.name]['sa']}"


def test_response_spectrum_agrees_with_the_fmu_without_blocks():
    # Issue #4: the FMU with nBlocks = 0 gives the spectral displacement (to 1e-4).
    path = RECORDS / "RSN6_IMPVALL.I_I-ELC180.AT2"
    t, a = sll.read_record(path)
    periods = [0.2, 0.5, 1.0, 2.0, 3.0]
    _, sd = seismic.response_spectrum(a, t[1] - t[0], periods)
    with sll.Model() as m:
        for T, expected in zip(periods, sd):
            peak = m.run(path, {"nBlocks": 0, "Tp": T, "zeta": 0.05})["peaks"]["peakUp"]
            assert peak == pytest.approx(expected, rel=1e-4), f"T = {T}"


def test_a_three_record_suite_meets_the_zone_v_criterion_and_runs_through_the_fmu(tmp_path):
    import ground_motions as gmod

    records = [RECORDS / f for f in ("RSN15_KERN_TAF111.AT2", "RSN787_LOMAP_SLC270.AT2",
                                     "RSN33_PARKF_TMB205.AT2")]
    labels = {f: note for _, f, note in gmod.PAPER_SUITE}
    suite = gmod.build_suite(records, "V", "I", "DBE", tmp_path, labels)
    assert [e["note"] for e in suite["records"]] == [labels[r.name] for r in records]
    assert suite["criterion"]["passed"], suite["criterion"]
    assert (tmp_path / "spectra.png").stat().st_size > 10_000
    for entry in suite["records"]:
        # Baseline correction: final velocity and displacement (integrated from the
        # written record) below 1 % of their peaks (measured < 0.1 %).
        assert entry["final_velocity_ratio"] < 0.01, entry
        assert entry["final_displacement_ratio"] < 0.01, entry
        # Each matched record's own spectrum is within 35 % of the target everywhere.
        assert entry["match_error"]["max_abs"] < 0.35, entry
        csv = tmp_path / entry["file"]
        t, a = sll.read_record(csv)
        psa, _ = seismic.response_spectrum(a / 9.81, t[1] - t[0], [0.3])
        assert psa[0] == pytest.approx(seismic.design_spectrum(0.3, "V"), rel=0.35)
        with sll.Model() as m:
            peaks = m.run(csv)["peaks"]
        assert np.isfinite(peaks["peakUp"]) and peaks["peakUp"] > 0


def test_suite_labels_name_the_papers_record_and_the_stand_ins():
    # The paper's Table 1 (seed text): #1 Kern County, Taft Lincoln School, PGA 0.18 g;
    # #6 Chi-Chi CHY028, Mw 6.2, PGA 0.20 g. SOURCES.md: TAF111 is that record,
    # CHY028-N is the Mw 7.6 main shock at that station (a stand-in).
    import ground_motions as gmod

    entries = {no: (f, note) for no, f, note in gmod.PAPER_SUITE}
    assert sorted(entries) == list(range(1, 12))
    taft, note = entries[1]
    assert taft == "RSN15_KERN_TAF111.AT2" and "the paper's record" in note
    assert round(float(np.max(np.abs(sll.read_record(RECORDS / taft, g=1.0)[1]))), 2) == 0.18
    chichi, note = entries[6]
    assert chichi == "CHY028-N.AT2" and "stand-in" in note and "Mw 7.6" in note and "Mw 6.2" in note
    # Only Taft 111 is called the paper's record; every entry is a file of SOURCES.md.
    assert [no for no, (_, n) in entries.items() if "(the paper's record" in n] == [1]
    sources = (RECORDS / "SOURCES.md").read_text()
    for f, _ in entries.values():
        assert (RECORDS / f).is_file() and f in sources, f
    row = next(line for line in sources.splitlines() if "| RSN15_KERN_TAF111.AT2 |" in line)
    assert "paper's, PGA 0.18 g" in row
    row = next(line for line in sources.splitlines() if "| CHY028-N.AT2 |" in line)
    assert "main shock, Mw 7.6" in row
    # The scripts no longer call TAF021 or CHY028-N the paper's record.
    for script in ("ground_motions.py", "study.py", "advise.py"):
        text = (ROOT / "scripts" / script).read_text()
        assert "TAF021" not in text, script
        assert not re.search(r"CHY028[^\n]*\(the paper's record", text), script


def test_matching_is_linear_in_the_target_so_mce_is_the_dbe_match_times_two():
    # IS 1893: the MCE spectrum is twice the DBE spectrum; the matcher (reqpy-m) is
    # linear in its target, so the study's MCE level (the DBE suite x 2, through the
    # FMU's recordScale) is the suite one would match to MCE (to rounding).
    import ground_motions as gmod

    path = RECORDS / "RSN33_PARKF_TMB205.AT2"
    dbe = gmod.match(path, {"zone": "V", "soil": "I", "level": "DBE"})
    mce = gmod.match(path, {"zone": "V", "soil": "I", "level": "MCE"})
    assert float(mce["scale"]) == pytest.approx(2 * float(dbe["scale"]), rel=1e-12)
    assert np.max(np.abs(mce["sc"] - 2 * dbe["sc"])) <= 1e-12 * np.max(np.abs(mce["sc"]))
    periods = [0.1, 0.5, 1.0, 2.0]
    assert np.allclose(seismic.design_spectrum(periods, "V", "I", "MCE"),
                       2 * seismic.design_spectrum(periods, "V", "I", "DBE"), rtol=1e-15)
