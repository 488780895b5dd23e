"""The parameters of detection and fitting: their defaults, their checks, the pipeline file.

``[detect]`` and ``[fit]`` of a pipeline TOML (``rattle-lab fit --pipeline``, and the
same tables of ``rattle-lab run``) are read and checked here; :data:`FIT_KEYS` and
:data:`SOUND_KEYS` are the defaults the fit completes them with.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

from rattle_lab._resources import read_pipeline_toml
from rattle_lab.detect import SOUND_KEYS, DetectParams
from rattle_lab.exceptions import ParameterError

#: Methods of the fit of e to the disappearance thresholds (:func:`fit_restitution_down`).
METHODS: tuple[str, ...] = ("ramp", "quasi-static")
FIT_KEYS = {"participation": None, "vary_participation": False, "outlier_k": 5.0,
            "conf_interval": True, "speed_of_sound_m_s": 343.0, "n_confirm": 3,
            "restitution_method": "ramp", "level_hold_periods": 1,
            "sound_field": "free", "loudness": True,  # [issue 17] acoustics options
            "ecma418_s": 0.0}  # [issue 26] seconds of rattle per run rated by ECMA-418-2


def load_pipeline(path: str | os.PathLike[str] | None) -> dict[str, dict[str, Any]]:
    """Keyword parameters ``{"detect": {...}, "fit": {...}}`` from a pipeline TOML (or defaults).

    ``[detect]`` takes the fields of :class:`~rattle_lab.detect.DetectParams` (those of
    :class:`~rattle_lab.detect.ImpactParams`, ``window_s``, ``first_fraction``,
    ``max_lag_s`` and ``channel``, the channel to detect on; default: chosen by what each
    channel measures), checked by :meth:`~rattle_lab.detect.DetectParams.from_mapping`
    and returned as the table gave them; ``[fit]`` takes
    ``participation`` (``Q1/Q2``; absent: from the records' rig metadata, see
    :func:`~rattle_lab.fit._store.store_participation`), ``vary_participation``, ``outlier_k``, ``conf_interval``,
    ``speed_of_sound_m_s``, ``n_confirm``, ``restitution_method`` (``"ramp"``, the
    default, or ``"quasi-static"``: see :func:`~rattle_lab.fit.fit_restitution_down`),
    ``level_hold_periods`` (forcing periods the drive holds each level of a ramp: 1 for
    a continuous ramp, the default; the synthetic rig holds ``piece_periods``),
    ``sound_field`` (``"free"``, the default, or ``"diffuse"``: the loudness's sound field,
    unless a run says ``x_sound_field``), ``loudness`` (compute ISO 532-1 loudness,
    default true) and ``ecma418_s`` (seconds of rattle episodes per run rated with
    ECMA-418-2 loudness, tonality and roughness; default 0, none: about 7 s of CPU per
    second of sound, and it needs the optional package sottek-hearing-model).
    Other tables are ignored (they belong to other stages); unknown keys in these two
    are errors.

    Raises
    ------
    ParameterError
        For an unreadable file, an unknown key, a ``[detect]`` value out of range, an
        unknown ``restitution_method`` or a ``level_hold_periods`` that is not an
        integer >= 1.
    """
    out: dict[str, dict[str, Any]] = {"detect": {}, "fit": {}}
    if path is None:
        return out
    doc, path = read_pipeline_toml(path)
    for table in ("detect", "fit"):
        values = doc.get(table, {})
        if not isinstance(values, dict):
            raise ParameterError(f"{path}: [{table}] must be a table")
        if table == "detect":
            DetectParams.from_mapping(values, f"{path}: [detect]: ")
        unknown = sorted(set(values) - set(FIT_KEYS)) if table == "fit" else []
        if unknown:
            raise ParameterError(f"{path}: [fit]: unknown key {unknown[0]!r} "
                                 f"(known: {', '.join(sorted(FIT_KEYS))})")
        out[table] = dict(values)
    _check_fit_values(out["fit"], f"{path}: [fit]: ")
    return out


def _check_fit_values(fit: Mapping[str, Any], where: str = "") -> None:
    method = fit.get("restitution_method", FIT_KEYS["restitution_method"])
    if method not in METHODS:
        raise ParameterError(f"{where}`restitution_method` must be one of {METHODS}, "
                             f"was {method!r}")
    if fit.get("sound_field", "free") not in ("free", "diffuse"):  # [issue 17]
        raise ParameterError(f"{where}`sound_field` must be 'free' or 'diffuse', "
                             f"was {fit.get('sound_field')!r}")
    ecma = fit.get("ecma418_s", 0.0)  # [issue 26]
    if isinstance(ecma, bool) or not isinstance(ecma, (int, float)) or not 0 <= ecma < math.inf:
        raise ParameterError(f"{where}`ecma418_s` must be a number >= 0, was {ecma!r}")
    hold = fit.get("level_hold_periods", FIT_KEYS["level_hold_periods"])
    if isinstance(hold, bool) or not isinstance(hold, (int, np.integer)) or hold < 1:
        raise ParameterError(f"{where}`level_hold_periods` must be an integer >= 1, was {hold!r}")


def check_fit_params(fit: Mapping[str, Any] | None) -> dict[str, Any]:
    """``fit`` completed with the defaults of ``FIT_KEYS`` and checked.

    Raises
    ------
    ParameterError
        For an unknown parameter or a value out of range.
    """
    out = {**FIT_KEYS, **dict(fit or {})}
    unknown = sorted(set(out) - set(FIT_KEYS))
    if unknown:
        raise ParameterError(f"unknown fit parameter {unknown[0]!r}")
    _check_fit_values(out)
    return out


__all__ = ["SOUND_KEYS", "FIT_KEYS", "load_pipeline", "check_fit_params"]
