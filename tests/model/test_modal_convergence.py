"""The omitted modes' element at the contact point (issue 24) against independent references.

* the element's mobility ``i omega / (k_r + i omega Z)`` against the infinite thin plate's
  point impedance ``Z = 8 sqrt(D m'')`` (Cremer, Heckl & Petersson), computed here from
  D and m'' directly, and the model's band-averaged point mobility against ``1/Z``;
* a sphere striking a large plate far from its edges against Zener's model (Phys. Rev.
  59, 669 (1941): Hertz contact on a plate point of real impedance Z), integrated here
  with scipy's DOP853 in its own three-variable form;
* convergence in N of one impact (contacts, e of mode 1, duration, predicted sound slope);
* the power balance of the element: the modal and spring energy lost equals the
  dashpot's dissipation ``int Z r'^2 dt``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rattle_lab.exceptions import ParameterError
from rattle_lab.model.modal import (HertzContact, KelvinVoigtContact, ModalState, ModalSystem, RigidContact,
                                    plate_system, predicted_spl_slope, simulate_modal)
from rattle_lab.model.plate import Plate
from plate_mobility import band_means, z_inf

THESIS = Plate(a_m=0.254, b_m=0.2286, h_p_m=1e-3, E_pa=7e10, nu=0.34, rho_kg_m3=2710.0, edges="CFCF")


@pytest.fixture(scope="module")
def thesis16() -> ModalSystem:
    return plate_system(THESIS, n_modes=16, skip_unexcited=True, omitted_modes=True, pressure_pa=0.0)


def test_element_has_the_infinite_plate_impedance_and_the_residual_flexibility(thesis16):
    Z = z_inf(THESIS)
    assert thesis16.local_impedance_n_s_m == pytest.approx(Z, rel=1e-12)
    assert Z == pytest.approx(33.8, abs=0.05)
    # Far above the cut the element is the dashpot (1/Z), far below it the static
    # residual flexibility (i omega G): its own closed form, to rounding.
    plain = thesis16.replace(local_impedance_n_s_m=0.0, residual_compliance_m_n=0.0)
    w_hi = np.array([2e9])  # k_r / (omega Z) ~ 1.5e-5 here
    y_el = thesis16.point_mobility(w_hi) - plain.point_mobility(w_hi)
    assert abs(y_el[0] * Z - 1.0) < 1e-4
    w_lo = np.array([10.0])
    y_lo = thesis16.point_mobility(w_lo) - plain.point_mobility(w_lo)
    assert y_lo[0].imag / (w_lo[0] * thesis16.residual_compliance_m_n) == pytest.approx(1.0, rel=1e-5)
    # The residual flexibility falls as modes are retained (2 / (pi Z omega_c)).
    s32 = plate_system(THESIS, n_modes=32, skip_unexcited=True, omitted_modes=True, pressure_pa=0.0)
    assert s32.residual_compliance_m_n < 0.6 * thesis16.residual_compliance_m_n


OCTAVES_HZ = (1000.0, 2000.0, 4000.0, 8000.0)


def test_band_mobility_approaches_one_over_z_where_the_plain_sum_has_none(thesis16):
    # Octave bands 1-8 kHz (edges 707 Hz .. 11.3 kHz) at the plate centre, N = 16 excited
    # modes (the last at 2.75 kHz).  The plain truncated sum has almost no real mobility
    # above its last mode; with the element every band carries between 0.5/Z and 1.2/Z.
    Z = z_inf(THESIS)
    plain = thesis16.replace(local_impedance_n_s_m=0.0, residual_compliance_m_n=0.0)
    with_el = band_means(thesis16, OCTAVES_HZ) * Z
    without = band_means(plain, OCTAVES_HZ) * Z
    assert np.all(without[2:] < 0.1)
    assert np.all((with_el > 0.5) & (with_el < 1.2)), with_el


@pytest.mark.xfail(strict=True, reason="issue 24 target not met: at N = 16 the one-element "
                   "correction has 0.53/Z to 0.76/Z in the two octaves above its cut, and the "
                   "1 kHz octave is 0.81/Z for every N from 32 to 256, which is the plate's "
                   "own value there (an independent Ritz solution gives 0.812/Z: "
                   "tests/model/test_cfcf_mobility.py; the same plate simply supported meets "
                   "it, test_band_mobility_of_a_simply_supported_plate_...)")
def test_band_mobility_within_ten_percent_of_one_over_z(thesis16):
    Z = z_inf(THESIS)
    assert np.all(np.abs(band_means(thesis16, OCTAVES_HZ) * Z - 1.0) < 0.10)


def test_band_mobility_of_64_modes_from_2_to_8_khz_is_one_over_z():
    # N = 64 excited modes (the last at 12.9 kHz, 37-term basis): in the octaves 2, 4 and
    # 8 kHz the converged modal sum itself carries the mobility, and its band means are
    # those of an infinite plate, 1/Z, within the 10 % (measured 1.043, 0.985,
    # 1.077; 1.035, 0.957, 0.998 at N = 128).  Not the 1 kHz octave: 0.81/Z at every N from
    # 32 to 256, the few modes of this finite plate seen at its centre there.
    s64 = plate_system(THESIS, n_modes=64, skip_unexcited=True, omitted_modes=True,
                       pressure_pa=0.0)
    Z = z_inf(THESIS)
    assert np.all(np.abs(band_means(s64, OCTAVES_HZ[1:]) * Z - 1.0) < 0.10)


def _zener_e(m: float, k_h: float, Z: float, v0: float) -> float:
    """Zener's model: sphere x'' = -F/m, plate point w' = F/Z, F = k_h (x - w)^1.5."""
    def rhs(t, y):
        a = y[0] - y[2]
        F = k_h * a**1.5 if a > 0 else 0.0
        return [y[1], -F / m, F / Z]

    def out(t, y):
        return y[0] - y[2]
    out.terminal, out.direction = True, -1
    sol = solve_ivp(rhs, (1e-12, 1e-2), [1e-12 * v0, v0, 0.0], method="DOP853", rtol=1e-12, atol=1e-18,
                    events=out)
    return float(-sol.y_events[0][0][1] / v0)


def test_sphere_on_a_large_plate_restitution_is_zeners():
    # A 2 mm steel ball at 1 m/s on a 1 x 0.8 m, 2 mm aluminium plate (SSSS), struck at the
    # centre: contact ~20 us, flexural waves need ~0.4 ms to come back from the edges, so
    # the plate is infinite for the impact.  The ball is one more coordinate of the
    # modal system (mass m, on a negligible 1 rad/s spring, seen with W = 1); the plate
    # keeps N = 16 excited modes (up to 470 Hz) plus the element.  Reference: Zener's
    # model (e = 0.563 here, an inelastic impact).  Tolerance 5 % (the issue's): the
    # element is a dashpot only above its cut; measured 1.3 % (N = 16), 2.6 % (N = 32).
    plate = Plate(a_m=1.0, b_m=0.8, h_p_m=2e-3, E_pa=7e10, nu=0.34, rho_kg_m3=2710.0, edges="SSSS")
    R = 2e-3
    m = 7800.0 * 4.0 / 3.0 * math.pi * R**3
    e_star = 1.0 / ((1 - 0.3**2) / 2.1e11 + (1 - 0.34**2) / 7e10)
    k_h = 4.0 / 3.0 * e_star * math.sqrt(R)
    s = plate_system(plate, n_modes=16, skip_unexcited=True, omitted_modes=True, pressure_pa=0.0)
    both = ModalSystem(omega_rad_s=np.r_[1.0, s.omega_rad_s], zeta=np.zeros(17),
                       modal_mass_kg=np.r_[m, s.modal_mass_kg], load_m2=np.r_[0.0, s.load_m2],
                       shape_at_striker=np.r_[1.0, s.shape_at_striker], gap_m=1e-3, pressure_pa=0.0,
                       freq_hz=50.0, local_impedance_n_s_m=s.local_impedance_n_s_m,
                       residual_compliance_m_n=s.residual_compliance_m_n)
    p0 = np.zeros(17)
    v0 = np.zeros(17)
    p0[0] = math.sqrt(m) * 1e-3 * (1 - 1e-9)
    v0[0] = math.sqrt(m) * 1.0
    res = simulate_modal(both, HertzContact(k_h), duration_s=2e-4, state=ModalState(0.0, p0, v0),
                         episode_gap_s=1e-4)
    assert len(res.contacts) == 1
    e_model = -res.state.v[0] / math.sqrt(m)
    e_zener = _zener_e(m, k_h, z_inf(plate), 1.0)
    assert 0.3 < e_zener < 0.8
    assert e_model == pytest.approx(e_zener, rel=0.05)
    # Without the element the truncated plate cannot take the energy: nearly elastic.
    plain = both.replace(local_impedance_n_s_m=0.0, residual_compliance_m_n=0.0)
    res0 = simulate_modal(plain, HertzContact(k_h), duration_s=2e-4, state=ModalState(0.0, p0, v0),
                          episode_gap_s=1e-4)
    assert -res0.state.v[0] / math.sqrt(m) > e_zener + 0.2


def _probe(n: int, omitted: bool):
    s = plate_system(THESIS, n_modes=n, skip_unexcited=True, omitted_modes=omitted, pressure_pa=0.0,
                     n_terms=28)
    p0 = np.zeros(n)
    v0 = np.zeros(n)
    p0[0] = s.gap_m * (1 - 1e-9) / s.beta[0]
    v0[0] = 1.0 / s.beta[0]
    span = 4.0 / s.omega_rad_s[0]
    return s, simulate_modal(s, KelvinVoigtContact(), duration_s=span, state=ModalState(0.0, p0, v0),
                             episode_gap_s=span / 2)


def test_one_impact_converges_from_n_to_2n():
    # Mode 1 at 1 m/s into the thesis striker (no forcing), one Ritz basis (28 terms):
    # with the element the impact is one contact whose e of mode 1 and duration change
    # by < 2 % from N = 16 to 32 (measured 1.1 % and 0.3 %); the plain sum breaks it into
    # a cluster whose count grows with N (measured 7 and 16).
    (_, a), (_, b) = _probe(16, True), _probe(32, True)
    assert len(a.contacts) == len(b.contacts) == 1
    assert b.impacts.e_mode1[0] == pytest.approx(a.impacts.e_mode1[0], rel=0.02)
    dur = [r.contacts.t_end_s[0] - r.contacts.t_start_s[0] for r in (a, b)]
    assert dur[1] == pytest.approx(dur[0], rel=0.02)
    (_, c), (_, d) = _probe(16, False), _probe(32, False)
    assert len(d.contacts) > len(c.contacts) > 3


def test_predicted_sound_slope_converges_within_five_percent():
    s16 = plate_system(THESIS, n_modes=16, skip_unexcited=True, omitted_modes=True, n_terms=28)
    s32 = plate_system(THESIS, n_modes=32, skip_unexcited=True, omitted_modes=True, n_terms=28)
    S16, S32 = predicted_spl_slope(s16), predicted_spl_slope(s32)
    assert S32 == pytest.approx(S16, rel=0.05)


def test_element_power_balance():
    # No forcing, no modal damping, an undamped striker: what the modes, the element's
    # spring and the striker lose is what the dashpot dissipates, int Z r'^2 dt.  The
    # integral is taken on a 2e5-point grid (trapezoid on r' from the dense output's r
    # by central differences: relative error ~1e-4 here).
    s = plate_system(THESIS, n_modes=6, skip_unexcited=True, omitted_modes=True, pressure_pa=0.0,
                     zeta=0.0)
    p0 = np.zeros(6)
    v0 = np.zeros(6)
    p0[0] = s.gap_m * (1 - 1e-9) / s.beta[0]
    v0[0] = 0.5 / s.beta[0]
    T = 3e-3
    res = simulate_modal(s, KelvinVoigtContact(), duration_s=T, state=ModalState(0.0, p0, v0), dense=True)
    assert len(res.contacts) >= 1
    t = np.linspace(0.0, T, 200001)
    r = res.residual_deflection_m(t)
    rd = np.gradient(r, t)
    diss = s.local_impedance_n_s_m * float(np.trapezoid(rd**2, t))
    kr = 1.0 / s.residual_compliance_m_n
    p, v = res.modal_state(t[[0, -1]])
    k = KelvinVoigtContact().stiffness_n_m

    def energy(i: int) -> float:
        d = max(float(s.beta @ p[:, i]) - r[[0, -1]][i] - s.gap_m, 0.0)
        return float(0.5 * np.sum(v[:, i] ** 2 + (s.omega_rad_s * p[:, i]) ** 2)
                     + 0.5 * kr * r[[0, -1]][i] ** 2 + 0.5 * k * d**2)
    lost = energy(0) - energy(1)
    assert diss > 0.01 * energy(0)
    assert lost == pytest.approx(diss, rel=2e-3)


def test_rigid_contact_is_refused_with_the_element(thesis16):
    with pytest.raises(ParameterError, match="rigid"):
        simulate_modal(thesis16, RigidContact(0.5), cycles=1)
    with pytest.raises(ParameterError, match="both"):
        thesis16.replace(local_impedance_n_s_m=0.0)


def test_a_run_continued_inside_a_contact_is_the_same_run():
    # A ramp's pieces may cut a contact (they last ~1.5 ms with the element): the second
    # piece starts inside it.  Same flows, restarted: the states agree to rounding of the
    # eigen-decomposition (1e-9 relative).
    s = plate_system(THESIS, n_modes=6, skip_unexcited=True, omitted_modes=True, pressure_pa=285.0,
                     freq_hz=99.8)
    p0 = np.zeros(6)
    v0 = np.zeros(6)
    p0[0] = s.gap_m * (1 - 1e-9) / s.beta[0]
    v0[0] = 0.5 / s.beta[0]
    start = ModalState(0.0, p0, v0)
    whole = simulate_modal(s, KelvinVoigtContact(), duration_s=3e-3, state=start)
    first = simulate_modal(s, KelvinVoigtContact(), duration_s=0.5e-3, state=start)
    assert float(s.beta @ first.state.p) - first.state.r_m > s.gap_m  # cut inside the contact
    rest = simulate_modal(s, KelvinVoigtContact(), duration_s=2.5e-3, state=first.state)
    scale = np.max(np.abs(whole.state.v))
    np.testing.assert_allclose(rest.state.v, whole.state.v, rtol=0, atol=1e-9 * scale)
    assert rest.state.r_m == pytest.approx(whole.state.r_m, rel=1e-8, abs=1e-15)
    assert rest.contacts.t_end_s[0] == pytest.approx(whole.contacts.t_end_s[0], rel=1e-9)


def test_first_peak_is_the_contact_force_on_an_infinite_plate_plus_the_plates_own_deceleration():
    # benchmarks/modal_first_peak.py's split of the early sound peak (issue 24, ask 3), at
    # N = 16 (its 200 us peak is not converged there, but the split holds at every N; the
    # benchmark prints N = 64).  The peak for impacts at 0.5-4 m/s is a straight line in
    # v_in (largest residual 0.015 Pa measured: allowed 0.1 Pa):
    # * its slope is the infinite plate's ``rho_0 F / (2 pi m'' r)`` for the model's own
    #   largest contact force (independent closed form; F_max = 1.25-1.28 Z v here, so the
    #   slope is 1.3 times the bound rho_0 Z / (2 pi m'' r)): within 5 % (1.0 % measured);
    # * its intercept is the sound of the plate held in mode 1 at the gap, its elastic
    #   deceleration w1^2 q1 phi_1 summed over the plate (the benchmark starts its run at
    #   the gap, so that sound starts with the impact): within 15 % (8.7 % measured; the
    #   farthest elements' share arrives up to 140 us after the centre's).
    from bench_module import benchmark_module

    with benchmark_module("modal_first_peak") as bench:
        sw = bench.sweep(16)
    assert sw["fit_residual"] < 0.1
    assert sw["slope"] == pytest.approx(sw["force_slope"], rel=0.05)
    assert sw["slope"] > 1.2 * sw["bound"]
    assert sw["intercept"] == pytest.approx(sw["static"], rel=0.15)


def test_an_impacts_own_sound_in_a_rattling_run_is_one_impacts_from_rest():
    # benchmarks/modal_sound_law.py (issue 24, ask 3: the campaign's first-peak law against
    # one impact's).  The model is linear outside the contact, so an impact's own sound is
    # the run continued from 2 ms before it with the striker less the same run without it.
    # In the first 6 impacts of a 30-period run at omega = 1.1 (N = 16) it is, per m/s, the
    # sound of one impact from rest interpolated at the same v_in (0.5, 1, 2 m/s): within
    # 2 % (0.4 % measured; at N = 64 over 28 impacts 0.2-3.4 % below, which the benchmark
    # prints).  So what a campaign's first-peak law reads besides it is the plate's other
    # sound, not a different impact sound.
    from bench_module import benchmark_module

    with benchmark_module("modal_sound_law") as bench:
        r = bench.laws(16, 1.1, max_impacts=6)
    assert r["v"].size == 6 and r["v"].min() > 0.5
    single = np.interp(r["v"], r["single_v"], r["single_own"])
    np.testing.assert_allclose(r["own"], single, rtol=0.02)
    # the first-peak rule on the own sound alone reads it too (within 300 us: the same peak)
    np.testing.assert_allclose(r["own_rule"], r["own"], rtol=0.05)


def _ssss_centre_series(plate: Plate, zeta: float, centres_hz: tuple[float, ...],
                        m_max: int = 200, n_freq: int = 2001) -> np.ndarray:
    """Band means of Re(Y) * Z at the centre of a simply supported plate from its closed-form
    modes ``sin(m pi x / a) sin(n pi y / b)``, ``w_mn = sqrt(D/m'') ((m pi/a)^2 + (n pi/b)^2)``,
    modal mass ``m'' a b / 4`` (every mode up to m, n = m_max: 1e4 modes to 3 MHz)."""
    D = plate.E_pa * plate.h_p_m**3 / (12.0 * (1.0 - plate.nu**2))
    m2 = plate.rho_kg_m3 * plate.h_p_m
    m = np.arange(1, m_max + 1, 2)[:, None]      # even m or n: a node at the centre
    n = np.arange(1, m_max + 1, 2)[None, :]
    wk = (math.sqrt(D / m2) * ((m * math.pi / plate.a_m) ** 2 + (n * math.pi / plate.b_m) ** 2)).ravel()
    b2 = 4.0 / (m2 * plate.a_m * plate.b_m)       # sin^2 = 1 at the centre for odd m, n
    out = []
    for fc in centres_hz:
        w = 2.0 * math.pi * np.linspace(fc / math.sqrt(2.0), fc * math.sqrt(2.0), n_freq)
        den = wk[:, None] ** 2 - w[None, :] ** 2 + 2j * zeta * wk[:, None] * w[None, :]
        out.append(float(np.mean(np.sum(b2 * 1j * w[None, :] / den, axis=0).real)))
    return np.array(out) * z_inf(plate)


def test_band_mobility_of_a_simply_supported_plate_matches_its_closed_form_series():
    # Issue 24 ask 2a on a plate whose modes are known in closed form: the thesis plate's
    # size and material, simply supported (SSSS), at its centre.  The exact modal series
    # (every mode to 3 MHz) gives band means within 10 % of 1/Z in the octaves 1-8 kHz
    # (1.061, 0.934, 0.966, 0.979 measured): the modal-density result holds there.  The
    # model (Ritz modes, 64 excited, and the omitted modes' element) gives the series' band
    # means within 4 % in the octaves 1-4 kHz (0.2, 1.0, 3.6 % measured; 1.063, 0.943,
    # 1.001); the 8 kHz octave, at its last modes, is 11 % above at N = 64 and 3.5 % at
    # N = 128 (docs/explanation/modal_convergence.md).  So the CFCF plate's 0.81/Z in the
    # 1 kHz octave is not the model's: the same sum meets the target on this plate.
    ssss = Plate(a_m=0.254, b_m=0.2286, h_p_m=1e-3, E_pa=7e10, nu=0.34, rho_kg_m3=2710.0,
                 edges="SSSS")
    s64 = plate_system(ssss, n_modes=64, skip_unexcited=True, omitted_modes=True, pressure_pa=0.0)
    zeta = float(np.atleast_1d(s64.zeta)[0])
    series = _ssss_centre_series(ssss, zeta, OCTAVES_HZ)
    assert np.all(np.abs(series - 1.0) < 0.10), series
    model = band_means(s64, OCTAVES_HZ[:3]) * z_inf(ssss)
    np.testing.assert_allclose(model, series[:3], rtol=0.04)
