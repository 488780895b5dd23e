"""``rattle-lab model modal-impact`` through the installed entry point."""

from __future__ import annotations

import json
import subprocess

import pytest

from rattle_lab.model.plate import ritz_modes

from conftest import RATTLE_LAB

EXE = str(RATTLE_LAB) if RATTLE_LAB.is_file() else None


def run(*args: str) -> subprocess.CompletedProcess[str]:
    assert EXE is not None, "the rattle-lab entry point is not installed"
    return subprocess.run([EXE, "model", "modal-impact", *args], capture_output=True, text=True, timeout=300)


@pytest.mark.slow  # > 8 s (measured under load)
def test_defaults_run_the_thesis_plate_json():
    proc = run("--cycles", "8", "--modes", "6", "--json")
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ""
    out = json.loads(proc.stdout)
    assert out["plate"] == {"a_m": 0.254, "b_m": 0.2286, "h_p_m": 0.001, "edges": "CFCF"}
    assert out["contact"] == "kelvin-voigt"
    assert len(out["modes"]) == 6
    # Mode 1 is the Ritz mode 1 of the thesis plate (105 Hz, section 5.1.1).
    lam1 = float(ritz_modes(0.9, "CFCF", nu=0.34, n_modes=1, n_terms=24).lam[0])  # the model's Ritz terms
    f1 = lam1 / (2 * 3.141592653589793 * 0.254**2) * (7e10 * 1e-9 / (12 * (1 - 0.34**2)) / (2710 * 1e-3)) ** 0.5
    assert out["modes"][0]["f_hz"] == pytest.approx(f1, rel=1e-6)
    # Mode 2 of the plate (Q1 = 0, not excited: thesis section 5.2) is skipped by default.
    assert out["modes"][1]["f_hz"] > 150
    impacts = out["impacts"]
    assert len(impacts) >= 4
    for imp in impacts:
        assert set(imp) >= {"t_s", "v_in_m_s", "v_out_m_s", "e_mode1"}
        assert imp["v_in_m_s"] > 0
    # impact velocities near 1 m/s at F = 0.3, omega = 0.95, h = 1 mm (thesis Fig. 5-5/5-7)
    assert 0.3 < impacts[-1]["v_in_m_s"] < 3.0
    assert len(out["mic"]) == len(impacts) and all(p > 0 for p in out["mic"])


def test_one_rigid_mode_gives_back_e():
    proc = run("--cycles", "20", "--modes", "1", "--contact", "rigid", "--e", "0.6", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert len(out["impacts"]) > 5
    assert all(imp["e_mode1"] == pytest.approx(0.6, rel=1e-12) for imp in out["impacts"])


@pytest.mark.slow  # > 8 s (measured under load)
def test_table_output_and_bad_input():
    proc = run("--cycles", "3", "--modes", "2", "--contact", "hertz")
    assert proc.returncode == 0 and proc.stderr == ""
    assert "v_in [m/s]" in proc.stdout and "hertz contact" in proc.stdout
    bad = run("--gap", "-1")
    assert bad.returncode == 2
    assert bad.stdout == ""
    assert len(bad.stderr.strip().splitlines()) == 1 and "gap_m" in bad.stderr
    bad = run("--striker", "1.0", "0.1")
    assert bad.returncode == 2 and "striker_xy_m" in bad.stderr


@pytest.mark.slow  # > 8 s (measured under load)
def test_omitted_modes_element_is_on_by_default_and_can_be_left_out():
    # Issue 24: the compliant contacts get the omitted modes' element by default; its
    # impedance is the infinite plate's, 8 sqrt(D m'') (computed here from the defaults).
    D = 7e10 * 1e-9 / (12 * (1 - 0.34**2))
    Z = 8 * (D * 2710 * 1e-3) ** 0.5
    out = json.loads(run("--cycles", "4", "--modes", "6", "--json").stdout)
    assert out["omitted_modes"]["local_impedance_n_s_m"] == pytest.approx(Z, rel=1e-12)
    assert out["omitted_modes"]["residual_compliance_m_n"] > 0
    assert all(imp["n_contacts"] == 1 for imp in out["impacts"])
    assert len(out["mic_measured"]) == len(out["impacts"])
    assert all(0 < h < 1.2 * p for h, p in zip(out["mic_measured"], out["mic"]))
    assert 60 < out["mic_fast_max_db"] < 140
    plain = json.loads(run("--cycles", "4", "--modes", "6", "--json", "--no-omitted-modes").stdout)
    assert plain["omitted_modes"] is None
    # the rigid contact never has the element (it has no meaning against a dashpot)
    rigid = json.loads(run("--cycles", "4", "--modes", "2", "--contact", "rigid", "--json").stdout)
    assert rigid["omitted_modes"] is None
