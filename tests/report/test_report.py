"""The PDF report (:mod:`rattle_lab.report`): structure, reproducibility, missing sections.

Checked by reading the PDF back with pypdf (page count, text, drawings), not pixels.
"""

from __future__ import annotations

import dataclasses
import re
import shutil
from pathlib import Path
from types import SimpleNamespace

import h5py
import numpy as np
import pypdf
import pytest

from rattle_lab.exceptions import OutputError, ParameterError, RattleLabError
from rattle_lab.fit import (DownRestitution, FitSummary, Fits, GrazingParameter, GrazingSummary,
                            RatioRestitution)
from rattle_lab.store import read_results
from rattle_lab.store import StoreError
from rattle_lab.report import ReportResult
from rattle_lab.report import write_pdf
from rattle_lab.workflow import build_pages, build_report_content, gather, write_report
from rattle_lab.fit import band_quantile, grazing_band_ms2
from rattle_lab.report._common import TEXT_WIDTH
from rattle_lab.workflow._report._summary import parameter_lines, summary_lines
from report_images import (TILE_TOLERANCE, load_reference, reference_paths, structure_rasters,
                           worst_tile)


@pytest.fixture(scope="module")
def stores(report_stores: dict[str, Path]) -> dict[str, Path]:
    """An ingest-only store and a fitted copy of it (the session's, ``conftest.py``)."""
    return report_stores


def _texts(path: Path) -> list[str]:
    return [page.extract_text() for page in pypdf.PdfReader(path).pages]


def test_full_report_structure(stores: dict[str, Path], full_report: tuple[ReportResult, Path]
                               ) -> None:
    result, path = full_report
    assert result.path == path and path.is_file()
    assert result.sections == ("summary", "rig and calibration", "thresholds", "impact patterns",
                               "waveforms", "SPL law", "acoustics", "model predictions")
    assert result.missing == {}
    texts = _texts(path)
    n = result.n_pages
    assert len(texts) == n == 11  # summary 2, rig, thresholds, patterns, waveforms, SPL,
    # acoustics 2 (levels; what a listener hears), 2 model
    for i, text in enumerate(texts, start=1):
        assert f"Page {i} of {n}" in text
    summary = texts[0] + texts[1]
    for key in ("gap h (ramp-corrected)", "zeta (ramp-corrected)", "f_s, ramp-corrected",
                "participation Q1/Q2", "gap h, eq. (3.4)", "zeta, eq. (3.4)", "f_s, eq. (3.4)",
                "e (velocity ratios)", "e (disappearance thresholds)", "95 % CI",
                "SPL first peak: slope", "Pa/(m/s)", "dB re 20 uPa at 1 m/s", "mm", "Hz",
                "Data-quality flags", "Provenance", "xxh3_128:", "rattle_lab 0.",
                "[fit] conf_interval = True"):
        assert key in summary, key
    assert "missing:" not in summary
    # no channel is flagged by ingest (a flagged channel is listed as key/run/channel: flags);
    # a hysteresis is listed only where it is below zero by more than its uncertainty (issue
    # 23): the default scene's 95 Hz ramps lie in the irregular regime, where another libm or
    # BLAS moves a threshold by a forcing cycle and the sign of its small hysteresis with it
    flags = summary.split("Data-quality flags")[1].split("Provenance")[0]
    assert "/" not in flags.replace("m/s^2", "")
    th = read_results(stores["fitted"]).thresholds
    h = th["up_ms2"] - th["down_ms2"]
    u = np.hypot(th["up_se_ms2"], th["down_se_ms2"])
    assert np.all(np.isfinite(u[np.isfinite(h)])) and np.all(u[np.isfinite(h)] > 0)
    for f_hz, h_f, u_f in zip(th["freq_hz"], h, u):
        assert (f"NEGATIVE hysteresis at {f_hz:g} Hz" in flags) == bool(h_f < -2.0 * u_f)


def test_summary_values_come_from_results(stores: dict[str, Path]) -> None:
    data = gather(stores["fitted"])
    g = data.results.summary["fits"]["grazing"]
    table = "\n".join(parameter_lines(data))
    row = next(ln for ln in table.splitlines() if ln.startswith("  gap h, eq. (3.4)"))
    value = float(row.split()[4])
    lo, hi = (float(x) for x in row[row.index("[") + 1:row.index("]")].split(", "))
    # printed with the digits the interval needs (at least 4 significant): within 1e-4
    assert value == pytest.approx(g["gap_m"]["value"] * 1e3, rel=1e-4)
    assert (lo, hi) == pytest.approx(tuple(1e3 * x for x in g["gap_m"]["ci"]), rel=1e-4)
    e = data.results.summary["fits"]["restitution_ratio"]
    assert f"{e['value']:.4g}"[:5] in table and f"from {e['n']} impacts" in table
    # every line fits the page (the text is monospaced, TEXT_WIDTH characters wide)
    assert max(len(line) for line in summary_lines(data, "0")) <= TEXT_WIDTH


def test_parameter_table_flags_unidentified_and_missing_fits() -> None:
    summary = FitSummary(n_runs=2, n_ok=2, fits=Fits(
        restitution_ratio=RatioRestitution(0.6, 0.01, "1", n=11),
        restitution_down=DownRestitution(0.999, 1.7, "1", n=2)),
        not_fitted={"grazing": "needs >= 4 upward thresholds, had 2",
                    "spl_law_first": "no microphone"})
    data = SimpleNamespace(results=SimpleNamespace(summary=summary.to_dict()), summary=summary,
                           missing={})
    text = "\n".join(parameter_lines(data))  # type: ignore[arg-type]
    assert "not fitted: needs >= 4 upward thresholds, had 2" in text
    assert "not fitted: no microphone" in text
    assert "NOT IDENTIFIED" in text.split("e (disappearance thresholds)")[1]
    assert "NOT IDENTIFIED" not in text.split("e (disappearance thresholds)")[0]
    # Student t with n - 1 = 10 degrees of freedom: t(0.975, 10) = 2.228139
    half = 2.2281388519649385 * 0.01
    assert f"[{0.6 - half:.4g}, {0.6 + half:.4g}]" in text


def test_every_figure_page_has_labelled_axes_and_drawings(full_report: tuple[ReportResult, Path]
                                                          ) -> None:
    _, path = full_report
    reader = pypdf.PdfReader(path)
    texts = [p.extract_text() for p in reader.pages]
    expected = {"rig and calibration": ["channel", "sensitivity", "PCB 352C33", "mV/g",
                                        "Sensors and calibration"],
                "thresholds": ["excitation frequency (Hz)", "(m/s^2)", "eq. (3.4) fit",
                               "ramp-corrected", "hysteresis", "95 % confidence band",
                               "less the fit (m/s^2)"],
                "impact patterns": ["excitation frequency (Hz)", "amplitude (m/s^2)",
                                    "1 impact per cycle"],
                "waveforms": ["time (s)", "plate acceleration (m/s^2)", "plate velocity (m/s)",
                              "sound pressure (Pa)", "first peak", "maximum peak"],
                "SPL law": ["impact velocity |v_in| (m/s)", "sound pressure (Pa)",
                            "95 % bands", "a later peak is larger than the first",
                            "one line through both branches"],
                "acoustics": ["third-octave band centre frequency (Hz)",
                              "band level (dB re 20 uPa)", "LAeq", "LAFmax", "LCpeak",
                              "ISO 532-1 loudness (sone)", "N5",
                              "RMS impact velocity of the run (m/s)",
                              "no calibrator record: the declared microphone sensitivity is "
                              "used",
                              # the second page: what a listener judges (issue 26)
                              "Impulsiveness (ISO/PAS 1996-3:2022", "K_I (dB)",
                              "loudness above background (sone)", "impact rate (1/s)",
                              "ECMA-418-2 loudness, tonality and roughness: not computed"],
                "model predictions": ["omega = f / f_s (nondimensional)",
                                      "F = Q A / (omega_s^2 h) (nondimensional)",
                                      "measured onset", "saddle-node", "model onset"]}
    for section, keys in expected.items():
        pages = [t for t in texts if f" - {section} - " in " ".join(t.split())]
        assert pages, section
        for key in keys:
            assert any(key in " ".join(t.split()) for t in pages), (section, key)
    for page in reader.pages[2:]:  # vector drawings: path operators in the content stream
        content = page.get_contents().get_data()
        assert b" l\n" in content or b" l " in content or b" re" in content


def test_no_text_overlaps_the_page_footer(stores: dict[str, Path]) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    pages, sections = build_pages(gather(stores["fitted"]), model=False)
    assert sections[0] == "summary" and len(pages) == 9
    for name, fig in pages:
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        renderer = canvas.get_renderer()
        footer = fig.texts[-1]
        assert footer.get_text().startswith("Page ")
        box = footer.get_window_extent(renderer)
        for ax in fig.axes:
            if ax.get_visible() and ax.axison:  # the rig tables' axes are switched off
                assert not ax.get_tightbbox(renderer).overlaps(box), name
        for text in fig.texts[:-1]:
            assert not text.get_window_extent(renderer).overlaps(box), (name, text.get_text())
            assert text.get_window_extent(renderer).x1 <= fig.bbox.x1, (name, text.get_text())


def test_every_axis_is_labelled_with_its_unit(stores: dict[str, Path]) -> None:
    pages, _ = build_pages(gather(stores["fitted"]), model=True)
    unit = re.compile(r"\((Hz|s|m/s|m/s\^2|Pa|nondimensional|[^()]*m/s\^2[^()]*|dB re 20 uPa|"
                      r"sone|dB|1/s)\)")
    n_axes = 0
    for name, fig in pages:
        plots = [ax for ax in fig.axes if ax.get_visible() and ax.axison]
        for ax in plots:
            n_axes += 1
            assert unit.search(ax.get_ylabel()), (name, ax.get_ylabel())
            if ax.get_xlabel():
                assert unit.search(ax.get_xlabel()), (name, ax.get_xlabel())
            else:  # a shared time axis: labelled on the bottom plot of its column
                assert any(o.get_xlabel() and o.get_xlim() == ax.get_xlim() for o in plots), name
    assert n_axes == 19  # thresholds 3, patterns 1, waveforms 3 x 2, SPL 1, acoustics 3 + 3
    # (the ECMA-418-2 panel is a note: not computed by default), model pages 2


def test_same_store_gives_identical_bytes(stores: dict[str, Path], full_report, tmp_path: Path
                                          ) -> None:
    _, first = full_report
    again = write_report(stores["fitted"], tmp_path / "again.pdf")
    assert again.path.read_bytes() == first.read_bytes()
    meta = pypdf.PdfReader(first).metadata
    assert "/CreationDate" not in meta and "/ModDate" not in meta


def test_store_without_results_says_why(stores: dict[str, Path], tmp_path: Path) -> None:
    out = tmp_path / "bare.pdf"
    result = write_report(stores["bare"], out)
    assert result.sections == ("summary", "rig and calibration")
    assert set(result.missing) == {"results", "thresholds", "impact patterns", "waveforms",
                                   "SPL law", "acoustics", "model predictions"}
    assert "rattle-lab fit" in result.missing["results"]
    texts = _texts(out)
    assert len(texts) == result.n_pages == 2
    assert "missing: thresholds: " in texts[0] and "rattle-lab fit" in texts[0]
    assert "Page 2 of 2" in texts[1]


def test_partial_results_drop_only_their_sections(stores: dict[str, Path], tmp_path: Path
                                                  ) -> None:
    store = tmp_path / "partial.h5"
    shutil.copyfile(stores["fitted"], store)
    with h5py.File(store, "a") as fh:  # thresholds lost, e.g. a campaign of dwells only
        for name in ("freq_hz", "up_ms2", "down_ms2", "hysteresis_ms2"):
            del fh[f"results/thresholds/{name}"]
            fh["results/thresholds"].create_dataset(name, data=np.zeros(0))
    # what write_report draws (its sections and what it says is missing) is this content;
    # the drawing itself is checked on the full report
    content = build_report_content(gather(store), model=False)
    assert "thresholds" in content.missing and "ramp thresholds" in content.missing["thresholds"]
    assert content.missing["model predictions"] == "not requested (model=False)"
    drawn = [name for name, _ in content.sections]
    assert {"waveforms", "SPL law", "impact patterns"} <= set(drawn) and "thresholds" not in drawn


def test_grazing_band_against_closed_form() -> None:
    # one varied parameter (gap): the threshold is linear in gap, so the delta-method band is
    # exactly 1.96 * stderr * A / gap (tolerance: central differences, relative 1e-6 step).
    g = GrazingSummary(gap_m=GrazingParameter(1e-3, 1e-4, "m"),
                       f_s_hz=GrazingParameter(96.0, None, "Hz"),
                       zeta=GrazingParameter(0.01, None, "1"),
                       participation=GrazingParameter(1.0, None, "1", vary=False),
                       correlation_names=("gap_m",), correlation=((1.0,),))
    f = np.array([90.0, 96.0, 100.0])
    y, half = grazing_band_ms2(f, g)
    np.testing.assert_allclose(half, 1.96 * 1e-4 * y / 1e-3, rtol=1e-6)


def test_band_uses_student_t_with_the_fit_degrees_of_freedom() -> None:
    p = GrazingParameter(1.0, 0.1, "1")
    g = GrazingSummary(gap_m=p, f_s_hz=p, zeta=p, participation=p,
                       residuals_ms2=(0.1, -0.2, 0.0, 0.3, 0.1), outliers_hz=(97.0,),
                       correlation_names=("gap_m", "f_s_hz"), correlation=((1, 0), (0, 1)))
    q, dof = band_quantile(g)
    assert dof == 2 and np.isclose(q, 4.302652729749464)  # t(0.975, 2), scipy reference
    g = dataclasses.replace(g, correlation_names=g.correlation_names + ("zeta",))
    assert band_quantile(g)[1] == 1
    # 4 points (5 less an outlier), 4 parameters
    g = dataclasses.replace(g, correlation_names=g.correlation_names + ("participation",))
    assert band_quantile(g)[1] == 0 and np.isnan(band_quantile(g)[0])


def test_errors(stores: dict[str, Path], tmp_path: Path) -> None:
    with pytest.raises(StoreError, match="no such store"):
        write_report(tmp_path / "absent.h5", tmp_path / "r.pdf")
    text = tmp_path / "not_a_store.h5"
    text.write_text("hello")
    with pytest.raises(RattleLabError):
        write_report(text, tmp_path / "r.pdf")
    with pytest.raises(ParameterError, match=r"`output` must end in \.pdf"):
        write_report(stores["bare"], tmp_path / "r.png")
    with pytest.raises(OutputError, match="does not exist"):
        write_report(stores["bare"], tmp_path / "no_dir" / "r.pdf", model=False)
    assert not (tmp_path / "r.pdf").exists()


# --- pages read back as images, and the figure guards (issue 17, 23, 27) ---------------------
#
# The drawn structure of each page (text removed, rasterised by PDFium, blurred) is compared
# with the reference images in tests/data/report_pages/ tile by tile (tests/report_images.py
# says how and why it survives other fonts and FreeType builds).  The tests only compare:
# after an intended change, `make reference-images` (tests/regen_reference_images.py)
# rewrites the references, to be looked at before they are committed.


def test_report_pages_match_reference_images(snapshot_report,
                                             snapshot_rasters: list[np.ndarray]) -> None:
    _, result, _ = snapshot_report
    assert len(snapshot_rasters) == result.n_pages
    refs = reference_paths()
    assert len(refs) == len(snapshot_rasters), \
        "reference images out of date: run `make reference-images` and look at them"
    for i, (img, ref_path) in enumerate(zip(snapshot_rasters, refs), start=1):
        ref = load_reference(ref_path)
        assert img.shape == ref.shape, (i, img.shape, ref.shape)
        assert worst_tile(img, ref) <= TILE_TOLERANCE, (i, worst_tile(img, ref))
        assert (img.std() > 5.0) == (ref.std() > 5.0)  # a drawing where the reference has
        # one (the summary pages are text only: blank here)


def test_the_snapshot_has_the_live_reports_sections_and_pages(
        snapshot_report, report_content, full_report: tuple[ReportResult, Path]) -> None:
    # the images are drawn from the content snapshot (tests/report_images.py says why); the
    # report simulated, ingested and fitted in this run has the same sections, the same
    # content types and as many pages; else `make reference-images` is due
    content, result, _ = snapshot_report
    live = dict(report_content.sections)
    assert [name for name, _ in content.sections] == list(live), \
        "content snapshot out of date: run `make reference-images` and look at the images"
    for name, section in content.sections:
        assert type(section) is type(live[name]), name
        assert [f.name for f in dataclasses.fields(section)] == \
            [f.name for f in dataclasses.fields(live[name])], name
    assert result.n_pages == full_report[0].n_pages


def test_no_test_writes_a_reference_image() -> None:
    # issue 23: regenerating is an explicit command, never a side effect of a test; the
    # names are built here so that this file does not hold them
    tests = Path(__file__).resolve().parents[1]
    writer, switch = "save_" + "references", "RATTLE_LAB_" + "REGEN_REFS"
    for path in tests.rglob("test_*.py"):
        text = path.read_text(encoding="utf-8")
        assert writer not in text and switch not in text, path


def _page_of(result: ReportResult, path: Path, section: str) -> int:
    """0-based index of the first page of ``section``."""
    reader = pypdf.PdfReader(path)
    for i, page in enumerate(reader.pages):
        if f" - {section} - " in " ".join(page.extract_text().split()):
            return i
    raise AssertionError(section)


@pytest.fixture(scope="module")
def variant_rasters(snapshot_report, tmp_path_factory: pytest.TempPathFactory):
    """Rasters of the same content drawn another way: ``name -> pages``.

    ``serif``: every page in another font family; the damaged ones: the summary and the one
    damaged section only (its page is then the last), to keep the test short.
    """
    import matplotlib

    report_content = snapshot_report[0]
    folder = tmp_path_factory.mktemp("variants")
    sections = dict(report_content.sections)
    spl, th = sections["SPL law"], sections["thresholds"]
    no_lines = dataclasses.replace(spl, curves=tuple(
        dataclasses.replace(c, line_pa=np.full_like(c.line_pa, np.nan)) for c in spl.curves))
    no_band = dataclasses.replace(th, curve=dataclasses.replace(th.curve, band_ms2=None))
    cases = {"serif": ({"font.family": "DejaVu Serif"}, report_content.sections),
             "no SPL lines": ({}, (("SPL law", no_lines),)),
             "no band": ({}, (("thresholds", no_band),))}
    out: dict[str, list[np.ndarray]] = {}
    for name, (rc, chosen) in cases.items():
        content = dataclasses.replace(report_content, sections=tuple(chosen))
        pdf = folder / f"{name.replace(' ', '_')}.pdf"
        with matplotlib.rc_context(rc):
            write_pdf(content, pdf)
        out[name] = structure_rasters(pdf)
    return out


def test_reference_comparison_survives_another_font(variant_rasters,
                                                    snapshot_rasters: list[np.ndarray]) -> None:
    # another font family (wider glyphs) moves the drawing through the layout: every page
    # stays within the tolerance
    pages = variant_rasters["serif"]
    worst = [worst_tile(a, b) for a, b in zip(pages, snapshot_rasters)]
    assert len(pages) == len(snapshot_rasters)
    assert max(worst) <= TILE_TOLERANCE, worst


@pytest.mark.parametrize("name, section", [("no SPL lines", "SPL law"),
                                           ("no band", "thresholds")])
def test_image_comparison_catches_a_lost_curve_or_band(name: str, section: str,
                                                      variant_rasters, snapshot_report,
                                                      snapshot_rasters: list[np.ndarray]
                                                      ) -> None:
    # the guard can fail: the SPL-law page without its fitted lines, the threshold page
    # without the fit's 95 % band, are each beyond the tolerance; the summary page, drawn
    # alike, is not
    pages = variant_rasters[name]
    k = _page_of(*snapshot_report[1:], section)
    assert worst_tile(pages[-1], snapshot_rasters[k]) > TILE_TOLERANCE
    assert worst_tile(pages[0], snapshot_rasters[0]) <= TILE_TOLERANCE


def test_negative_hysteresis_is_flagged(stores: dict[str, Path], tmp_path: Path) -> None:
    store = tmp_path / "negative.h5"
    shutil.copyfile(stores["fitted"], store)
    with h5py.File(store, "a") as fh:
        # the disappearance 0.5 m/s^2 above the onset where that is most significant (the
        # best-measured frequency; at the 95 Hz ramps' irregular regime 0.5 is within 2 u)
        up = fh["results/thresholds/up_ms2"][()]
        down = fh["results/thresholds/down_ms2"][()]
        u = np.hypot(fh["results/thresholds/up_se_ms2"][()],
                     fh["results/thresholds/down_se_ms2"][()])
        k = int(np.nanargmin(np.where(np.isfinite(up) & np.isfinite(down), u, np.nan)))
        assert 0.5 > 4.0 * u[k]
        down[k] = up[k] + 0.5
        fh["results/thresholds/down_ms2"][...] = down
        f_k = float(fh["results/thresholds/freq_hz"][k])
    # the summary and the threshold page, drawn as write_report draws them (the other pages
    # do not show the flag)
    content = build_report_content(gather(store), model=False)
    content = dataclasses.replace(content, sections=tuple(
        (name, page) for name, page in content.sections if name == "thresholds"))
    out = tmp_path / "negative.pdf"
    write_pdf(content, out)
    texts = _texts(out)
    assert f"NEGATIVE hysteresis at {f_k:g} Hz (-0.5 m/s^2)" in texts[0] + texts[1]
    threshold_page = next(t for t in texts if " - thresholds - " in " ".join(t.split()))
    assert "NEGATIVE: disappearance above onset" in threshold_page


def test_bifurcation_page_styles_follow_model_bifsets(stores: dict[str, Path]) -> None:
    from matplotlib.lines import Line2D

    from rattle_lab.plot import BIFURCATION_LINESTYLES
    from rattle_lab.report._pages_model import model_pages
    from rattle_lab.workflow._report._content_model import model_content

    import rattle_lab.model.analysis as analysis

    captured = {}
    real = analysis.bifurcation_sets

    def spy(*args, **kwargs):
        captured["sets"] = real(*args, **kwargs)
        return captured["sets"]

    analysis.bifurcation_sets = spy
    try:
        fig = model_pages(model_content(gather(stores["fitted"])))[0]
    finally:
        analysis.bifurcation_sets = real
    # the legend sits in the column right of the plot (an axes of its own, no axis drawn)
    (box,) = [a.get_legend() for a in fig.axes if a.get_legend() is not None]
    assert not fig.axes[1].axison and box.axes is fig.axes[1]
    legend = {t.get_text(): h for t, h in zip(box.get_texts(), box.legend_handles)}
    kinds = [k for k in ("saddle-node", "period-doubling", "secondary-grazing") if k in legend]
    assert kinds, legend.keys()
    for kind in kinds:
        probe = Line2D([], [], ls=BIFURCATION_LINESTYLES[kind])
        assert legend[kind].get_linestyle() == probe.get_linestyle(), kind
    # where the 1/1 and 1/2 shadings overlap (a blended colour), the legend names it
    sets = captured["sets"]
    overlap = bool((sets.exists[0] & sets.exists[1]).any())
    assert any("both exist" in label for label in legend) == overlap


def test_smooth_region_follows_the_boundary() -> None:
    from rattle_lab.plot import smooth_region

    # a disc on a coarse grid: the 0.5 level of the smoothed field stays within one cell
    w = np.linspace(0.0, 1.0, 21)
    f = np.linspace(0.0, 1.0, 21)
    ww, ff = np.meshgrid(w, f)
    mask = (ww - 0.5) ** 2 + (ff - 0.5) ** 2 < 0.3**2
    w2, f2, z = smooth_region(w, f, mask)
    ww2, ff2 = np.meshgrid(w2, f2)
    r = np.hypot(ww2 - 0.5, ff2 - 0.5)
    cell = w[1] - w[0]
    assert np.all(z[r < 0.3 - cell] > 0.5) and np.all(z[r > 0.3 + cell] < 0.5)


def test_building_the_content_leaves_the_gathered_data_alone(stores: dict[str, Path]) -> None:
    # issue 12: the report used to write the missing sections into the frozen ReportData
    from rattle_lab.report import render_pages
    from rattle_lab.workflow import build_report_content

    data = gather(stores["bare"])
    before = dict(data.missing)
    content = build_report_content(data, model=False)
    assert data.missing == before
    assert set(content.missing) == set(before) | {"thresholds", "impact patterns", "waveforms",
                                                  "SPL law", "acoustics", "model predictions"}
    assert [name for name, _ in content.sections] == ["rig and calibration"]
    pages, sections = render_pages(content)
    assert sections == ("summary", "rig and calibration") and len(pages) == 2
    assert data.missing == before


def test_summary_leads_with_the_recommended_values(stores: dict[str, Path]) -> None:
    # issue 27: the ramp-corrected gap and zeta first, intervals with the digits to differ,
    # the SPL rows with a standard error; the eq. (3.4) values after, labelled, with the
    # biases the fit names
    from scipy import stats

    data = gather(stores["fitted"])
    fits = data.summary.fits
    assert fits.grazing_ramp is not None
    lines = parameter_lines(data)
    rows = [ln for ln in lines if ln.startswith("  ") and not ln.startswith("      ")]
    assert rows[2].startswith("  gap h (ramp-corrected)")
    assert rows[3].startswith("  zeta (ramp-corrected)")
    assert rows[4].startswith("  f_s, ramp-corrected")
    cells = rows[2].split()
    assert float(cells[3]) == pytest.approx(1e3 * fits.grazing_ramp.gap_m.value, rel=1e-4)
    eq34 = lines.index(next(ln for ln in lines if ln.startswith("Eq. (3.4) fit")))
    assert eq34 > lines.index(rows[4])
    after = "\n".join(lines[eq34:])
    assert "gap h, eq. (3.4)" in after and "zeta, eq. (3.4)" in after
    assert after.count("BIASED: ") == 2  # gap and zeta: the ramp lag
    for row in rows:  # every interval's bounds differ as printed
        if "[" in row:
            lo, hi = row[row.index("[") + 1:row.index("]")].split(", ")
            assert lo != hi, row
    law = fits.spl_law("first").linear
    t = stats.t.ppf(0.975, law.n - 2)
    se = (law.slope_ci_high - law.slope_ci_low) / (2 * t)
    slope_row = next(r for r in rows if r.startswith("  SPL first peak: slope"))
    assert slope_row.split()[5] == format(se, ".3g")


def test_waveform_windows_do_not_end_on_an_impact(report_content) -> None:
    # issue 27: an impact at a window's edge was drawn unmarked; the windows are centred on
    # an impact, so that the edges fall between impacts
    waveforms = dict(report_content.sections)["waveforms"]
    for column in waveforms.columns:
        vel = column.traces[1]
        period = 1.0 / column.freq_hz
        assert vel.impact_t_s.size >= 3
        assert vel.impact_t_s.min() - vel.t_s[0] > 0.2 * period
        assert vel.t_s[-1] - vel.impact_t_s.max() > 0.2 * period


def test_hysteresis_is_not_shaded_across_a_frequency_without_a_run(report_content) -> None:
    th = dict(report_content.sections)["thresholds"]
    f = th.freq_hz[th.both]
    for i, j in th.hysteresis_segments:
        steps = np.diff(f[i:j])
        assert steps.size == 0 or steps.max() <= 1.5 * np.min(np.diff(np.unique(th.freq_hz)))
    assert sum(j - i for i, j in th.hysteresis_segments) == f.size


def test_the_listener_page_plots_each_runs_stored_psychoacoustics(stores: dict[str, Path]
                                                                  ) -> None:
    # issue 26: impulsiveness, loudness above the background, impact rate and the ECMA-418-2
    # metrics against impact velocity, read from /results as `fit --json` writes them
    from rattle_lab.workflow import build_report_content

    content = build_report_content(gather(stores["fitted"]), model=False)
    acoustics = dict(content.sections)["acoustics"]
    m = acoustics.listener
    stored = {(r["input_key"], r["run_id"]): r["acoustics"]
              for r in read_results(stores["fitted"]).summary["runs"] if r.get("acoustics")}
    rows = acoustics.rows
    assert len(rows) == len(stored) > 4
    for i, row in enumerate(rows):
        ac = stored[(row["input_key"], row["run_id"])]
        for arr, key in ((m.impulse_prominence, "impulse_prominence"),
                         (m.impulse_penalty_db, "impulse_penalty_db"),
                         (m.impacts_per_s, "impacts_per_s"),
                         (m.above_background_sone, "loudness_above_background_sone"),
                         (m.background_spread_sone, "background_loudness_spread_sone")):
            want = ac.get(key)
            assert (np.isnan(arr[i]) if want is None else arr[i] == want), (key, i)
    # a rattling run is louder than its background and impacts at a positive rate
    assert np.nanmax(m.above_background_sone) > 0 and np.nanmax(m.impacts_per_s) > 0
    # ECMA-418-2 is not rated by default ([fit] ecma418_s = 0): the panel says why
    assert np.isnan(m.loudness_ecma_sone).all() and "ecma418_s = 0" in m.ecma_note


def test_pages_are_drawn_in_the_default_style_whatever_the_session_says(
        stores: dict[str, Path]) -> None:
    # A session whose rcParams carry large fonts (a user's matplotlibrc, or a package that
    # sets them on import) draws the same pages: every text at the size it has by default.
    import matplotlib

    content = gather(stores["fitted"])

    def sizes() -> list[list[float]]:
        pages, _ = build_pages(content, model=False)
        return [[t.get_fontsize() for t in fig.texts]
                + [ax.title.get_fontsize() for ax in fig.axes] for _, fig in pages]

    plain = sizes()
    with matplotlib.rc_context({"font.size": 16, "axes.titlesize": 18, "figure.titlesize": 20}):
        large = sizes()
    assert large == plain
