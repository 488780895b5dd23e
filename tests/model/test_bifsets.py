"""Tests of rattle_lab.model.analysis.bifsets: traced boundary curves, regions, plot.

The traced curves are checked against the condition each one stands for,
evaluated independently (multipliers, clearance, eq. 3.4, eq. 3.11), against
the sweep events at F = 0.2 and the thesis's statements (section 3.3, 4.2).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from rattle_lab.exceptions import OutputError, ParameterError
from rattle_lab.model.analysis import bifsets
from rattle_lab.model.analysis.bifsets import BifurcationSets, bifurcation_sets
from rattle_lab.model.analysis.orbits import (
    branch_events,
    floquet_multipliers,
    grazing_forcing,
    one_over_n_orbits,
    orbit_clearance,
    orbit_forcing,
    saddle_node_forcing,
)
from rattle_lab.model.sdf import SDFParams
from rattle_lab.plot import plot_bifurcation_sets

ZETA, E = 0.05, 0.6


@pytest.fixture(scope="module")
def sets() -> BifurcationSets:
    # The thesis's domain (Fig. 3-10) on a coarse grid: the curves are refined to the exact
    # boundary whatever the grid, the grid only decides which pieces are found.
    return bifurcation_sets([1, 2, 3], omega_range=(0.6, 1.5), F_range=(0.0, 0.6),
                            zeta=ZETA, e=E, n_omega=91, n_F=61, n_v=41)


def test_every_kind_is_traced(sets: BifurcationSets) -> None:
    kinds = {(c.n, c.kind) for c in sets.curves}
    for n in (1, 2, 3):
        assert (n, "grazing") in kinds and (n, "saddle-node") in kinds
        assert (n, "period-doubling") in kinds
    assert (2, "secondary-grazing") in kinds and (3, "secondary-grazing") in kinds
    for c in sets.curves:
        assert c.omega.shape == c.F.shape == c.v_im.shape and c.omega.size >= 2
        assert np.all((c.F >= 0.0) & (c.F <= 0.6)) and np.all((c.omega >= 0.6) & (c.omega <= 1.5))


def test_curves_satisfy_their_conditions(sets: BifurcationSets) -> None:
    for c in sets.curves:
        F, _ = orbit_forcing(c.n, c.omega, c.v_im, ZETA, E)
        np.testing.assert_allclose(F, c.F, rtol=1e-12)
        if c.kind == "grazing":
            np.testing.assert_allclose(c.F, grazing_forcing(c.omega, ZETA), rtol=1e-12)
        elif c.kind == "saddle-node":
            F_sn, v_sn = saddle_node_forcing(c.n, c.omega, ZETA, E)
            np.testing.assert_allclose(c.F, F_sn, rtol=1e-12)
            assert np.all(v_sn > 0)
        elif c.kind == "period-doubling":
            l1, l2 = floquet_multipliers(c.n, c.omega, c.v_im, ZETA, E)
            nearest = np.where(np.abs(l1 + 1) < np.abs(l2 + 1), l1, l2)
            # Bisection to 2**-32 of a grid edge: |P(-1)| ~ slope * edge * 2**-32.
            np.testing.assert_allclose(nearest, -1.0, atol=1e-6)
            clear, _ = orbit_clearance(c.n, c.omega, c.v_im, ZETA, E)
            assert np.all(clear > 0)  # kept only where the orbit exists
        else:
            clear, _ = orbit_clearance(c.n, c.omega, c.v_im, ZETA, E)
            np.testing.assert_allclose(clear, 0.0, atol=1e-7)
            assert np.all(c.v_im > 0)


def _omega_at_F(sets: BifurcationSets, n: int, kind: str, F: float, near: float) -> float:
    hits = []
    for c in sets.curves_of(n, kind):  # type: ignore[arg-type]
        s = np.sign(c.F - F)
        for i in np.flatnonzero(s[:-1] * s[1:] < 0):
            f = (F - c.F[i]) / (c.F[i + 1] - c.F[i])
            hits.append(c.omega[i] + f * (c.omega[i + 1] - c.omega[i]))
    hits = [h for h in hits if abs(h - near) < 0.01]
    assert len(hits) == 1, (n, kind, hits)
    return float(hits[0])


@pytest.mark.parametrize("n, kind, omega_thesis", [
    (1, "saddle-node", 1.230), (2, "secondary-grazing", 0.985), (3, "secondary-grazing", 0.953),
    (2, "period-doubling", 0.973), (3, "period-doubling", 0.950)])
def test_curves_cross_F02_at_the_sweep_events_and_the_thesis_values(
        sets: BifurcationSets, n: int, kind: str, omega_thesis: float) -> None:
    w = _omega_at_F(sets, n, kind, 0.2, omega_thesis)
    assert w == pytest.approx(omega_thesis, abs=2e-3)  # thesis 4.2, 3 digits
    ev = [x for x in branch_events(n, 0.2, omega_range=(omega_thesis - 0.01, omega_thesis + 0.01),
                                   zeta=ZETA, e=E, n_omega=20) if x.kind == kind]
    assert len(ev) == 1
    # Linear interpolation between refined vertices of a coarse grid: error ~ curvature * step^2.
    assert w == pytest.approx(ev[0].omega, abs=2e-4)


def test_regions_agree_with_the_pointwise_orbits(sets: BifurcationSets) -> None:
    rng = np.random.default_rng(11)
    for _ in range(150):
        i, j = rng.integers(sets.F.size), rng.integers(sets.omega.size)
        F, w = float(sets.F[i]), float(sets.omega[j])
        if F == 0.0:
            continue
        for k, n in enumerate(sets.ns):
            orbs = one_over_n_orbits(SDFParams(F=F, omega=w, zeta=ZETA, e=E), n)
            assert sets.exists[k, i, j] == any(o.exists for o in orbs)
            assert sets.stable[k, i, j] == any(o.exists and o.stable for o in orbs)


def test_thesis_section_3_3_statements(sets: BifurcationSets) -> None:
    k2 = sets.ns.index(2)
    # "Note we don't have any region of existence for 1/2 when omega > 1" (Fig. 3-7).
    assert not sets.exists[k2][:, sets.omega > 1.0].any()
    # Every 1/n region lies above the grazing curve's minimum F = 2 zeta sqrt(1 - zeta^2).
    F_min = 2 * ZETA * math.sqrt(1 - ZETA ** 2)
    assert not sets.exists[:, sets.F < F_min - 1e-3, :].any()
    # The stable 1/1 region at F = 0.2 ends at the saddle-node 1.230 (thesis 4.2).
    k1 = sets.ns.index(1)
    i = int(np.argmin(np.abs(sets.F - 0.2)))
    stable_w = sets.omega[sets.stable[k1, i]]
    assert stable_w.max() == pytest.approx(1.23, abs=sets.omega[1] - sets.omega[0] + 2e-3)


def test_to_dict_is_json(sets: BifurcationSets) -> None:
    doc = json.loads(json.dumps(sets.to_dict(include_regions=True)))
    assert doc["ns"] == [1, 2, 3]
    assert np.array(doc["exists"]).shape == sets.exists.shape
    assert {c["kind"] for c in doc["curves"]} == set(bifsets.KINDS)
    assert doc["provenance"]["function"] == "rattle_lab.model.analysis.bifurcation_sets"


def test_plot_pdf_structure(sets: BifurcationSets, tmp_path: Path) -> None:
    pypdf = pytest.importorskip("pypdf")
    out = plot_bifurcation_sets(sets, tmp_path / "bif.pdf")
    assert out == tmp_path / "bif.pdf"
    reader = pypdf.PdfReader(str(out))
    assert len(reader.pages) == 1
    text = reader.pages[0].extract_text()
    for label in ("forcing frequency omega (nondimensional)",
                  "forcing amplitude F (nondimensional)", "1/2 stable", "grazing, eq. (3.4)",
                  "period-doubling", "secondary-grazing", "saddle-node"):
        assert label in text
    assert [p.name for p in tmp_path.iterdir()] == ["bif.pdf"]  # no temporary left


def test_plot_png_and_errors(sets: BifurcationSets, tmp_path: Path) -> None:
    out = plot_bifurcation_sets(sets, tmp_path / "bif.png")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with pytest.raises(ParameterError, match=r"plot file '.*bif.txt' must end in .png, .pdf or .svg"):
        plot_bifurcation_sets(sets, tmp_path / "bif.txt")
    with pytest.raises(OutputError, match="output directory .*missing does not exist"):
        plot_bifurcation_sets(sets, tmp_path / "missing" / "bif.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bif.png"]


@pytest.mark.parametrize("kwargs, message", [
    ({"ns": []}, r"`ns` must name at least one n, was empty"),
    ({"ns": [0]}, r"`ns` must hold integers >= 1, was 0"),
    ({"omega_range": (1.5, 0.6)}, r"`omega_range` must satisfy 0 < lo < hi, was \(1.5, 0.6\)"),
    ({"F_range": (-0.1, 0.6)}, r"`F_range` must satisfy 0 <= lo < hi, was \(-0.1, 0.6\)"),
    ({"zeta": 0.0}, r"`zeta` must be > 0 for bifurcation sets, was 0.0"),
    ({"e": 1.2}, r"`e` must be in \(0, 1\], was 1.2"),
    ({"n_F": 3}, r"`n_F` must be an integer >= 8, was 3"),
])
def test_bad_arguments(kwargs: dict, message: str) -> None:
    args = {"ns": [1]} | kwargs
    with pytest.raises(ParameterError, match=message):
        bifurcation_sets(**args)


def test_bifsets_doctests() -> None:
    import doctest

    result = doctest.testmod(bifsets)
    assert result.failed == 0 and result.attempted > 0


def test_workers_give_the_serial_sets(sets: BifurcationSets) -> None:
    """The orbit types on 2 local worker processes: regions and curves equal bit for bit."""
    pooled = bifurcation_sets([1, 2, 3], omega_range=(0.6, 1.5), F_range=(0.0, 0.6),
                              zeta=ZETA, e=E, n_omega=91, n_F=61, n_v=41, workers=2)
    np.testing.assert_array_equal(pooled.exists, sets.exists)
    np.testing.assert_array_equal(pooled.stable, sets.stable)
    assert len(pooled.curves) == len(sets.curves) > 3
    for a, b in zip(pooled.curves, sets.curves):
        assert (a.n, a.kind) == (b.n, b.kind)
        for name in ("omega", "F", "v_im"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
