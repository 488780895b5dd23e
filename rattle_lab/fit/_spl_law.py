"""SPL law: sound pressure linear in impact velocity (thesis Fig. 6-7), and its dB form.

Linear law ``p = slope * v + intercept`` by ordinary least squares
(``scipy.stats.linregress``) with 95 % t-intervals; dB law
``L = 20 log10(v) + C`` with ``C`` the mean of ``L - 20 log10 v`` (and its
95 % t-interval), plus the free-slope fit ``L = k log10(v) + C'`` as a check (``k`` near 20).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

from rattle_lab.detect import spl_db
from rattle_lab.exceptions import ParameterError
from ._estimates import DbLawSummary, LinearLawSummary


#: The linear SPL law: one class with the stored one (``slope_ci`` is ``(low, high)``).
LinearLaw = LinearLawSummary

#: The dB SPL law: one class with the stored one (``c_ci`` is ``(low, high)``).
DbLaw = DbLawSummary


def _clean(v: object, p: object) -> tuple[np.ndarray, np.ndarray]:
    va = np.abs(np.asarray(v, dtype=float))
    pa = np.abs(np.asarray(p, dtype=float))
    if va.shape != pa.shape:
        raise ParameterError(f"`v_m_s` and `p_pa` must have equal shapes, had {va.shape}, {pa.shape}")
    ok = np.isfinite(va) & np.isfinite(pa) & (va > 0) & (pa > 0)
    if ok.sum() < 3:
        raise ParameterError(f"the SPL law needs >= 3 finite positive (v, p) pairs, had {int(ok.sum())}")
    return va[ok], pa[ok]


def fit_linear_law(v_m_s: object, p_pa: object) -> LinearLawSummary:
    """Fit ``|p| = slope |v| + intercept``.

    Examples
    --------
    >>> import numpy as np
    >>> law = fit_linear_law([0.1, 0.2, 0.3, 0.4], [0.05, 0.10, 0.15, 0.20])
    >>> bool(np.isclose(law.slope, 0.5) and np.isclose(law.r2, 1.0))
    True
    """
    v, p = _clean(v_m_s, p_pa)
    r = stats.linregress(v, p)
    t = stats.t.ppf(0.975, v.size - 2)
    return LinearLawSummary(float(r.slope), float(r.slope - t * r.stderr),
                            float(r.slope + t * r.stderr), float(r.intercept),
                            float(r.intercept - t * r.intercept_stderr),
                            float(r.intercept + t * r.intercept_stderr), float(r.rvalue**2),
                            int(v.size))


def fit_db_law(v_m_s: object, p_pa: object) -> DbLawSummary:
    """Fit ``L = 20 log10 v + C`` (C in dB re 20 uPa at 1 m/s)."""
    v, p = _clean(v_m_s, p_pa)
    level = spl_db(p)
    c = level - 20.0 * np.log10(v)
    sem = float(stats.sem(c)) if c.size > 1 else np.nan
    t = stats.t.ppf(0.975, c.size - 1)
    k = float(stats.linregress(np.log10(v), level).slope)
    return DbLawSummary(float(np.mean(c)), float(np.mean(c) - t * sem),
                        float(np.mean(c) + t * sem), k, int(v.size))
