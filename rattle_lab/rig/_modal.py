"""The rig's opt-in multi-mode model (``[model] kind = "modal"``, issue 14).

Instead of the single-mode (SDF) simulator with canned contact pulses, ringing and
acoustic law, a run is simulated by :mod:`rattle_lab.model.modal`: the plate's lowest
``modes`` Ritz modes against a point striker with a compliant (Kelvin-Voigt, Hertz) or
rigid contact.  The base-excited plate relative to its frame obeys the modal equations
under the uniform inertial pressure ``rho h_p A cos(theta)`` (``A`` the base
acceleration amplitude, ``a_base = -A cos(theta)`` as in the SDF rig), so the forcing
phase, ramps and sweeps are those of the SDF rig, piece by piece, with ``Omega t + phi``
continuous across pieces.

What the channels get:

* vibrometer: the plate's velocity relative to the base at the striker's point (all
  modes; the plate centre unless ``striker_x_m``, ``striker_y_m`` say otherwise),
  band-limited like the SDF vibrometer;
* plate accelerometer: base acceleration plus the central difference of the sampled
  relative velocity (so it is band-limited to the sample rate);
* microphone: the Rayleigh integral of the baffled plate at ``(a/2, b/2, mic_distance_m)``
  over the whole run (settling included, so the first samples hear the motion before),
  with its propagation delay; plus the fan tone of ``[artefacts]``.

The compliant contacts include the omitted modes' element at the contact point (issue 24,
:func:`rattle_lab.model.modal.plate_system` with ``omitted_modes=True``) and the sound its
point source; the rigid contact keeps the plain truncated sum.

The truth's impacts are the contact episodes (first touch to final separation) and
``v_in_m_s``, ``v_out_m_s`` are the velocities of the plate **at the contact point**,
towards the striker at first touch and away from it at final separation.  The main
mode's own restitution per impact (``e_mode1``) is summarised in ``/truth`` as ``e``
(its ``v_in**2``-weighted mean over the campaign, clipped to [0, 1]) and the extra
attribute ``e_mode1_weighted``.  An episode that straddles a ramp's piece boundary
is reported as two (contacts through the omitted modes' element last ~1.5 ms on the
thesis plate, pieces several forcing periods of ~10 ms).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any
from collections.abc import Callable

import numpy as np

from rattle_lab.model.modal import (C_AIR_M_S, Contact, ModalResult, ModalState, ModalSystem,
                                    contact_from_name, plate_surface, plate_system,
                                    rayleigh_pressure, residual_pressure, simulate_modal)
from rattle_lab.model.plate import Plate
from rattle_lab.records import Rig
from ._counter import StageCounter
from ._modal_spec import ModalRigSpec
from ._motion import Modal, RunMotion, schedule
from ._scene import RunSpec, Scene, SceneError

TWO_PI = 2.0 * math.pi


def plate_of(scene: Scene) -> Plate:
    """The scene's plate as a :class:`rattle_lab.model.plate.Plate`."""
    p = scene.plate
    if p is None:
        raise SceneError(f"{scene.source}: `model.kind` = \"modal\" needs a [plate], was None")
    return Plate(a_m=p.length_m, b_m=p.width_m, h_p_m=p.thickness_m, E_pa=p.E_pa, nu=p.nu,
                 rho_kg_m3=p.rho_kg_m3, edges=p.edges)


def modal_spec(scene: Scene) -> ModalRigSpec:
    """The ``[model] kind = "modal"`` options of a modal scene."""
    spec = scene.model.modal
    assert spec is not None, "not a modal scene"   # parse_scene sets it with kind = "modal"
    return spec


def build_system(scene: Scene) -> tuple[ModalSystem, Contact]:
    """The modal system (unforced) and contact law a modal scene describes."""
    spec = modal_spec(scene)
    plate = plate_of(scene)
    xs = plate.a_m / 2 if spec.striker_x_m is None else spec.striker_x_m
    ys = plate.b_m / 2 if spec.striker_y_m is None else spec.striker_y_m
    try:
        system = plate_system(plate, n_modes=spec.modes, gap_m=scene.model.gap_m, striker_xy_m=(xs, ys),
                              pressure_pa=0.0, freq_hz=scene.runs[0].freq_hz, zeta=scene.model.zeta,
                              omitted_modes=spec.contact != "rigid")
    except SceneError:
        raise
    except ValueError as exc:   # ParameterError: e.g. the striker off the plate
        raise SceneError(f"{scene.source}: `model` (modal): {exc}") from exc
    contact = contact_from_name(spec.contact, e=scene.model.e, stiffness_n_m=spec.contact_stiffness_n_m,
                                damping_n_s_m=spec.contact_damping_n_s_m, hertz_n_m15=spec.hertz_n_m15)
    return system, contact


def pressure_pa(scene: Scene, level_m_s2: float) -> float:
    """Uniform inertial pressure amplitude ``rho h_p A`` [Pa] of a base acceleration ``A``."""
    p = scene.plate
    assert p is not None
    return p.rho_kg_m3 * p.thickness_m * level_m_s2


def _steady(system: ModalSystem) -> tuple[np.ndarray, np.ndarray]:
    """Linear steady state ``(p, v)`` at time 0 (no contact)."""
    w, z, Om = system.omega_rad_s, system.zeta, TWO_PI * system.freq_hz
    phi = system.load_m2 * system.pressure_pa / np.sqrt(system.modal_mass_kg)
    H = phi / (w**2 - Om**2 + 2j * z * w * Om) * np.exp(1j * system.phase_rad)
    return H.real, (1j * Om * H).real


def start_state(system: ModalSystem, contact: Contact, settle_time_constants: float
                ) -> tuple[ModalState, ModalResult | None]:
    """The state a run starts from and the settling run (None when not needed).

    Below grazing the run starts on the linear steady state (the shaker has been
    running); above grazing the plate starts at rest and settles for
    ``settle_time_constants / (zeta_1 omega_1)`` seconds at the first piece's forcing.
    """
    p, v = _steady(system)
    beta = system.shape_at_striker / np.sqrt(system.modal_mass_kg)
    amp = abs(complex(np.sum(beta * p), -np.sum(beta * v) / (TWO_PI * system.freq_hz)))
    if amp < system.gap_m:
        return ModalState(0.0, p, v), None
    settle_s = settle_time_constants / (max(float(system.zeta[0]), 1e-3) * float(system.omega_rad_s[0]))
    res = simulate_modal(system, contact, duration_s=settle_s, dense=True)
    return res.state, res


def simulate_run_modal(scene: Scene, base: ModalSystem, contact: Contact, run: RunSpec,
                       sample_rate_hz: float, counter: StageCounter | None = None
                       ) -> tuple[RunMotion, np.ndarray | None, Any]:
    """Simulate one run with the modal model.

    Returns
    -------
    motion : RunMotion
        Forcing phase, level, frequency, velocity and acceleration relative to the base at
        the striker's point, and the impacts (contact episodes, contact-point velocities).
    mic_pa : numpy.ndarray or None
        Sound pressure at the microphone (None when the scene records no microphone).
    episodes : list of EpisodeLog
        The contact episodes of every piece (times from the run start).
    """
    counter = counter if counter is not None else StageCounter()
    pieces = schedule(run, scene.simulation.piece_periods)
    first = base.replace(pressure_pa=pressure_pa(scene, pieces[0].level_m_s2), freq_hz=pieces[0].freq_hz,
                         phase_rad=0.0)
    state, settle = start_state(first, contact, scene.simulation.settle_time_constants)
    t0 = state.t_s                                   # run time 0 in simulation time
    theta0 = TWO_PI * first.freq_hz * t0              # forcing phase at the run start
    n = round(run.duration_s * sample_rate_hz)
    t = np.arange(n) / sample_rate_hz
    results: list[ModalResult] = [] if settle is None else [settle]
    theta = np.empty(n)
    level = np.empty(n)
    freq = np.empty(n)
    bounds = np.searchsorted(t, [p.t0_s for p in pieces] + [run.duration_s], side="left")
    th = theta0
    for k, piece in enumerate(pieces):
        Om = TWO_PI * piece.freq_hz
        start = t0 + piece.t0_s
        sys_k = first.replace(pressure_pa=pressure_pa(scene, piece.level_m_s2), freq_hz=piece.freq_hz,
                              phase_rad=th - Om * start)
        res = simulate_modal(sys_k, contact, duration_s=t0 + piece.t1_s - state.t_s, state=state, dense=True)
        counter.add("simulate")
        lo, hi = int(bounds[k]), int(bounds[k + 1])
        theta[lo:hi] = th + Om * (t[lo:hi] - piece.t0_s)
        level[lo:hi] = piece.level_m_s2
        freq[lo:hi] = piece.freq_hz
        th += Om * (piece.t1_s - piece.t0_s)
        results.append(res)
        state = res.state
    starts = np.array([r.segments[0][0] if r.segments else 0.0 for r in results])
    t_lo, t_hi = results[0].segments[0][0], results[-1].state.t_s

    def velocity(tt: np.ndarray) -> np.ndarray:
        """Modal velocities [m/s] at simulation times (held before the first and after the last)."""
        tt = np.clip(np.asarray(tt, dtype=float), t_lo, t_hi)
        idx = np.clip(np.searchsorted(starts, tt, side="right") - 1, 0, len(results) - 1)
        out = np.empty((base.n_modes, tt.size))
        for i in np.unique(idx):
            sel = idx == i
            out[:, sel] = results[i].modal_velocity_m_s(tt[sel])
        return out

    counter.add("motion_dense")
    plate = base.plate
    assert plate is not None and base.modes is not None
    W = np.asarray(base.modes.evaluate(base.striker_xi, base.striker_eta), dtype=float)  # type: ignore[attr-defined,type-var]
    v_rel = W @ velocity(t0 + t)
    a_rel = np.gradient(v_rel, 1.0 / sample_rate_hz) if n > 1 else np.zeros(n)
    mic = None
    if scene.sensor("mic") is not None:
        counter.add("acoustic")
        mic_xyz = (0.5 * plate.a_m, 0.5 * plate.b_m, scene.mic_distance_m)
        mic = rayleigh_pressure(plate_surface(base, modal_spec(scene).radiation_grid), velocity, t0 + t, mic_xyz)
        if base.corrected:
            def deflection(tt: np.ndarray) -> np.ndarray:
                tt = np.clip(np.asarray(tt, dtype=float), t_lo, t_hi)
                idx = np.clip(np.searchsorted(starts, tt, side="right") - 1, 0, len(results) - 1)
                out = np.empty(tt.size)
                for i in np.unique(idx):
                    sel = idx == i
                    out[sel] = results[i].residual_deflection_m(tt[sel])
                return out
            mic = mic + residual_pressure(base, deflection, t0 + t, mic_xyz)
    eps = [r.impacts for r in results[(0 if settle is None else 1):]]
    cat: Callable[[list[np.ndarray]], np.ndarray] = lambda parts: np.concatenate(parts) if parts else np.empty(0)
    counts = np.array([len(e) for e in eps], dtype=np.int64)
    motion = RunMotion(pieces=pieces, impact_t_s=cat([e.t_s - t0 for e in eps]),
                       impact_v_in_m_s=cat([e.v_in_m_s for e in eps]),
                       impact_v_out_m_s=cat([e.v_out_m_s for e in eps]),
                       impact_level_m_s2=cat([np.full(len(e), p.level_m_s2) for e, p in zip(eps, pieces)]),
                       piece_impacts=counts, theta=theta, level_m_s2=level, freq_hz=freq,
                       v_rel_m_s=v_rel, a_rel_m_s2=a_rel)
    return motion, mic, eps


def truth_modal(scene: Scene, system: ModalSystem) -> Modal:
    """What ``/truth`` states of the main mode: its frequency, damping and participation.

    ``participation = rho h_p L_1 / M_1 = Q1/Q2`` of mode 1 (as the SDF rig's); ``e`` is
    the contact restitution here and is replaced by the median ``e_mode1`` in
    :func:`truth_extra`.
    """
    p = scene.plate
    assert p is not None
    part = float(p.rho_kg_m3 * p.thickness_m * system.load_m2[0] / system.modal_mass_kg[0])
    return Modal(f_s_hz=float(system.omega_rad_s[0]) / TWO_PI, zeta=float(system.zeta[0]),
                 participation=abs(part), gap_m=system.gap_m, e=scene.model.e)


def truth_extra(scene: Scene, system: ModalSystem, contact: Contact, e_mode1: list[tuple[np.ndarray, np.ndarray]],
                extra: dict[str, float | str]) -> tuple[str, float]:
    """Add the modal model's attributes to ``extra``; return the acoustic law text and ``e``.

    ``e`` is the main mode's effective restitution ``e_mode1`` averaged over the
    campaign's impacts with weights ``v_in**2`` (the strong impacts dominate; light
    touches exchange energy with the other modes both ways and their ``e_mode1`` scatter
    widely), clipped to [0, 1]; the scene's ``model.e`` when the campaign has no impact.
    """
    spec = modal_spec(scene)
    e_all = np.concatenate([e for e, _ in e_mode1]) if e_mode1 else np.empty(0)
    w_all = np.concatenate([v**2 for _, v in e_mode1]) if e_mode1 else np.empty(0)
    ok = np.isfinite(e_all)
    e_med = (float(np.clip(np.sum(e_all[ok] * w_all[ok]) / np.sum(w_all[ok]), 0.0, 1.0))
             if ok.any() and np.sum(w_all[ok]) > 0 else math.nan)
    plate = system.plate
    assert plate is not None
    extra.update(model_kind="modal", modal_modes=float(system.n_modes), modal_contact=spec.contact,
                 modal_freqs_hz=" ".join(f"{w / TWO_PI:.6g}" for w in system.omega_rad_s),
                 striker_x_m=system.striker_xi * plate.a_m, striker_y_m=system.striker_eta * plate.b_m,
                 impact_velocity_point="contact point (striker)",
                 mic_distance_m=scene.mic_distance_m, sound_speed_m_s=C_AIR_M_S,
                 radiation_grid=float(spec.radiation_grid))
    law = (f"Rayleigh integral of the baffled plate ({spec.radiation_grid}x{spec.radiation_grid} elements), "
           f"microphone {scene.mic_distance_m!r} m in front of the plate centre, c = {C_AIR_M_S!r} m/s")
    if math.isfinite(e_med):
        extra["e_mode1_weighted"] = e_med
    return law, e_med if math.isfinite(e_med) else scene.model.e


def place_striker(rig: Rig, system: ModalSystem) -> Rig:
    """The rig with the modal model's striker position; the vibrometer and the plate
    accelerometer sit at the striker's point (on the other face), as simulated."""
    plate = system.plate
    assert plate is not None
    xs, ys = system.striker_xi * plate.a_m, system.striker_eta * plate.b_m
    sensors = tuple(dataclasses.replace(s, position_m=(xs, ys, s.position_m[2]))
                    if s.sensor_id in ("velocity", "plate") else s for s in rig.sensors)
    return dataclasses.replace(rig, striker_x_m=xs, striker_y_m=ys, sensors=sensors)
