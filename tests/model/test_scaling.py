"""Physical <-> nondimensional conversions (thesis eq. 2.3, 2.16-2.31, 4.4, 4.5)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rattle_lab.model import scaling as sc
from rattle_lab.exceptions import ParameterError

# The thesis's FEM plate (section 5.1.1) with Table 2.1's b/a = 0.9 data.
A_M, H_P_M, E_PA, NU, RHO = 0.254, 1e-3, 7e10, 0.34, 2710.0
LAM, Q1, Q2 = 27.4, 0.5, 0.402
PLATE = (A_M, H_P_M, E_PA, NU, RHO)



class TestThesisWorkedExample:
    def test_flexural_rigidity(self):
        # Eq. (2.22) by hand: 7e10 * 1e-9 / (12 * (1 - 0.1156)).
        assert sc.flexural_rigidity_nm(E_PA, H_P_M, NU) == pytest.approx(70.0 / 10.6128, rel=1e-12)

    def test_f1_is_105_hz(self):
        # Section 5.1.1: "we get f1 = 105 Hz" (3 digits): 105 +- 0.5.
        assert sc.f_s_hz(LAM, *PLATE) == pytest.approx(105.0, abs=0.5)

    def test_F_per_pascal(self):
        # Eq. (5.3): F = 1.05e-3 P_e for h = 1 mm (3 digits): +- 0.005e-3 per Pa.
        omega_s = sc.omega_s_rad_s(LAM, *PLATE)
        F_per_pa = sc.F_from_pressure(1.0, sc.participation_factor(Q1, Q2), RHO * H_P_M, omega_s, 1e-3)
        assert F_per_pa == pytest.approx(1.05e-3, abs=0.005e-3)

    def test_eq_5_4_static_amplitude(self):
        # Eq. (5.4): X_max = 3e-4 m / sqrt(...) for P_e = 285 Pa: the numerator is
        # F_es / omega_s^2 (1 digit given: +- 0.05e-4 m).
        omega_s = sc.omega_s_rad_s(LAM, *PLATE)
        F_es = sc.F_es_from_pressure(285.0, sc.participation_factor(Q1, Q2), RHO * H_P_M)
        assert F_es / omega_s**2 == pytest.approx(3e-4, abs=0.05e-4)

    def test_F_0p3_for_285_pa(self):
        # Section 5.3.2: "Using forcing pressure P_e = 285 Pa ... F = 0.3 for h = 1mm".
        s = sc.SDFScaling.from_modal_data(lam=LAM, Q1=Q1, Q2=Q2, gap_m=1e-3, a_m=A_M, h_p_m=H_P_M,
                                          E_pa=E_PA, nu=NU, rho_kg_m3=RHO)
        assert s.to_nondimensional(freq_hz=99.8, pressure_pa=285.0).F == pytest.approx(0.3, abs=0.005)


class TestRoundTrips:
    def test_lambda_frequency(self):
        lam = np.array([5.51, 27.4, 245.6])
        back = sc.lam_from_f_s(sc.f_s_hz(lam, *PLATE), *PLATE)
        np.testing.assert_allclose(back, lam, rtol=1e-14)
        assert sc.omega_s_rad_s(LAM, *PLATE) == pytest.approx(2 * math.pi * sc.f_s_hz(LAM, *PLATE), rel=1e-15)

    def test_eq_2_25_definition(self):
        w = sc.omega_s_rad_s(LAM, *PLATE)
        D = sc.flexural_rigidity_nm(E_PA, H_P_M, NU)
        assert w * A_M**2 * math.sqrt(RHO * H_P_M / D) == pytest.approx(LAM, rel=1e-14)

    @settings(derandomize=True, max_examples=60, deadline=None)
    @given(F=st.floats(0.0, 50.0), participation=st.floats(0.05, 3.0), omega_s=st.floats(10.0, 1e4),
           gap=st.floats(1e-5, 1e-2))
    def test_forcing(self, F, participation, omega_s, gap):
        A = sc.accel_ms2_from_F(F, participation, omega_s, gap)
        assert sc.F_from_accel(A, participation, omega_s, gap) == pytest.approx(F, rel=1e-12, abs=1e-300)
        P = sc.pressure_pa_from_F(F, participation, 2.71, omega_s, gap)
        assert sc.F_from_pressure(P, participation, 2.71, omega_s, gap) == pytest.approx(F, rel=1e-12, abs=1e-300)
        assert sc.F_es_from_F(sc.F_from_F_es(A, omega_s, gap), omega_s, gap) == pytest.approx(A, rel=1e-12)

    def test_pressure_accel_eq_2_3(self):
        assert sc.pressure_pa_from_accel(9.81, RHO, H_P_M) == pytest.approx(RHO * H_P_M * 9.81, rel=1e-15)
        assert sc.accel_ms2_from_pressure(26.5851, RHO, H_P_M) == pytest.approx(9.81, rel=1e-12)
        # Eq. (2.27): pressure and equivalent acceleration give the same modal forcing.
        q = sc.participation_factor(Q1, Q2)
        assert sc.F_es_from_pressure(26.5851, q, RHO * H_P_M) == pytest.approx(sc.F_es_from_accel(9.81, q), rel=1e-12)

    def test_omega_time_displacement(self):
        f = np.array([95.0, 105.0, 120.0])
        np.testing.assert_allclose(sc.freq_hz_from_omega(sc.omega_from_freq(f, 105.0), 105.0), f, rtol=1e-15)
        assert sc.time_s_from_tau(sc.tau_from_time(0.37, 660.0), 660.0) == pytest.approx(0.37, rel=1e-15)
        assert sc.tau_from_time(1.0 / 660.0, 660.0) == pytest.approx(1.0, rel=1e-15)  # tau = omega_s t
        assert sc.displacement_m_from_x(sc.x_from_displacement(3e-4, 1e-3), 1e-3) == pytest.approx(3e-4)

    def test_impact_velocity_eq_4_4_and_4_5(self):
        omega_s, gap, F_es = 662.0, 1e-3, 130.0
        v_phys = sc.impact_velocity_ms(1.7, omega_s, gap)
        assert v_phys == pytest.approx(omega_s * gap * 1.7, rel=1e-15)
        assert sc.v_im_from_velocity(v_phys, omega_s, gap) == pytest.approx(1.7, rel=1e-15)
        # Eq. (4.5): with F = F_es / (omega_s^2 h), v_im / F = omega_s v / F_es and 1/F = omega_s^2 h / F_es.
        F = sc.F_from_F_es(F_es, omega_s, gap)
        assert sc.inv_F_from_gap(gap, omega_s, F_es) == pytest.approx(1.0 / F, rel=1e-14)
        assert sc.v_im_over_F_from_velocity(v_phys, omega_s, F_es) == pytest.approx(1.7 / F, rel=1e-14)
        assert sc.gap_m_from_inv_F(1.0 / F, omega_s, F_es) == pytest.approx(gap, rel=1e-14)
        assert sc.velocity_ms_from_v_im_over_F(1.7 / F, omega_s, F_es) == pytest.approx(v_phys, rel=1e-14)

    def test_vectorised_and_scalar_types(self):
        out = sc.omega_from_freq(np.array([[1.0, 2.0]]), 2.0)
        assert isinstance(out, np.ndarray) and out.shape == (1, 2)
        assert isinstance(sc.omega_from_freq(1.0, 2.0), float)


class TestSDFScaling:
    def make(self, **kw):
        args = dict(lam=LAM, Q1=Q1, Q2=Q2, gap_m=1e-3, a_m=A_M, h_p_m=H_P_M, E_pa=E_PA, nu=NU, rho_kg_m3=RHO)
        return sc.SDFScaling.from_modal_data(**(args | kw))

    def test_round_trip(self):
        s = self.make()
        assert s.participation == pytest.approx(Q1 / Q2)
        assert s.mass_per_area_kg_m2 == pytest.approx(2.71)
        ex = s.to_nondimensional(freq_hz=np.array([100.0, 110.0]), accel_ms2=50.0)
        phys = s.to_physical(ex.F, ex.omega)
        np.testing.assert_allclose(phys.freq_hz, [100.0, 110.0], rtol=1e-14)
        assert phys.accel_ms2 == pytest.approx(50.0, rel=1e-14)
        assert phys.pressure_pa == pytest.approx(50.0 * 2.71, rel=1e-14)
        ex_p = s.to_nondimensional(freq_hz=100.0, pressure_pa=50.0 * 2.71)
        assert ex_p.F == pytest.approx(float(ex.F), rel=1e-14)

    def test_helpers(self):
        s = self.make()
        assert s.velocity_ms(s.v_im(0.25)) == pytest.approx(0.25)
        assert s.time_s(s.tau(0.01)) == pytest.approx(0.01)
        assert s.displacement_m(s.x(2e-4)) == pytest.approx(2e-4)
        assert s.f_s_hz == pytest.approx(sc.f_s_hz(LAM, *PLATE), rel=1e-15)

    def test_without_mass_per_area(self):
        s = sc.SDFScaling(omega_s_rad_s=660.0, gap_m=1e-3, participation=1.2)
        assert s.to_physical(0.1, 1.0).pressure_pa is None
        with pytest.raises(ParameterError, match=r"`pressure_pa` needs `mass_per_area_kg_m2` .* was None"):
            s.to_nondimensional(freq_hz=100.0, pressure_pa=10.0)

    def test_errors(self):
        s = self.make()
        with pytest.raises(ParameterError,
                           match=r"give exactly one of `accel_ms2` and `pressure_pa`, was accel_ms2=None"):
            s.to_nondimensional(freq_hz=100.0)
        with pytest.raises(ParameterError, match=r"give exactly one of .* accel_ms2=1.0, pressure_pa=2.0"):
            s.to_nondimensional(freq_hz=100.0, accel_ms2=1.0, pressure_pa=2.0)
        with pytest.raises(ParameterError, match=r"`participation` must be != 0 .* was 0.0"):
            self.make(Q1=0.0)
        with pytest.raises(ParameterError, match=r"`lam` must be > 0, was 0.0"):
            self.make(lam=0.0)
        with pytest.raises(ParameterError, match=r"`gap_m` must be > 0, was -0.001"):
            sc.SDFScaling(omega_s_rad_s=660.0, gap_m=-1e-3, participation=1.2)
        with pytest.raises(ParameterError, match=r"`mass_per_area_kg_m2` must be > 0, was 0.0"):
            sc.SDFScaling(omega_s_rad_s=660.0, gap_m=1e-3, participation=1.2, mass_per_area_kg_m2=0.0)
        with pytest.raises(ParameterError, match=r"`participation` must be finite, was nan"):
            sc.SDFScaling(omega_s_rad_s=660.0, gap_m=1e-3, participation=float("nan"))


class TestErrors:
    @pytest.mark.parametrize(
        ("call", "match"),
        [
            (lambda: sc.flexural_rigidity_nm(-1.0, 1e-3, 0.3), r"`E_pa` must be > 0, was -1.0"),
            (lambda: sc.flexural_rigidity_nm(7e10, 0.0, 0.3), r"`h_p_m` must be > 0, was 0.0"),
            (lambda: sc.flexural_rigidity_nm(7e10, 1e-3, 0.5), r"`nu` must satisfy -1 < nu < 0.5, was 0.5"),
            (lambda: sc.omega_s_rad_s(-1.0, *PLATE), r"`lam` must be >= 0, was -1.0"),
            (lambda: sc.omega_s_rad_s(27.4, float("nan"), H_P_M, E_PA, NU, RHO), r"`a_m` must be > 0, was nan"),
            (lambda: sc.omega_s_rad_s(27.4, A_M, H_P_M, E_PA, NU, 0.0), r"`rho_kg_m3` must be > 0, was 0.0"),
            (lambda: sc.lam_from_f_s(np.array([1.0, -2.0]), *PLATE), r"`f_s_hz` must be >= 0, was -2.0"),
            (lambda: sc.lam_from_f_s(1.0, -1.0, H_P_M, E_PA, NU, RHO), r"`a_m` must be > 0, was -1.0"),
            (lambda: sc.lam_from_f_s(1.0, A_M, H_P_M, E_PA, NU, -1.0), r"`rho_kg_m3` must be > 0, was -1.0"),
            (lambda: sc.participation_factor(0.5, 0.0), r"`Q2` must be > 0, was 0.0"),
            (lambda: sc.participation_factor(float("inf"), 0.4), r"`Q1` must be finite, was inf"),
            (lambda: sc.pressure_pa_from_accel(-1.0, RHO, H_P_M), r"`accel_ms2` must be >= 0, was -1.0"),
            (lambda: sc.accel_ms2_from_pressure(-1.0, RHO, H_P_M), r"`pressure_pa` must be >= 0, was -1.0"),
            (lambda: sc.F_es_from_pressure(1.0, 1.2, 0.0), r"`mass_per_area_kg_m2` must be > 0, was 0.0"),
            (lambda: sc.F_es_from_accel(1.0, float("nan")), r"`participation` must be finite, was nan"),
            (lambda: sc.F_from_F_es(1.0, 0.0, 1e-3), r"`omega_s_rad_s` must be > 0, was 0.0"),
            (lambda: sc.F_from_F_es(float("nan"), 1.0, 1e-3), r"`F_es_ms2` must be finite, was nan"),
            (lambda: sc.F_es_from_F(float("inf"), 1.0, 1e-3), r"`F` must be finite, was inf"),
            (lambda: sc.accel_ms2_from_F(-0.1, 1.2, 660.0, 1e-3), r"`F` must be >= 0, was -0.1"),
            (lambda: sc.accel_ms2_from_F(0.1, 0.0, 660.0, 1e-3), r"`participation` must be != 0 .* was 0.0"),
            (lambda: sc.omega_from_freq(100.0, 0.0), r"`f_s_hz` must be > 0, was 0.0"),
            (lambda: sc.freq_hz_from_omega(-1.0, 105.0), r"`omega` must be >= 0, was -1.0"),
            (lambda: sc.tau_from_time(float("nan"), 660.0), r"`time_s` must be finite, was nan"),
            (lambda: sc.time_s_from_tau(float("inf"), 660.0), r"`tau` must be finite, was inf"),
            (lambda: sc.x_from_displacement(float("nan"), 1e-3), r"`displacement_m` must be finite, was nan"),
            (lambda: sc.displacement_m_from_x(float("nan"), 1e-3), r"`x` must be finite, was nan"),
            (lambda: sc.impact_velocity_ms(float("nan"), 660.0, 1e-3), r"`v_im` must be finite, was nan"),
            (lambda: sc.v_im_from_velocity(float("nan"), 660.0, 1e-3), r"`velocity_ms` must be finite, was nan"),
            (lambda: sc.inv_F_from_gap(1e-3, 660.0, 0.0), r"`F_es_ms2` must be > 0, was 0.0"),
            (lambda: sc.gap_m_from_inv_F(0.0, 660.0, 130.0), r"`inv_F` must be > 0, was 0.0"),
            (lambda: sc.v_im_over_F_from_velocity(float("nan"), 660.0, 130.0),
             r"`velocity_ms` must be finite, was nan"),
            (lambda: sc.velocity_ms_from_v_im_over_F(float("nan"), 660.0, 130.0),
             r"`v_im_over_F` must be finite, was nan"),
        ],
    )
    def test_messages_name_argument_and_value(self, call, match):
        with pytest.raises(ParameterError, match=match):
            call()
