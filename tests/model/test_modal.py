"""The multi-mode plate impact model against independent references.

* closed-form modes of the simply supported plate (thesis eq. 2.20-2.24);
* the one-mode limit: the exact SDF simulator after the plate-to-SDF scaling;
* energy: conserved with restitution 1 and no damping or forcing; the loss of a rigid
  impact equals the closed form ``(1 - e**2) m_eff u**2 / 2``;
* the Kelvin-Voigt and Hertz contacts against a tight DOP853 integration of the same
  modal equations (written here, in plain numpy).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rattle_lab.model import scaling
from rattle_lab.exceptions import ParameterError
from rattle_lab.model.modal import (HertzContact, KelvinVoigtContact, ModalState, ModalSystem, RigidContact,
                              plate_system, simulate_modal)
from rattle_lab.model.plate import Plate
from rattle_lab.model.sdf import SDFParams, simulate

THESIS = Plate(a_m=0.254, b_m=0.2286, h_p_m=1e-3, E_pa=7e10, nu=0.34, rho_kg_m3=2710.0, edges="CFCF")


def _ss_system(n_modes: int, xs: float, ys: float, *, zeta: float = 0.0, pressure_pa: float = 0.0,
               gap_m: float = 1e-3) -> ModalSystem:
    """Simply supported plate modes in closed form (eq. 2.20-2.24), W = sin sin (max 1)."""
    a, b, h, E, nu, rho = 0.3, 0.2, 1e-3, 7e10, 0.33, 2700.0
    D = E * h**3 / (12 * (1 - nu**2))
    cands = sorted((math.pi**2 * ((m / a) ** 2 + (n / b) ** 2) * math.sqrt(D / (rho * h)), m, n)
                   for m in range(1, 8) for n in range(1, 8))[:n_modes]
    omega = np.array([c[0] for c in cands])
    W = np.array([math.sin(m * math.pi * xs / a) * math.sin(n * math.pi * ys / b) for _, m, n in cands])
    L = np.array([a * b / (m * n * math.pi**2) * (1 - (-1) ** m) * (1 - (-1) ** n) for _, m, n in cands])
    return ModalSystem(omega_rad_s=omega, zeta=np.full(n_modes, zeta),
                       modal_mass_kg=np.full(n_modes, rho * h * a * b / 4),
                       load_m2=L, shape_at_striker=W, gap_m=gap_m, pressure_pa=pressure_pa, freq_hz=50.0)


def test_plate_system_matches_closed_form_simply_supported_modes():
    # The Ritz solver with SSSS edges against eq. 2.20-2.24 (the solver's sine basis is
    # exact for SSSS: agreement to 1e-9 relative, the accuracy of the Gauss quadrature).
    plate = Plate(a_m=0.3, b_m=0.2, h_p_m=1e-3, E_pa=7e10, nu=0.33, rho_kg_m3=2700.0, edges="SSSS")
    xs, ys = 0.11, 0.07
    got = plate_system(plate, n_modes=6, striker_xy_m=(xs, ys), pressure_pa=0.0, freq_hz=50.0)
    ref = _ss_system(6, xs, ys)
    np.testing.assert_allclose(got.omega_rad_s, ref.omega_rad_s, rtol=1e-9)
    np.testing.assert_allclose(got.modal_mass_kg, ref.modal_mass_kg, rtol=1e-9)
    # W's sign is a normalisation choice: compare sign-free products.
    np.testing.assert_allclose(got.shape_at_striker**2, ref.shape_at_striker**2, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(got.load_m2 * got.shape_at_striker, ref.load_m2 * ref.shape_at_striker,
                               rtol=1e-9, atol=1e-14)
    # Effective mass at the striker falls as modes are added (finite point impedance).
    m_eff = [plate_system(plate, n_modes=n, striker_xy_m=(xs, ys)).effective_mass_kg for n in (1, 4, 16)]
    assert m_eff[0] > m_eff[1] > m_eff[2]


@pytest.mark.parametrize(("freq_hz", "e"), [(99.8, 0.6), (115.6, 0.8), (105.0, 0.3)])
def test_one_mode_rigid_limit_is_the_sdf_simulator(freq_hz, e):
    # N = 1, rigid contact: every impact agrees with the exact SDF simulator after the
    # plate-to-SDF scaling (eq. 2.26-2.33) to 1e-12 (both are exact to rounding; these
    # orbits are stable, so rounding does not grow).
    system = plate_system(THESIS, n_modes=1, gap_m=1e-3, pressure_pa=285.0, freq_hz=freq_hz, zeta=0.05,
                          n_terms=12)  # the same Ritz basis as `THESIS.modes(1, n_terms=12)`
    modes = THESIS.modes(1, n_terms=12)
    sc = scaling.SDFScaling.from_modal_data(lam=float(modes.lam[0]), Q1=float(modes.Q1[0]),
                                            Q2=float(modes.Q2[0]), gap_m=1e-3 / float(system.shape_at_striker[0]),
                                            a_m=THESIS.a_m, h_p_m=THESIS.h_p_m, E_pa=THESIS.E_pa, nu=THESIS.nu,
                                            rho_kg_m3=THESIS.rho_kg_m3)
    ex = sc.to_nondimensional(freq_hz=freq_hz, pressure_pa=285.0)
    res = simulate_modal(system, RigidContact(e=e), cycles=60)
    sdf = simulate(SDFParams(F=float(ex.F), omega=float(ex.omega), zeta=0.05, e=e),
                   duration=float(sc.tau(60 / freq_hz)))
    assert len(res.contacts) == len(sdf.impacts) > 20
    np.testing.assert_allclose(sc.tau(res.contacts.t_start_s), sdf.impacts.t, rtol=1e-12)
    v_in = sc.v_im(res.contacts.u_in_m_s / system.shape_at_striker[0])
    np.testing.assert_allclose(v_in, sdf.impacts.v_in, rtol=1e-12)
    np.testing.assert_allclose(res.impacts.e_mode1, e, rtol=1e-12)


def _energy(system: ModalSystem, p: np.ndarray, v: np.ndarray) -> float:
    return float(0.5 * np.sum(v**2 + (system.omega_rad_s * p) ** 2))


def test_elastic_rigid_impacts_conserve_energy_over_1e4_impacts():
    # e = 1, no damping, no forcing: each impulse conserves sum (p'^2 + w^2 p^2)/2
    # exactly; the closed-form flights do too.  Rounding only: 1e-12 relative over 1e4 impacts.
    system = _ss_system(4, 0.11, 0.07)
    p0 = np.zeros(4)
    v0 = np.array([0.3, -0.1, 0.05, 0.02])  # kg^1/2 m/s
    E0 = _energy(system, p0, v0)
    res = simulate_modal(system, RigidContact(e=1.0), duration_s=120.0, state=ModalState(0.0, p0, v0),
                         max_events=10**6)
    assert len(res.contacts) >= 10_000
    assert abs(_energy(system, res.state.p, res.state.v) - E0) <= 1e-12 * E0


def test_kelvin_voigt_elastic_contact_conserves_energy():
    # c = 0, no damping or forcing: at each separation (delta = 0) the modal energy is
    # the total energy.  The coupled flow is an eigen-decomposition (cond(V) ~ 1e2), so
    # allow 1e-11 over ~1e3 contacts.
    system = _ss_system(4, 0.11, 0.07)
    p0 = np.zeros(4)
    v0 = np.array([0.3, -0.1, 0.05, 0.02])
    E0 = _energy(system, p0, v0)
    res = simulate_modal(system, KelvinVoigtContact(stiffness_n_m=2e6), duration_s=12.0,
                         state=ModalState(0.0, p0, v0))
    assert len(res.contacts) >= 1000
    assert abs(_energy(system, res.state.p, res.state.v) - E0) <= 1e-11 * E0


def test_rigid_impact_energy_loss_matches_effective_mass():
    # One impact with e: the energy lost is (1 - e^2) m_eff u^2 / 2, m_eff = 1/sum beta^2.
    system = _ss_system(5, 0.11, 0.07)
    v0 = np.array([0.3, -0.1, 0.05, 0.02, 0.01])
    e = 0.5
    res = simulate_modal(system, RigidContact(e=e), duration_s=2e-3, state=ModalState(0.0, np.zeros(5), v0),
                         dense=True)
    t_hit = res.contacts.t_start_s[0]
    u = res.contacts.u_in_m_s[0]
    before = res.modal_energy_j([t_hit * (1 - 1e-12)]).sum()
    after = res.modal_energy_j([t_hit * (1 + 1e-12)]).sum()
    expected = 0.5 * (1 - e**2) * system.effective_mass_kg * u**2
    assert before - after == pytest.approx(expected, rel=1e-6)  # 1e-12 s of flight either side


def _reference_run(system: ModalSystem, force, t_end: float, p0: np.ndarray, v0: np.ndarray):
    """DOP853 at rtol 1e-13 with contact start/stop events: plain numpy, its own code."""
    n = system.n_modes
    beta = system.shape_at_striker / np.sqrt(system.modal_mass_kg)
    phi = system.load_m2 * system.pressure_pa / np.sqrt(system.modal_mass_kg)
    w, z, Om = system.omega_rad_s, system.zeta, 2 * np.pi * system.freq_hz

    def rhs(t, y):
        d = beta @ y[:n] - system.gap_m
        dd = beta @ y[n:]
        return np.concatenate([y[n:], phi * np.cos(Om * t) - 2 * z * w * y[n:] - w**2 * y[:n]
                               - beta * force(d, dd)])

    def gap_event(t, y):
        return beta @ y[:n] - system.gap_m
    gap_event.direction = 1
    sol = solve_ivp(rhs, (0, t_end), np.concatenate([p0, v0]), method="DOP853", rtol=1e-13, atol=1e-16,
                    events=gap_event, max_step=2e-5)
    return sol.t_events[0], np.array([beta @ y[n:] for y in sol.y_events[0]])


def test_kelvin_voigt_contact_matches_direct_integration():
    system = plate_system(THESIS, n_modes=4, pressure_pa=285.0, freq_hz=115.6, zeta=0.05, skip_unexcited=True)
    k = 1e6
    res = simulate_modal(system, KelvinVoigtContact(stiffness_n_m=k, damping_n_s_m=5.0), duration_s=0.12)
    t_ref, u_ref = _reference_run(system, lambda d, dd: max(k * d + 5.0 * dd, 0.0) if d > 0 else 0.0,
                                  0.12, np.zeros(4), np.zeros(4))
    n = min(len(t_ref), len(res.contacts))
    assert n >= 8
    # Reference tolerance 1e-13 over ~12 forcing periods: agreement to 1e-8.
    np.testing.assert_allclose(res.contacts.t_start_s[:n], t_ref[:n], rtol=1e-8)
    np.testing.assert_allclose(res.contacts.u_in_m_s[:n], u_ref[:n], rtol=1e-6, atol=1e-9)


def test_hertz_contact_matches_direct_integration():
    system = plate_system(THESIS, n_modes=3, pressure_pa=285.0, freq_hz=115.6, zeta=0.05, skip_unexcited=True)
    kh = 1e9
    res = simulate_modal(system, HertzContact(stiffness_n_m15=kh), duration_s=0.1)
    t_ref, u_ref = _reference_run(system, lambda d, dd: kh * d**1.5 if d > 0 else 0.0, 0.1,
                                  np.zeros(3), np.zeros(3))
    n = min(len(t_ref), len(res.contacts))
    assert n >= 6
    # Hertz runs at rtol 1e-10 (stated default): agreement to 1e-6.
    np.testing.assert_allclose(res.contacts.t_start_s[:n], t_ref[:n], rtol=1e-6)
    np.testing.assert_allclose(res.contacts.u_in_m_s[:n], u_ref[:n], rtol=1e-5, atol=1e-8)


def test_one_mode_rigid_sticking_releases_where_the_force_reverses():
    # e = 0: the plate sticks at once; with N = 1 it is released where the load no
    # longer pushes into the striker, F cos(theta) = 1 (nondimensional), i.e.
    # phi cos(theta) beta = omega^2 gap.
    system = plate_system(THESIS, n_modes=1, gap_m=0.1e-3, pressure_pa=285.0, freq_hz=99.8, zeta=0.05)
    res = simulate_modal(system, RigidContact(e=0.0), cycles=20)
    stuck = res.contacts.kind == 2
    assert stuck.sum() >= 5
    theta = 2 * np.pi * system.freq_hz * res.contacts.t_end_s[stuck]
    lhs = system.phi[0] * np.cos(theta) * system.beta[0]
    np.testing.assert_allclose(lhs, system.omega_rad_s[0] ** 2 * system.gap_m, rtol=1e-9)


def test_bad_input_is_rejected():
    with pytest.raises(ParameterError, match="zeta"):
        plate_system(THESIS, n_modes=2, zeta=[0.05, 1.2])
    with pytest.raises(ParameterError, match="striker_xy_m"):
        plate_system(THESIS, n_modes=2, striker_xy_m=(0.5, 0.1))
    with pytest.raises(ParameterError, match="exactly one"):
        simulate_modal(plate_system(THESIS, n_modes=1), cycles=1, duration_s=1.0)
    with pytest.raises(ParameterError, match="e"):
        RigidContact(e=1.5)
    with pytest.raises(ParameterError, match="node line"):
        plate_system(THESIS, n_modes=1, striker_xy_m=(0.1, 0.0))  # on the clamped edge y = 0


def test_bad_scalars_are_refused_before_the_plate_solve(monkeypatch):
    # the CLI's 64 modes take a Ritz solve of seconds: a bad gap, pressure or frequency is
    # refused first, with ModalSystem's own message
    import rattle_lab.model.plate as plate_module

    def no_solve(*args, **kwargs):
        raise AssertionError("the Ritz solve ran")

    monkeypatch.setattr(plate_module, "ritz_modes", no_solve)
    for kwargs, name in (({"gap_m": -1e-3}, "gap_m"), ({"gap_m": math.nan}, "gap_m"),
                         ({"pressure_pa": -1.0}, "pressure_pa"), ({"freq_hz": 0.0}, "freq_hz")):
        with pytest.raises(ParameterError, match=f"`{name}` must be finite and"):
            plate_system(THESIS, n_modes=64, **kwargs)


def test_one_mode_chatter_and_sticking_agree_with_the_sdf_simulator():
    # Below resonance with a small gap (F ~ 3) the impacts chatter, accumulate and stick.
    # Releases are where F cos(theta) = 1: agreement to 1e-12.  The accumulation point
    # is estimated by both solvers from the geometric tail of unresolved flights
    # (relative accuracy of the tail ~1e-3, tail ~1e-6): agreement to 2e-8 in tau.
    system = plate_system(THESIS, n_modes=1, gap_m=0.1e-3, pressure_pa=285.0, freq_hz=50.0, zeta=0.05, n_terms=12)
    modes = THESIS.modes(1, n_terms=12)
    sc = scaling.SDFScaling.from_modal_data(lam=float(modes.lam[0]), Q1=float(modes.Q1[0]), Q2=float(modes.Q2[0]),
                                            gap_m=0.1e-3 / float(system.shape_at_striker[0]), a_m=THESIS.a_m,
                                            h_p_m=THESIS.h_p_m, E_pa=THESIS.E_pa, nu=THESIS.nu,
                                            rho_kg_m3=THESIS.rho_kg_m3)
    ex = sc.to_nondimensional(freq_hz=50.0, pressure_pa=285.0)
    res = simulate_modal(system, RigidContact(e=0.5), cycles=20)
    sdf = simulate(SDFParams(F=float(ex.F), omega=float(ex.omega), zeta=0.05, e=0.5),
                   duration=float(sc.tau(20 / 50.0)))
    stuck = res.contacts.kind == 2
    assert stuck.sum() == len(sdf.sticking) >= 10
    np.testing.assert_allclose(sc.tau(res.contacts.t_end_s[stuck]), sdf.sticking[:, 1], rtol=1e-12)
    np.testing.assert_allclose(sc.tau(res.contacts.t_start_s[stuck]), sdf.sticking[:, 0], rtol=0, atol=2e-8)


def test_many_mode_sticking_holds_the_constraint_and_releases_at_zero_force():
    # N = 6, e = 0: the plate sticks; while stuck the contact point stays on the striker
    # and the contact force (from the modal equations, evaluated here) pushes; it is
    # released where that force reaches zero.
    system = plate_system(THESIS, n_modes=6, gap_m=0.1e-3, pressure_pa=285.0, freq_hz=50.0, zeta=0.05,
                          skip_unexcited=True)
    res = simulate_modal(system, RigidContact(e=0.0), cycles=6, dense=True)
    stuck = np.flatnonzero(res.contacts.kind == 2)
    assert stuck.size >= 3
    beta, nb2 = system.beta, float(system.beta @ system.beta)
    w, z, Om = system.omega_rad_s, system.zeta, system.Omega_rad_s

    def force(t):
        p, v = res.modal_state(t)
        acc = system.phi[:, None] * np.cos(Om * t)[None, :] - (2 * z * w)[:, None] * v - (w**2)[:, None] * p
        return beta @ acc / nb2, beta @ p - system.gap_m, beta @ v

    scale = float(np.abs(beta @ system.phi)) / nb2
    for i in stuck:
        t0, t1 = res.contacts.t_start_s[i], res.contacts.t_end_s[i]
        inside = np.linspace(t0, t1, 50)[1:-1]
        lam, d, u = force(inside)
        assert np.all(lam > 0)
        assert np.max(np.abs(d)) <= 1e-12 * system.gap_m
        assert np.max(np.abs(u)) <= 1e-9 * system.gap_m * w[0]
        lam_end, _, _ = force(np.array([t1]))
        assert abs(lam_end[0]) <= 1e-9 * scale


@pytest.mark.parametrize(("margin", "touches"), [(1e-12, True), (-1e-12, False)])
def test_grazing_contact_is_found_or_excluded_to_rounding(margin, touches):
    # Two undamped, unforced modes whose sum peaks once per beat at (1 + margin) gap: a
    # narrow, near-tangent maximum between far-apart ones.  The derivative-bound search
    # must find the touch when the peak exceeds the gap by 1e-12 relative, and exclude
    # it when it falls short by as much (the grazing tolerance is 4 eps = 9e-16).
    system = ModalSystem(omega_rad_s=[600.0, 660.0], zeta=[0.0, 0.0], modal_mass_kg=[1.0, 1.0], load_m2=[0.0, 0.0],
                         shape_at_striker=[1.0, 1.0], gap_m=1e-3, pressure_pa=0.0, freq_hz=50.0)
    amp = 0.5e-3 * (1 + margin)  # the two modes peak together at t0: sum 2 amp = (1 + margin) gap
    t0 = 1e-3
    w = np.array([600.0, 660.0])
    p0 = amp * np.cos(-w * t0)  # p_k(t) = amp cos(w_k (t - t0))
    v0 = -amp * w * np.sin(-w * t0)
    res = simulate_modal(system, RigidContact(e=1.0), duration_s=2e-3, state=ModalState(0.0, p0, v0))
    if touches:
        assert len(res.contacts) >= 1
        assert res.contacts.t_start_s[0] == pytest.approx(t0, abs=1e-6)
    else:
        assert len(res.contacts) == 0
