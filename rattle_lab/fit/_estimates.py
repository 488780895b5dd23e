"""Typed fit results: one estimate (value, stderr, interval, unit, notes) and one class per
fit, each with ``to_dict``/``from_dict`` (the layout is documented in
:mod:`rattle_lab.fit._summary`).

One class per fit: what the fitting function returns (:func:`~rattle_lab.fit.fit_grazing`
a :class:`GrazingSummary`, :func:`~rattle_lab.fit.fit_grazing_ramp` a :class:`RampGrazing`,
:func:`~rattle_lab.fit.fit_zeta_ramp` a :class:`RampDamping`,
:func:`~rattle_lab.fit.fit_restitution_down` a :class:`DownRestitution`,
:func:`~rattle_lab.fit.ratios_of_runs` a :class:`RatioRestitution`,
:func:`~rattle_lab.fit.fit_linear_law` and :func:`~rattle_lab.fit.fit_db_law` a
:class:`LinearLawSummary` and a :class:`DbLawSummary`) is what the store keeps.  A fitting
function's working data that the store does not keep (the points fitted, the model at them,
the chi-square profile, ...) are *working fields* (``metadata={"stored": False}``): left out
of ``to_dict``, of ``==`` and of ``repr``, and empty (or None, NaN) in an object read back.

Every class normalises its fields when built (:class:`_Normalised`): a number that is not
finite becomes None, NumPy scalars become Python numbers, arrays and lists become tuples and
mappings become JSON values -- so ``from_dict(to_dict(x)) == x`` holds exactly.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from rattle_lab.exceptions import SummaryFormatError
from rattle_lab.model.linear import threshold_accel_unchecked

_F = "float | None"


# --- normalisation: the one place where numbers, arrays and mappings become JSON values -------

def _num(x: Any) -> float | None:
    """``float(x)``, or None for None and non-finite values."""
    if x is None:
        return None
    if isinstance(x, (bool, np.bool_, str, bytes)):
        raise TypeError(f"expected a number or None, got {x!r}")
    v = float(x)
    return v if math.isfinite(v) else None


def _int(x: Any) -> int:
    if isinstance(x, (bool, np.bool_)) or isinstance(x, (float, np.floating)) and x != int(x):
        raise TypeError(f"expected an integer, got {x!r}")
    return int(x)


def _nums(xs: Any) -> tuple[float | None, ...]:
    if isinstance(xs, (str, bytes, Mapping)):
        raise TypeError(f"expected a sequence of numbers, got {xs!r}")
    return tuple(_num(x) for x in (np.asarray(xs).ravel() if isinstance(xs, np.ndarray) else xs))


def _strs(xs: Any) -> tuple[str, ...]:
    if isinstance(xs, (str, bytes, Mapping)):
        raise TypeError(f"expected a sequence of strings, got {xs!r}")
    return tuple(_str(x) for x in xs)


def _str(x: Any) -> str:
    if not isinstance(x, str):
        raise TypeError(f"expected a string, got {x!r}")
    return x


def _json(x: Any) -> Any:
    """A JSON value: mappings with str keys, lists, str, int, float (finite), bool, None."""
    if isinstance(x, Mapping):
        return {str(k): _json(v) for k, v in x.items()}
    if isinstance(x, (list, tuple, np.ndarray)):
        return [_json(v) for v in x]
    if x is None or isinstance(x, (str, bool)):
        return x
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return _num(x)
    raise TypeError(f"not a JSON value: {x!r}")


_COERCE: dict[str, Any] = {
    _F: _num,
    "int": _int,
    "bool": lambda v: bool(v) if isinstance(v, (bool, np.bool_)) else _fail("a bool", v),
    "str": _str,
    "tuple[str, ...]": _strs,
    "tuple[float | None, ...]": _nums,
    "tuple[tuple[float | None, ...], ...]": lambda m: tuple(_nums(r) for r in m),
    "dict[str, Any] | None": lambda v: None if v is None else _mapping(v),
    "dict[str, str]": lambda v: {_str(k): _str(w) for k, w in _mapping(v).items()},
    "tuple[dict[str, Any], ...]": lambda v: tuple(_mapping(m) for m in v),
}


def _fail(what: str, v: Any) -> Any:
    raise TypeError(f"expected {what}, got {v!r}")


def _mapping(v: Any) -> dict[str, Any]:
    if not isinstance(v, Mapping):
        raise TypeError(f"expected a mapping, got {v!r}")
    out: dict[str, Any] = _json(v)
    return out


class _Normalised:
    """Mixin: coerce every field to its canonical JSON-compatible form when built.

    The coercion is chosen by the field's annotation (a string, under ``from __future__
    import annotations``) through :data:`_COERCE`; a field of another type (a nested result
    class) is left as given.
    """

    def __post_init__(self) -> None:
        for f in fields(self):  # type: ignore[arg-type]
            coerce = _COERCE.get(str(f.type))
            if coerce is not None:
                try:
                    value = coerce(getattr(self, f.name))
                except (TypeError, ValueError) as exc:
                    raise SummaryFormatError(f"{type(self).__name__}.{f.name}: {exc}") from exc
                object.__setattr__(self, f.name, value)


class _In:
    """A mapping being read by ``from_dict``: every error names the path of the field."""

    def __init__(self, d: Any, path: str):
        if not isinstance(d, Mapping):
            raise SummaryFormatError(f"summary: {path}: expected a mapping, got {d!r}")
        self.d, self.path = d, path

    def __contains__(self, key: str) -> bool:
        return key in self.d

    def __getitem__(self, key: str) -> Any:
        if key not in self.d:
            raise SummaryFormatError(f"summary: {self.path}: missing {key!r}")
        return self.d[key]

    def get(self, key: str, default: Any = None) -> Any:
        return self.d.get(key, default)

    def sub(self, key: str) -> _In:
        return _In(self[key], f"{self.path}.{key}")

    def pair(self, key: str) -> tuple[float | None, float | None]:
        v = self[key]
        if not isinstance(v, (list, tuple)) or len(v) != 2:
            raise SummaryFormatError(f"summary: {self.path}.{key}: expected [low, high], got {v!r}")
        return v[0], v[1]

    def build(self, cls: Any, **kw: Any) -> Any:
        try:
            return cls(**kw)
        except SummaryFormatError as exc:
            raise SummaryFormatError(f"summary: {self.path}: {exc}") from exc


def _work(default: Any = None, *, factory: Any = None) -> Any:
    """A working field: the fitting function's data that the store does not keep (not in
    ``to_dict``, ``==`` or ``repr``; ``from_dict`` leaves it at its default)."""
    kw: dict[str, Any] = dict(compare=False, repr=False, metadata={"stored": False})
    if factory is not None:
        return field(default_factory=factory, **kw)
    return field(default=default, **kw)


def _empty() -> np.ndarray:
    return np.zeros(0)


def stored_fields(obj: Any) -> tuple[str, ...]:
    """The names of the fields of result ``obj`` that ``to_dict`` keeps (all but the working
    fields)."""
    return tuple(f.name for f in fields(obj) if f.metadata.get("stored", True))


# --- estimates ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Estimate(_Normalised):
    """One fitted quantity.

    Attributes
    ----------
    value : float or None
        Best estimate, in ``unit`` (None: not available).
    stderr : float or None
        Standard error, in ``unit`` (None: not identifiable / not computed).
    unit : str
        ``"m"``, ``"Hz"``, ``"1"`` (nondimensional), ...
    ci_low, ci_high : float or None
        Confidence interval as the fit gives it (2 sigma profile interval for the lmfit
        fits); None when not computed.
    notes : tuple of str
        Data-quality notes on this value (e.g. a stderr that leaves out a known bias).
    vary : bool
        False for a parameter held fixed, not fitted (stored only when False, except by
        :class:`GrazingParameter`, which always stores it).

    The one estimate type of :mod:`rattle_lab.fit`: the fitting functions
    (:func:`~rattle_lab.fit.fit_grazing`, :func:`~rattle_lab.fit.fit_zeta_ramp`,
    :func:`~rattle_lab.fit.fit_restitution_down`, ...) return their parameters as
    Estimates, and the store-level fits are made of them; what is not available is None.
    """

    value: float | None
    stderr: float | None
    unit: str
    ci_low: float | None = None
    ci_high: float | None = None
    notes: tuple[str, ...] = ()
    vary: bool = True

    def _base(self, *, ci: bool = True) -> dict[str, Any]:
        d: dict[str, Any] = {"value": self.value, "stderr": self.stderr, "unit": self.unit}
        if ci:
            d["ci"] = [self.ci_low, self.ci_high]
        return d

    @property
    def float_value(self) -> float:
        """``value`` as a float for arithmetic: NaN where it is not available (None)."""
        return float("nan") if self.value is None else self.value

    def _fixed(self, d: dict[str, Any]) -> dict[str, Any]:
        """``d`` with ``"vary": false`` added for a parameter held fixed."""
        if not self.vary:
            d["vary"] = False
        return d

    def to_dict(self) -> dict[str, Any]:
        """``{"value", "stderr", "unit", "ci": [low, high]}``, ``"notes"`` when any and
        ``"vary": false`` for a parameter held fixed."""
        d = self._base()
        if self.notes:
            d["notes"] = list(self.notes)
        return self._fixed(d)

    @staticmethod
    def _read(r: _In, *, ci: bool = True) -> dict[str, Any]:
        lo, hi = r.pair("ci") if ci or "ci" in r else (None, None)
        return dict(value=r["value"], stderr=r["stderr"], unit=r["unit"], ci_low=lo, ci_high=hi,
                    notes=r.get("notes", ()), vary=r.get("vary", True))

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "estimate") -> Estimate:
        """Inverse of :meth:`to_dict`."""
        r = _In(d, path)
        return r.build(cls, **cls._read(r))  # type: ignore[no-any-return]


@dataclass(frozen=True)
class GrazingParameter(Estimate):
    """A parameter of the eq. (3.4) grazing fit (``gap_m`` m, ``f_s_hz`` Hz, ``zeta`` and
    ``participation`` nondimensional).

    Attributes
    ----------
    vary : bool
        False for a parameter held fixed (``participation`` by default); always stored.
    bias_rel : float or None
        ``zeta`` only, with a ramp-replay damping: ``zeta / zeta_ramp - 1`` (eq. 3.4 reads
        the ramp lag as damping; its interval leaves that out).
    bias_note : str
        The same in words ("" when not computed).
    """

    bias_rel: float | None = None
    bias_note: str = ""

    def to_dict(self) -> dict[str, Any]:
        d = self._base()
        if self.notes:
            d["notes"] = list(self.notes)
        d["vary"] = self.vary
        if self.bias_rel is not None or self.bias_note:
            d.update(bias_rel=self.bias_rel, bias_note=self.bias_note)
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "parameter") -> GrazingParameter:
        r = _In(d, path)
        return r.build(cls, **{**cls._read(r), "vary": r["vary"]},  # type: ignore[no-any-return]
                       bias_rel=r.get("bias_rel"), bias_note=r.get("bias_note", ""))


@dataclass(frozen=True)
class GrazingSummary(_Normalised):
    """The eq. (3.4) grazing fit of the upward thresholds (:func:`~rattle_lab.fit.fit_grazing`).

    Attributes
    ----------
    gap_m, f_s_hz, zeta, participation : GrazingParameter
        Gap (m), natural frequency (Hz), damping ratio and modal participation ``Q1/Q2``.
    unidentifiable : tuple of str
        Notes on parameters the data cannot identify.
    outliers_hz : tuple of float
        Frequencies of the points left out as outliers, Hz.
    residuals_ms2 : tuple of float or None
        Model minus measured crossing level per threshold, m/s^2.
    correlation_names : tuple of str
        The varied parameters, in the order of ``correlation``.
    correlation : tuple of tuple of float or None
        Their correlation matrix (None entries without a covariance).
    redchi : float or None
        Reduced chi-square of the relative residuals of the final fit.

    What :func:`~rattle_lab.fit.fit_grazing` returns (without ``bias_rel``, ``bias_note``:
    :func:`~rattle_lab.fit.summarise_fits` adds them against the ramp-corrected fits) and
    the store keeps.  Arithmetic on the tuples: ``np.asarray(fit.residuals_ms2, dtype=float)``
    (None becomes NaN).
    """

    gap_m: GrazingParameter
    f_s_hz: GrazingParameter
    zeta: GrazingParameter
    participation: GrazingParameter
    unidentifiable: tuple[str, ...] = ()
    outliers_hz: tuple[float | None, ...] = ()
    residuals_ms2: tuple[float | None, ...] = ()
    correlation_names: tuple[str, ...] = ()
    correlation: tuple[tuple[float | None, ...], ...] = ()
    redchi: float | None = None

    PARAMETERS = ("gap_m", "f_s_hz", "zeta", "participation")

    @property
    def params(self) -> dict[str, GrazingParameter]:
        """``{"gap_m": ..., "f_s_hz": ..., "zeta": ..., "participation": ...}``."""
        return {n: getattr(self, n) for n in self.PARAMETERS}

    def predict(self, freq_hz: object) -> np.ndarray:
        """Threshold acceleration of the fitted eq. (3.4) at ``freq_hz``, m/s^2 (NaN where a
        parameter is not available)."""
        p = self.params
        return threshold_accel_unchecked(np.asarray(freq_hz, dtype=float),
                                         p["gap_m"].float_value, p["f_s_hz"].float_value,
                                         p["zeta"].float_value, p["participation"].float_value)

    def to_dict(self) -> dict[str, Any]:
        return {**{n: p.to_dict() for n, p in self.params.items()},
                "unidentifiable": list(self.unidentifiable),
                "outliers_hz": list(self.outliers_hz),
                "residuals_ms2": list(self.residuals_ms2),
                "correlation": {"names": list(self.correlation_names),
                                "matrix": [list(row) for row in self.correlation]},
                "redchi": self.redchi}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "fits.grazing") -> GrazingSummary:
        r = _In(d, path)
        corr = r.sub("correlation")
        params = {n: GrazingParameter.from_dict(r[n], f"{path}.{n}") for n in cls.PARAMETERS}
        return r.build(cls, **params, unidentifiable=r["unidentifiable"],  # type: ignore[no-any-return]
                       outliers_hz=r["outliers_hz"], residuals_ms2=r["residuals_ms2"],
                       correlation_names=corr["names"], correlation=corr["matrix"],
                       redchi=r["redchi"])


@dataclass(frozen=True)
class RatioRestitution(Estimate):
    """``e`` as the mean of the per-impact velocity ratios ``-v_out/v_in`` (nondimensional;
    :func:`~rattle_lab.fit.ratios_of_runs`).

    Attributes
    ----------
    std, median : float or None
        Spread and median of the ratios.
    n : int
        Impacts with a velocity on both sides.
    n_runs : int
        Runs they come from; ``stderr`` is clustered by run (0 in summaries that predate it).
    ringing_share, ringing_share_stderr : float or None
        The higher modes' share of each measured velocity jump, pooled over the runs whose
        flight model gave one, and its standard error; the ratios are taken without it
        (:func:`~rattle_lab.fit.ringing_corrected_ratios`) and ``stderr`` includes its
        error.  None where no run gave one (no correction).
    ringing_runs : int
        Runs the share was pooled from.
    ringing_runs_unmeasured : int
        Working field (not stored): runs whose local fits showed ringing after the impacts
        when no run gave a share (their ratios are biased; the store says so in ``notes``
        and the data-quality flags).

    :func:`~rattle_lab.fit.ratios_of_runs` returns it with ``stderr`` from the ratios and
    the share; :func:`~rattle_lab.fit.summarise_fits` adds the vibrometer's delay and
    measurand systematics to ``stderr`` and the notes, and the store keeps that.
    """

    std: float | None = None
    median: float | None = None
    n: int = 0
    n_runs: int = 0
    ringing_share: float | None = None
    ringing_share_stderr: float | None = None
    ringing_runs: int = 0
    ringing_runs_unmeasured: int = _work(0)

    def to_dict(self) -> dict[str, Any]:
        d = {**self._base(ci=self.ci_low is not None or self.ci_high is not None),
             "std": self.std, "median": self.median, "n": self.n, "n_runs": self.n_runs}
        if self.ringing_runs:
            d.update(ringing_share=self.ringing_share,
                     ringing_share_stderr=self.ringing_share_stderr,
                     ringing_runs=self.ringing_runs)
        if self.notes:
            d["notes"] = list(self.notes)
        return self._fixed(d)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "fits.restitution_ratio"
                  ) -> RatioRestitution:
        r = _In(d, path)
        return r.build(cls, **cls._read(r, ci=False), std=r["std"],  # type: ignore[no-any-return]
                       median=r["median"], n=r["n"], n_runs=r.get("n_runs", 0),
                       ringing_share=r.get("ringing_share"),
                       ringing_share_stderr=r.get("ringing_share_stderr"),
                       ringing_runs=r.get("ringing_runs", 0))


@dataclass(frozen=True)
class _RampReplay(Estimate):
    """A parameter fitted to measured ramp thresholds by replaying each ramp through the
    exact simulator (the part common to :class:`RampDamping` and :class:`DownRestitution`).

    Attributes
    ----------
    method : str
        How it was fitted.
    n : int
        Thresholds used.
    residuals_ms2 : tuple of float or None
        Model minus measured threshold, m/s^2, per threshold used.
    freq_hz, accel_ms2, sigma_ms2, model_ms2 : ndarray
        Working fields (not stored): per threshold used, its frequency (Hz), the measured
        threshold, its standard deviation and the model at the fitted value (m/s^2).
    chi2_scale : float
        Working field (not stored): ``s2 = max(1, chi2_min / (n - 1))`` (1 with one point),
        the residual scatter beyond ``sigma_ms2`` that widens the interval (NaN where not
        computed).
    """

    method: str = ""
    n: int = 0
    residuals_ms2: tuple[float | None, ...] = ()
    freq_hz: np.ndarray = _work(factory=_empty)
    accel_ms2: np.ndarray = _work(factory=_empty)
    sigma_ms2: np.ndarray = _work(factory=_empty)
    model_ms2: np.ndarray = _work(factory=_empty)
    chi2_scale: float = _work(math.nan)

    @property
    def params(self) -> dict[str, Estimate]:
        """``{name: self}`` (``"zeta"`` or ``"e"``; the same shape as the other fits)."""
        return {self._PARAM: self}

    _PARAM = ""

    def _extra(self) -> dict[str, Any]:
        return {"method": self.method, "n": self.n}

    def to_dict(self) -> dict[str, Any]:
        return self._fixed({**self._base(), **self._extra(),
                            "residuals_ms2": list(self.residuals_ms2), "notes": list(self.notes)})


@dataclass(frozen=True)
class RampDamping(_RampReplay):
    """``zeta`` refitted to the upward thresholds by replaying each ramp (nondimensional;
    :func:`~rattle_lab.fit.fit_zeta_ramp`, which returns it and the store keeps).

    ``stderr``: linearised, ``sqrt(s2 / sum((g / sigma)^2))`` with ``g = dA/dzeta`` by
    central differences at ``+-2 %``; ``ci_low``, ``ci_high``: ``value -+ 2 stderr``;
    ``notes``: warnings (an estimate at a bound of the search).  Besides the fields of the
    ramp replay (``method``, ``n``, ``residuals_ms2``; working: ``freq_hz``, ``accel_ms2``,
    ``sigma_ms2``, ``model_ms2``, ``chi2_scale``):

    Attributes
    ----------
    run_ids : tuple of str
        Working field (not stored): the runs used, in the order of the arrays.
    chi2 : float
        Working field (not stored): ``sum((residuals / sigma)^2)`` at the fit.
    """

    run_ids: tuple[str, ...] = _work(())
    chi2: float = _work(math.nan)

    _PARAM = "zeta"

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "fits.damping_ramp") -> RampDamping:
        r = _In(d, path)
        return r.build(cls, **cls._read(r), method=r["method"], n=r["n"],  # type: ignore[no-any-return]
                       residuals_ms2=r["residuals_ms2"])


@dataclass(frozen=True)
class DownRestitution(_RampReplay):
    """``e`` from the disappearance (downward) thresholds above resonance (nondimensional;
    :func:`~rattle_lab.fit.fit_restitution_down`, which returns it and the store keeps).

    ``method`` is ``"ramp"`` (the ramp replayed) or ``"quasi-static"`` (the fold of eq.
    3.11).  Ramp method: ``value`` is the vertex of a parabola ``chi2 ~ a (e - value)^2 + c``
    fitted to the profile within ``4 s2`` of its minimum (``s2 = chi2_scale``); ``stderr``
    is ``sqrt(s2 / a)`` (or, without a parabola, half the width of the set where ``chi2 <=
    min + s2``) combined in quadrature with ``stderr_from_zeta``; ``ci_low``, ``ci_high``
    are the outer edges of the set where ``chi2 <= min + 4 s2`` (2 sigma), widened likewise,
    None where the profile does not rise that far inside ``e_bounds`` (see ``notes``).
    Quasi-static: lmfit's standard error and ``value +- 2 stderr``.  Besides the fields of
    the ramp replay (``method``, ``n``, ``residuals_ms2``; working: ``freq_hz``,
    ``accel_ms2``, ``sigma_ms2`` (NaN for quasi-static, which weights by ``1 /
    accel_ms2``), ``model_ms2``, ``chi2_scale``):

    Attributes
    ----------
    run_ids : tuple of str
        The runs whose thresholds were used, in the order of the arrays.
    zeta_used : float or None
        The damping ratio the fit held.
    stderr_from_zeta : float or None
        The part of ``stderr`` propagated from ``zeta``'s (``|de/dzeta| stderr_zeta``).
    e_grid, chi2 : ndarray
        Working fields (not stored): the profile ``chi2(e) = sum(((model(e) - accel) /
        sigma)^2)`` at the values of ``e`` evaluated (ramp method; empty otherwise).
    """

    run_ids: tuple[str, ...] = ()
    zeta_used: float | None = None
    stderr_from_zeta: float | None = None
    e_grid: np.ndarray = _work(factory=_empty)
    chi2: np.ndarray = _work(factory=_empty)

    _PARAM = "e"

    def _extra(self) -> dict[str, Any]:
        return {"method": self.method, "n": self.n, "run_ids": list(self.run_ids),
                "zeta_used": self.zeta_used, "stderr_from_zeta": self.stderr_from_zeta}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "fits.restitution_down"
                  ) -> DownRestitution:
        r = _In(d, path)
        return r.build(cls, **cls._read(r), method=r["method"], n=r["n"],  # type: ignore[no-any-return]
                       residuals_ms2=r["residuals_ms2"], run_ids=r["run_ids"],
                       zeta_used=r["zeta_used"], stderr_from_zeta=r["stderr_from_zeta"])


@dataclass(frozen=True)
class LinearLawSummary(_Normalised):
    """``|p| = slope |v| + intercept``: slope Pa/(m/s), intercept Pa, each with its 95 %
    interval; ``r2`` and the ``n`` points used.  What :func:`~rattle_lab.fit.fit_linear_law`
    returns (:class:`~rattle_lab.fit.LinearLaw` is this class) and the store keeps."""

    slope: float | None
    slope_ci_low: float | None
    slope_ci_high: float | None
    intercept: float | None
    intercept_ci_low: float | None
    intercept_ci_high: float | None
    r2: float | None
    n: int
    slope_unit: str = "Pa/(m/s)"
    intercept_unit: str = "Pa"

    @property
    def slope_ci(self) -> tuple[float | None, float | None]:
        """``(slope_ci_low, slope_ci_high)``."""
        return self.slope_ci_low, self.slope_ci_high

    @property
    def intercept_ci(self) -> tuple[float | None, float | None]:
        """``(intercept_ci_low, intercept_ci_high)``."""
        return self.intercept_ci_low, self.intercept_ci_high

    def to_dict(self) -> dict[str, Any]:
        return {"slope": self.slope, "slope_ci": [self.slope_ci_low, self.slope_ci_high],
                "intercept": self.intercept,
                "intercept_ci": [self.intercept_ci_low, self.intercept_ci_high],
                "r2": self.r2, "n": self.n, "slope_unit": self.slope_unit,
                "intercept_unit": self.intercept_unit}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "linear") -> LinearLawSummary:
        r = _In(d, path)
        s, i = r.pair("slope_ci"), r.pair("intercept_ci")
        return r.build(cls, slope=r["slope"], slope_ci_low=s[0],  # type: ignore[no-any-return]
                       slope_ci_high=s[1], intercept=r["intercept"], intercept_ci_low=i[0],
                       intercept_ci_high=i[1], r2=r["r2"], n=r["n"],
                       slope_unit=r["slope_unit"], intercept_unit=r["intercept_unit"])


@dataclass(frozen=True)
class DbLawSummary(_Normalised):
    """``L = 20 log10 v + c_db``: ``c_db`` in dB re 20 uPa at 1 m/s with its 95 % interval,
    the free slope ``k_db_per_decade`` and ``n`` points.  What
    :func:`~rattle_lab.fit.fit_db_law` returns (:class:`~rattle_lab.fit.DbLaw` is this
    class) and the store keeps."""

    c_db: float | None
    c_ci_low: float | None
    c_ci_high: float | None
    k_db_per_decade: float | None
    n: int
    unit: str = "dB re 20 uPa at 1 m/s"

    @property
    def c_ci(self) -> tuple[float | None, float | None]:
        """``(c_ci_low, c_ci_high)``."""
        return self.c_ci_low, self.c_ci_high

    def to_dict(self) -> dict[str, Any]:
        return {"c_db": self.c_db, "c_ci": [self.c_ci_low, self.c_ci_high],
                "k_db_per_decade": self.k_db_per_decade, "n": self.n, "unit": self.unit}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "db") -> DbLawSummary:
        r = _In(d, path)
        c = r.pair("c_ci")
        return r.build(cls, c_db=r["c_db"], c_ci_low=c[0], c_ci_high=c[1],  # type: ignore[no-any-return]
                       k_db_per_decade=r["k_db_per_decade"], n=r["n"], unit=r["unit"])


@dataclass(frozen=True)
class SplLawSummary:
    """The SPL law of one peak measure (first, max or RMS) against impact velocity."""

    linear: LinearLawSummary
    db: DbLawSummary

    def to_dict(self) -> dict[str, Any]:
        return {"linear": self.linear.to_dict(), "db": self.db.to_dict()}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "spl_law") -> SplLawSummary:
        r = _In(d, path)
        return cls(LinearLawSummary.from_dict(r["linear"], f"{path}.linear"),
                   DbLawSummary.from_dict(r["db"], f"{path}.db"))


@dataclass(frozen=True)
class RampGrazing(_Normalised):
    """Eq. (3.4) refitted to the upward thresholds less each ramp's replayed lag
    (:func:`~rattle_lab.fit.fit_grazing_ramp`, which returns it and the store keeps).

    Attributes
    ----------
    gap_m, f_s_hz, zeta : Estimate
        Gap (m), natural frequency (Hz) and damping ratio, fitted together, with profile
        95 % intervals.
    method : str
        How it was fitted.
    lag_rel : tuple of float or None
        Each threshold's replayed ramp lag relative to its level.
    iterations : int
        Rounds of lag replay and refit.
    grazing : GrazingSummary or None
        Working field (not stored): eq. (3.4) fitted to the lag-corrected levels (per
        frequency: the mean over runs), the fit ``gap_m``, ``f_s_hz``, ``zeta`` come from
        (with the fixed participation, the residuals, the correlation).
    quasi_static : GrazingSummary or None
        Working field (not stored): eq. (3.4) on the uncorrected crossing levels.
    run_ids : tuple of str
        Working field (not stored): the upward thresholds used.
    freq_hz, accel_ms2, lag_ms2 : ndarray
        Working fields (not stored): per threshold, frequency (Hz), measured onset level and
        the replayed lag at the final parameters (m/s^2).
    """

    gap_m: Estimate
    f_s_hz: Estimate
    zeta: Estimate
    method: str = ""
    lag_rel: tuple[float | None, ...] = ()
    iterations: int = 0
    grazing: GrazingSummary | None = _work(None)
    quasi_static: GrazingSummary | None = _work(None)
    run_ids: tuple[str, ...] = _work(())
    freq_hz: np.ndarray = _work(factory=_empty)
    accel_ms2: np.ndarray = _work(factory=_empty)
    lag_ms2: np.ndarray = _work(factory=_empty)

    PARAMETERS = ("gap_m", "f_s_hz", "zeta")

    @property
    def params(self) -> dict[str, Estimate]:
        """``{"gap_m": ..., "f_s_hz": ..., "zeta": ...}``."""
        return {n: getattr(self, n) for n in self.PARAMETERS}

    def to_dict(self) -> dict[str, Any]:
        return {**{n: p.to_dict() for n, p in self.params.items()},
                "method": self.method, "lag_rel": list(self.lag_rel),
                "iterations": self.iterations}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "fits.grazing_ramp") -> RampGrazing:
        r = _In(d, path)
        params = {n: Estimate.from_dict(r[n], f"{path}.{n}") for n in cls.PARAMETERS}
        return r.build(cls, **params, method=r["method"],  # type: ignore[no-any-return]
                       lag_rel=r["lag_rel"], iterations=r["iterations"])


_FIT_TYPES: dict[str, Any] = {
    "grazing": GrazingSummary, "grazing_ramp": RampGrazing, "restitution_ratio": RatioRestitution,
    "damping_ramp": RampDamping, "restitution_down": DownRestitution,
    "spl_law_first": SplLawSummary, "spl_law_max": SplLawSummary, "spl_law_rms": SplLawSummary,
}


@dataclass(frozen=True)
class Fits:
    """The fits that were made (None: not made; :attr:`FitSummary.not_fitted` says why)."""

    grazing: GrazingSummary | None = None
    grazing_ramp: RampGrazing | None = None
    restitution_ratio: RatioRestitution | None = None
    damping_ramp: RampDamping | None = None
    restitution_down: DownRestitution | None = None
    spl_law_first: SplLawSummary | None = None
    spl_law_max: SplLawSummary | None = None
    spl_law_rms: SplLawSummary | None = None

    def spl_law(self, name: str) -> SplLawSummary | None:
        """The SPL law of peak measure ``name`` (``"first"``, ``"max"`` or ``"rms"``)."""
        law: SplLawSummary | None = getattr(self, f"spl_law_{name}")
        return law

    def to_dict(self) -> dict[str, Any]:
        return {n: getattr(self, n).to_dict() for n in _FIT_TYPES if getattr(self, n) is not None}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], path: str = "fits") -> Fits:
        r = _In(d, path)
        unknown = sorted(set(r.d) - set(_FIT_TYPES))
        if unknown:
            raise SummaryFormatError(f"summary: {path}: unknown fit {unknown[0]!r}")
        return cls(**{n: t.from_dict(r[n], f"{path}.{n}") for n, t in _FIT_TYPES.items()
                      if n in r})


__all__ = ["DbLawSummary", "DownRestitution", "Estimate", "Fits", "GrazingParameter",
           "GrazingSummary", "LinearLawSummary", "RampDamping", "RampGrazing", "RatioRestitution",
           "SplLawSummary"]
