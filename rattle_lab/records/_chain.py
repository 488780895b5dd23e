"""The measurement chain a record declares (schema v2): participation, measurands, delays.

What a fit needs to know about the chain and that v1 records could not say:

* the modal participation factor ``Q1/Q2`` at the measurement point (rig attribute
  ``modal_participation``), or the plate geometry from which the plate model computes it
  (``plate_length_m``, ``plate_width_m``, ``edge_conditions`` in the order of
  :data:`rattle_lab.model.plate.EDGE_ORDER`, ``plate_poisson_ratio``);
* per velocity channel its ``measurand`` (:data:`MEASURANDS`) and ``sign_convention``;
* per channel the known ``group_delay_s`` of its filters (vibrometer decoder, anti-alias),
  which :func:`channel_time_offset_s` subtracts together with ``start_time_s`` before two
  channels are paired; or, where the lab knows the filter's setting but not its delay, the
  filter itself (``filter_type``, ``filter_order``, ``filter_cutoff_hz`` and, for a digital
  filter, ``filter_sample_rate_hz``), whose delay :func:`filter_group_delay_s` computes.

When the participation is neither given nor computable, 1.0 is assumed and the named
data-quality flag :data:`FLAG_PARTICIPATION_ASSUMED` says so.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

from rattle_lab.exceptions import ParameterError

#: What a velocity channel measures: the panel alone, or the panel relative to the striker.
MEASURANDS = ("panel_absolute", "panel_relative_to_striker")
#: Sign conventions of a velocity or acceleration channel.
SIGN_CONVENTIONS = ("toward_striker_positive", "away_from_striker_positive")
#: Low-pass filter families a channel may declare (``filter_type``).
FILTER_TYPES = ("butterworth", "bessel")
#: Highest ``filter_order`` accepted.
MAX_FILTER_ORDER = 16

#: Data-quality flag: no participation in the record or on the command line; 1.0 assumed.
FLAG_PARTICIPATION_ASSUMED = "participation_assumed"
#: Data-quality flag: participation from the plate geometry with Poisson's ratio assumed.
FLAG_POISSON_ASSUMED = "participation_poisson_ratio_assumed"
#: Data-quality flag: a velocity channel does not say what it measures.
FLAG_MEASURAND_UNDECLARED = "velocity_measurand_undeclared"
#: Data-quality flag: the velocity is the panel alone (striker motion not subtracted).
FLAG_MEASURAND_ABSOLUTE = "velocity_panel_absolute"

#: Poisson's ratio assumed for the plate model when the rig does not give it (aluminium).
ASSUMED_POISSON_RATIO = 0.33


@dataclass(frozen=True)
class Participation:
    """The modal participation factor a fit uses, and where it came from.

    Attributes
    ----------
    value : float
        ``Q1/Q2`` of the fitted mode at the measurement point (thesis eq. 2.27), 1.
    source : str
        ``"command line"``, ``"pipeline"``, ``"rig modal_participation"``,
        ``"plate model (...)"`` or ``"assumed"``.
    flags : tuple of str
        Named data-quality flags (:data:`FLAG_PARTICIPATION_ASSUMED`, ...).
    """

    value: float
    source: str
    flags: tuple[str, ...] = ()


def participation_from_plate(length_m: float, width_m: float, edges: str,
                             poisson_ratio: float) -> float:
    """``Q1/Q2`` of the first plate mode (Rayleigh-Ritz; closed form for SSSS).

    ``edges`` are four letters for the edges in the order of
    :data:`rattle_lab.model.plate.EDGE_ORDER` (y=0, x=a, y=b, x=0).  ``Q1`` and ``Q2`` do not
    depend on the plate's thickness, modulus or density, only on its shape, edges and
    Poisson's ratio (the free edges' conditions carry it).
    """
    return _first_mode(float(length_m), float(width_m), str(edges), float(poisson_ratio))[1]


@functools.lru_cache(maxsize=32)
def _first_mode(length_m: float, width_m: float, edges: str,
                poisson_ratio: float) -> tuple[float, float]:
    """``(lambda, Q1/Q2)`` of the plate's first mode (shared by the participation and f1:
    one Ritz solve per plate and process)."""
    from rattle_lab.model.plate import Plate, simply_supported_modes

    plate = Plate(a_m=length_m, b_m=width_m, h_p_m=1e-3, E_pa=7e10, nu=poisson_ratio,
                  rho_kg_m3=2700.0, edges=edges)
    if plate.edges == "SSSS":
        mode = next(iter(simply_supported_modes(plate.aspect_ratio, 1)))
        return float(mode.lam), float(mode.Q1 / mode.Q2)
    first = plate.modes(1)[0]
    return float(first.lam), float(first.Q1 / first.Q2)


def rig_participation(rig: Any) -> Participation | None:
    """The participation a record's rig declares or implies, or None.

    ``modal_participation`` wins; else the plate geometry (``plate_length_m``,
    ``plate_width_m``, ``edge_conditions`` and ``plate_poisson_ratio``; without the ratio
    :data:`ASSUMED_POISSON_RATIO` is used and flagged).
    """
    value = getattr(rig, "modal_participation", None)
    if value is not None:
        return Participation(float(value), "rig modal_participation")
    a, b, edges = rig.plate_length_m, rig.plate_width_m, rig.edge_conditions
    if a is None or b is None or edges is None:
        return None
    nu = getattr(rig, "plate_poisson_ratio", None)
    flags: tuple[str, ...] = ()
    if nu is None:
        nu, flags = ASSUMED_POISSON_RATIO, (FLAG_POISSON_ASSUMED,)
    q = participation_from_plate(float(a), float(b), str(edges), float(nu))
    return Participation(q, f"plate model ({edges}, {a:g} m x {b:g} m, nu = {nu:g})", flags)


#: Young's modulus (Pa) and density (kg/m^3) of the plate materials the plate model knows,
#: by a word of ``plate_material`` (handbook values of the usual alloys; f1 goes as
#: sqrt(E/rho), which the alloys of one metal share to about 2 %).
PLATE_MATERIALS: dict[str, tuple[float, float]] = {
    "aluminium": (7.0e10, 2700.0), "aluminum": (7.0e10, 2700.0),
    "steel": (2.0e11, 7850.0), "stainless": (1.93e11, 8000.0),
    "brass": (1.0e11, 8500.0), "copper": (1.2e11, 8900.0), "titanium": (1.1e11, 4500.0)}


@dataclass(frozen=True)
class PlateF1:
    """The plate model's first natural frequency for a rig that declares its plate."""

    f1_hz: float
    participation: float
    description: str


def plate_model_f1(rig: Any) -> PlateF1 | None:
    """The plate model's f1 (Hz) and ``Q1/Q2`` for the plate ``rig`` declares, or None.

    Needs ``plate_length_m``, ``plate_width_m``, ``plate_thickness_m``, ``edge_conditions``
    and a ``plate_material`` naming one of :data:`PLATE_MATERIALS` (Poisson's ratio:
    ``plate_poisson_ratio`` or :data:`ASSUMED_POISSON_RATIO`).
    """
    from rattle_lab.model.plate import Plate

    a, b, h = rig.plate_length_m, rig.plate_width_m, rig.plate_thickness_m
    edges, material = rig.edge_conditions, rig.plate_material
    if None in (a, b, h, edges, material):
        return None
    words = str(material).lower().replace("-", " ").split()
    known = [w for w in words if w in PLATE_MATERIALS]
    props = PLATE_MATERIALS["stainless" if "stainless" in known else known[0]] if known else None
    if props is None:
        return None
    nu = getattr(rig, "plate_poisson_ratio", None)
    nu = ASSUMED_POISSON_RATIO if nu is None else float(nu)
    plate = Plate(a_m=float(a), b_m=float(b), h_p_m=float(h), E_pa=props[0], nu=nu,
                  rho_kg_m3=props[1], edges=str(edges))
    lam, q = _first_mode(float(a), float(b), plate.edges, nu)   # lambda: no h, E or rho
    return PlateF1(float(plate.frequency_hz(lam)), float(q),
                   f"{edges}, {float(a):g} m x {float(b):g} m x {float(h):g} m {material} "
                   f"(E = {props[0]:.3g} Pa, rho = {props[1]:g} kg/m^3, nu = {nu:g})")


def resolve_participation(rigs: list[Any], given: float | None, given_source: str
                          ) -> Participation:
    """The participation for a fit over records with ``rigs``.

    ``given`` (from the command line or a pipeline) wins.  Else every rig must agree (to
    1e-6 relative) on its :func:`rig_participation`; when none declares one, 1.0 is
    assumed with :data:`FLAG_PARTICIPATION_ASSUMED`.

    Raises
    ------
    ParameterError
        If ``given`` is not a positive finite number, or the records disagree.
    """
    if given is not None:
        if isinstance(given, bool) or not isinstance(given, (int, float)) or \
                not math.isfinite(given) or given <= 0:
            raise ParameterError(f"`participation` must be a finite number > 0, was {given!r}")
        return Participation(float(given), given_source)
    found = [p for p in (rig_participation(r) for r in rigs) if p is not None]
    if not found:
        return Participation(1.0, "assumed", (FLAG_PARTICIPATION_ASSUMED,))
    first = found[0]
    for p in found[1:]:
        if abs(p.value - first.value) > 1e-6 * first.value:
            raise ParameterError(
                f"the records disagree on the modal participation ({first.value:.6g} from "
                f"{first.source}, {p.value:.6g} from {p.source}): fit them separately or give "
                "--participation")
    flags = tuple(sorted({f for p in found for f in p.flags}))
    return Participation(first.value, first.source, flags)


def check_filter(filter_type: Any, filter_order: Any, filter_cutoff_hz: Any,
                 filter_sample_rate_hz: Any = None) -> str | None:
    """What is wrong with a declared low-pass filter (None: nothing, or no filter declared).

    The three attributes come together; ``filter_sample_rate_hz`` (a digital filter) needs
    them and a cut-off below its Nyquist frequency.
    """
    given = [v is not None for v in (filter_type, filter_order, filter_cutoff_hz)]
    if not any(given):
        return ("filter_sample_rate_hz needs filter_type, filter_order and filter_cutoff_hz"
                if filter_sample_rate_hz is not None else None)
    if not all(given):
        return "filter_type, filter_order and filter_cutoff_hz are declared together"
    if filter_type not in FILTER_TYPES:
        return f"filter_type is one of {', '.join(FILTER_TYPES)}, was {filter_type!r}"
    if isinstance(filter_order, bool) or not isinstance(filter_order, (int, float)) or \
            filter_order != int(filter_order) or not 1 <= filter_order <= MAX_FILTER_ORDER:
        return f"filter_order is an integer from 1 to {MAX_FILTER_ORDER}, was {filter_order!r}"
    if not (isinstance(filter_cutoff_hz, (int, float)) and math.isfinite(filter_cutoff_hz)
            and filter_cutoff_hz > 0):
        return f"filter_cutoff_hz is a frequency > 0 Hz, was {filter_cutoff_hz!r}"
    if filter_sample_rate_hz is not None and not (
            isinstance(filter_sample_rate_hz, (int, float))
            and math.isfinite(filter_sample_rate_hz)
            and filter_cutoff_hz < filter_sample_rate_hz / 2):
        return (f"filter_sample_rate_hz must exceed twice filter_cutoff_hz "
                f"({filter_cutoff_hz!r} Hz), was {filter_sample_rate_hz!r}")
    return None


def filter_group_delay_s(filter_type: str, order: int, cutoff_hz: float,
                         sample_rate_hz: float | None = None) -> float:
    """Low-frequency group delay, s, of a declared low-pass filter: the delay with which an
    event (an impact's velocity step, whose centroid a low-pass keeps at ``t + tau(0)``)
    shows in the channel.

    The filter is the ``filter_type`` low-pass of ``order`` with its -3 dB point at
    ``cutoff_hz`` (Bessel: magnitude-normalised, as a data sheet quotes it); analog, or, with
    ``sample_rate_hz``, digital at that rate by the bilinear transform with the cut-off
    prewarped (what ``scipy.signal.butter(..., fs=)`` designs).  For an all-pole prototype
    with poles ``p_k`` the delay at DC is ``sum(-Re p_k / |p_k|**2)``; the bilinear transform
    keeps it, at the prewarped cut-off ``2 fs tan(pi fc / fs)``.

    >>> round(filter_group_delay_s("butterworth", 4, 10e3) * 1e6, 2)   # 1 / (wc sin(pi/8))
    41.59
    >>> round(filter_group_delay_s("butterworth", 4, 10e3, 25600.0) * 1e6, 2)
    18.26
    """
    problem = check_filter(filter_type, order, cutoff_hz, sample_rate_hz)
    if problem is not None:
        raise ParameterError(problem)
    import numpy as np
    from scipy.signal import besselap, buttap

    _, poles, _ = buttap(int(order)) if filter_type == "butterworth" else \
        besselap(int(order), norm="mag")
    wc = 2 * math.pi * cutoff_hz if sample_rate_hz is None else \
        2 * sample_rate_hz * math.tan(math.pi * cutoff_hz / sample_rate_hz)
    p = np.asarray(poles) * wc
    return float(np.sum(-p.real / np.abs(p) ** 2))


def declared_delay_s(channel: Any) -> float | None:
    """The delay a channel declares, s: its ``group_delay_s``, else its declared filter's
    (:func:`filter_group_delay_s`), else None (nothing declared)."""
    delay = getattr(channel, "group_delay_s", None)
    if delay is not None:
        return float(delay)
    kind = getattr(channel, "filter_type", None)
    if kind is None:
        return None
    return filter_group_delay_s(kind, int(channel.filter_order), float(channel.filter_cutoff_hz),
                                getattr(channel, "filter_sample_rate_hz", None))


def channel_time_offset_s(channel: Any) -> float:
    """Seconds to add to a channel's sample times to get the time of the physical event.

    ``-delay``: a filter of known group delay (vibrometer decoder, anti-alias) shows an
    event that much late (:func:`declared_delay_s`: ``group_delay_s``, or the declared
    filter's).  (``start_time_s`` is honoured by the caller's time base.)
    """
    delay = declared_delay_s(channel)
    return -delay if delay else 0.0


__all__ = ["ASSUMED_POISSON_RATIO", "FILTER_TYPES", "FLAG_MEASURAND_ABSOLUTE",
           "FLAG_MEASURAND_UNDECLARED", "MAX_FILTER_ORDER",
           "FLAG_PARTICIPATION_ASSUMED", "FLAG_POISSON_ASSUMED", "MEASURANDS", "PLATE_MATERIALS",
           "Participation", "PlateF1", "SIGN_CONVENTIONS", "channel_time_offset_s",
           "check_filter", "declared_delay_s", "filter_group_delay_s",
           "participation_from_plate", "plate_model_f1", "resolve_participation",
           "rig_participation"]
