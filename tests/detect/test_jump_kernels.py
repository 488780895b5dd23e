"""The compiled local fits of every impact (``_jump_fits_all``) against the same fits made
impact by impact in Python (``_jump_fits``), on a record made here with plain numpy.

The two compute the same least squares (one LAPACK ``gelsd`` on the same design) and differ
only in the order of their sums (pairwise in numpy, in index order in the kernel) and in the
fits' evaluation (BLAS ``gemv`` against a loop).  Each centroid sums about 20-60 normalised
step values of order one, each from fits whose terms are at most ``A / jump`` ~ 10 times the
step: the rounding difference is ~ 60 * 10 * 2.2e-16 * (index ~ 1e4) ~ 1e-10 sample at
most, so 1e-8 sample is a bound with a margin of 100; a wrong window or an off-by-one moves a
centroid by 1e-3 sample or more.  Velocities are compared at 1e-10 relative (the same
argument, without the index).
"""

from __future__ import annotations

import numpy as np
import pytest

from rattle_lab.detect._local_fits import (_fit_rows, _fits_at, _jump_fits, _jump_fits_all,
                                           _JumpFits)
from rattle_lab.detect._trigger import _half_region, characteristic, trigger_onsets

FS, F_HZ = 25600.0, 95.0


def bouncing_record(seed: int, seconds: float = 0.5, contact_samples: float = 3.0
                    ) -> tuple[np.ndarray, np.ndarray]:
    """A forced plate velocity with one impact a period (a half-sine contact, a
    velocity reversal with e ~ 0.6), a 900 Hz mode ringing after each, and noise; and its
    acceleration (the analytic derivative plus noise)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS)) / FS
    w = 2 * np.pi * F_HZ
    v = 0.4 * np.cos(w * t + 0.3)
    acc = -0.4 * w * np.sin(w * t + 0.3)
    t_imp = (np.arange(1, int(seconds * F_HZ)) + 0.31 + 0.05 * rng.standard_normal()) / F_HZ
    dur = contact_samples / FS
    for ti in t_imp:
        jump = 0.16 * (1 + 0.1 * rng.standard_normal())
        x = np.clip((t - ti) / dur + 0.5, 0.0, 1.0)
        v += jump * 0.5 * (1 - np.cos(np.pi * x))
        pulse = (x > 0) & (x < 1)
        acc[pulse] += jump * 0.5 * np.pi / dur * np.sin(np.pi * x[pulse])
        after = t > ti
        ring = 0.004 * np.exp(-(t[after] - ti) / 4e-3)
        v[after] += ring * np.sin(2 * np.pi * 900 * (t[after] - ti))
        acc[after] += ring * 2 * np.pi * 900 * np.cos(2 * np.pi * 900 * (t[after] - ti))
    return v + 2e-4 * rng.standard_normal(t.size), acc + 2.0 * rng.standard_normal(t.size)


def spans_of(v: np.ndarray) -> list[tuple[int, int, int, int]]:
    """The triggers' half-height regions and their neighbours' limits, as the detector
    forms them."""
    cf = characteristic(v, 0.0, 64, jump=True)
    trig = trigger_onsets(cf, 8.0, 3.0, int(2e-3 * FS))
    out = []
    for j, (start, _, end) in enumerate(trig):
        pk = start + int(np.argmax(cf[start:end + 1]))
        j_lo, j_hi = _half_region(cf, pk)
        lo_lim = trig[j - 1][2] + 1 if j > 0 else 0
        hi_lim = trig[j + 1][0] - 1 if j + 1 < len(trig) else v.size - 1
        out.append((j_lo, j_hi, lo_lim, hi_lim))
    return out


def assert_same(a: _JumpFits, b: _JumpFits) -> None:
    for name in ("t_v", "t_a", "t_half", "t_s", "a_lo", "a_hi", "a_sign"):
        x, y = getattr(a, name), getattr(b, name)
        assert np.isnan(x) == np.isnan(y), name
        if np.isfinite(x):
            assert abs(x - y) <= 1e-8, (name, x, y)
    for t in (a.t_half - 3.0, a.t_half, a.t_half + 3.5):
        np.testing.assert_allclose(a.at(t), b.at(t), rtol=1e-10, atol=0.0)
        # the compiled scalar evaluator against the design matrix times the coefficients
        for fit, value in zip((b.p, b.q), a.at(t)):
            if fit is not None:
                np.testing.assert_allclose(value, fit(np.array([t]))[0], rtol=1e-10, atol=0.0)


@pytest.mark.parametrize("omega, degree, with_accel, contact", [
    (2 * np.pi * F_HZ / FS, 2, True, 3.0),    # the forced-mode basis, as dwells use it
    (2 * np.pi * F_HZ / FS, 2, True, 7.5),    # a long contact (a wider pulse and jump)
    (2 * np.pi * F_HZ / FS, 2, False, 3.0),
    (None, 2, True, 3.0),                     # polynomials
])
def test_the_compiled_fits_are_the_python_fits(omega, degree, with_accel, contact):
    v, a = bouncing_record(3, contact_samples=contact)
    spans = spans_of(v)
    assert len(spans) >= 40          # every impact triggers
    kw = dict(n_fit=51, n_guard=2, degree=degree, omega_per_sample=omega,
              accel=a if with_accel else None)
    batch = _jump_fits_all(v, spans, **kw)
    one_by_one = [_jump_fits(v, *s, **kw) for s in spans]
    for x, y in zip(batch, one_by_one):
        assert_same(x, y)
    if with_accel:
        # the pulses were found (the comparison is not of NaNs)
        assert np.isfinite([b.t_a for b in batch]).mean() > 0.9
    t = np.array([b.t_half + 0.25 for b in batch])
    got = _fits_at(_fit_rows(batch), t)
    want = np.array([b.at(tt) for b, tt in zip(one_by_one, t)])
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=0.0)


def test_a_non_finite_sample_goes_the_python_way_and_the_rest_stay_compiled():
    # detect_impacts refuses non-finite samples; the batch still leaves such a window to
    # the Python path rather than decide it differently
    v, a = bouncing_record(5)
    spans = spans_of(v)
    kw = dict(n_fit=51, n_guard=2, degree=2, omega_per_sample=2 * np.pi * F_HZ / FS, accel=a)
    t10 = _jump_fits(v, *spans[10], **kw).t_a
    a = a.copy()
    a[int(round(t10))] = np.nan        # in impact 10's contact pulse
    kw["accel"] = a
    batch = _jump_fits_all(v, spans, **kw)
    assert np.isnan(batch[10].t_a)     # numpy's arithmetic gives no pulse there
    for x, s in zip(batch, spans):
        assert_same(x, _jump_fits(v, *s, **kw))


@pytest.mark.parametrize("omega", [2 * np.pi * F_HZ / FS, None])
def test_windows_cut_short_by_neighbours(omega):
    # a neighbouring trigger 0-9 samples beyond each guard: fits over fewer samples than
    # n_fit (the forced-mode basis drops to degree 0), fewer than its parameters (a
    # low-degree polynomial instead), or none at all
    v, a = bouncing_record(13, seconds=0.2)
    base = spans_of(v)
    spans = []
    for i, (j_lo, j_hi, _, _) in enumerate(base):
        n_pad = (j_hi - j_lo + 1) + 2
        cut_lo, cut_hi = i % 10, (3 * i) % 10
        spans.append((j_lo, j_hi, j_lo - 1 - n_pad - cut_lo + 1, j_hi + n_pad + cut_hi - 1))
    kw = dict(n_fit=51, n_guard=2, degree=2, omega_per_sample=omega, accel=a)
    batch = _jump_fits_all(v, spans, **kw)
    kinds = set()
    for x, s_ in zip(batch, spans):
        ref = _jump_fits(v, *s_, **kw)
        assert_same(x, ref)
        for fx, fr in ((x.p, ref.p), (x.q, ref.q)):
            assert (fx is None) == (fr is None)
            kinds.add(None if fr is None else (fr.degree, fr.w is None))
            if fr is not None:
                assert (fx.degree, fx.w is None) == (fr.degree, fr.w is None)
    # the fallbacks were reached: no fit, and fits of two kinds at least (forced-mode degree
    # 0 and a polynomial of degree 0; polynomials of degree 0, 1 and 2 without omega)
    assert None in kinds and len(kinds) >= 3


def test_edges_and_no_impacts():
    v, a = bouncing_record(7, seconds=0.1)
    spans = spans_of(v)
    # a neighbour right before the jump: no sample left for the fit before it
    spans = [(spans[0][0], spans[0][1], spans[0][0] - 1, spans[0][3])] + spans
    kw = dict(n_fit=51, n_guard=2, degree=2, omega_per_sample=2 * np.pi * F_HZ / FS, accel=a)
    batch = _jump_fits_all(v, spans, **kw)
    assert batch[0].p is None and np.isnan(batch[0].t_v)
    for x, s in zip(batch, spans):
        assert_same(x, _jump_fits(v, *s, **kw))
    assert _jump_fits_all(v, [], **kw) == []


def reference_sound_peaks(p, fs, t_imp, n_win, n_base, omega, fraction, t0=0.0, delay=0.0,
                          guard=2):
    """The sound-peak rule written out with numpy (module docstring of detect._sound): the
    window after each impact, opened ``guard`` samples before the first sample at or after
    the arrival and cut at the next impact's, the forcing-frequency sinusoid fitted over
    the baseline before it (columns 1, cos, sin of omega k) and removed, the first local
    maximum reaching ``fraction`` of the largest, both refined by a parabola unless at an
    onset."""
    out = np.full((t_imp.size, 5), np.nan)
    prev_hi = 0
    arrival = [int(np.ceil((t + delay - t0) * fs - 1e-9)) - guard for t in t_imp]
    for i in range(t_imp.size):
        lo = arrival[i]
        hi = lo + guard + n_win if i + 1 == t_imp.size else min(lo + guard + n_win,
                                                                arrival[i + 1])
        lo, hi = max(lo, 0), min(hi, p.size)
        if hi <= lo:
            continue
        k = np.arange(lo, hi)
        seg = np.abs(p[lo:hi])
        b_lo = max(0, lo - n_base, prev_hi)
        if lo - b_lo >= 9:
            kb = np.arange(b_lo, lo)
            design = lambda kk: np.column_stack([np.ones(kk.size), np.cos(omega * kk),  # noqa: E731
                                                 np.sin(omega * kk)])
            coef = np.linalg.lstsq(design(kb), p[b_lo:lo], rcond=None)[0]
            seg = np.abs(p[lo:hi] - design(k) @ coef)
        prev_hi = hi
        out[i, 4] = np.sqrt(np.mean(seg ** 2))
        k_max = int(np.argmax(seg))
        if seg[k_max] == 0.0:      # silence: no peak
            continue
        is_peak = (seg >= fraction * seg[k_max]) & (seg >= np.r_[seg[1:], -np.inf])
        k_first = int(np.flatnonzero(is_peak)[0])
        for col, kk in ((0, k_first), (1, k_max)):
            loc, h = float(kk), seg[kk]
            if 0 < kk < seg.size - 1 and not seg[kk - 1] < 0.5 * seg[kk]:
                a, b, c = seg[kk - 1], seg[kk], seg[kk + 1]
                if a - 2 * b + c < 0:
                    d = 0.5 * (a - c) / (a - 2 * b + c)
                    loc, h = kk + d, b - 0.25 * (a - c) * d
            out[i, col], out[i, col + 2] = t0 + (lo + loc) / fs, h
    return out


def test_sound_peaks_follow_the_rule_written_out():
    from rattle_lab.detect import sound_peaks

    rng = np.random.default_rng(11)
    fs, f = 25600.0, 95.0
    t = np.arange(int(0.4 * fs)) / fs
    p = 0.3 * np.sin(2 * np.pi * f * t + 0.2) + 0.01 * rng.standard_normal(t.size)
    t_imp = np.sort(rng.uniform(0.01, 0.39, 30))
    for ti in t_imp:     # a decaying 2.5 kHz burst 0.4 ms after each impact
        after = t > ti + 4e-4
        p[after] += 2.0 * np.exp(-(t[after] - ti) / 1.5e-3) * np.sin(2 * np.pi * 2500 * (t[after] - ti))
    n_win, n_base = round(5e-3 * fs), round(3e-3 * fs)
    omega = 2 * np.pi * f / fs
    got = sound_peaks(p, fs, t_imp, excitation_freq_hz=f)
    want = reference_sound_peaks(p, fs, t_imp, n_win, n_base, omega, 0.5)
    # the same arithmetic but for the baseline fit's basis (a rotation of cos, sin) and the
    # order of sums: peak values ~1 Pa agree to ~1e-15 relative times the fit's condition
    # (~10); times to rounding of t ~ 0.4 s
    np.testing.assert_allclose(got.t_first_s, want[:, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.t_max_s, want[:, 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.p_first_pa, want[:, 2], rtol=1e-11)
    np.testing.assert_allclose(got.p_max_pa, want[:, 3], rtol=1e-11)
    np.testing.assert_allclose(got.p_rms_pa, want[:, 4], rtol=1e-11)
    assert np.isfinite(want).all()
    # without the excitation frequency no baseline is removed
    raw = sound_peaks(p, fs, t_imp)
    want_raw = reference_sound_peaks(p, fs, t_imp, n_win, 0, omega, 0.5)
    np.testing.assert_allclose(raw.p_max_pa, want_raw[:, 3], rtol=1e-12)


def test_a_zero_jump_divides_as_numpy_does():
    # no jump: the fits either side are the same and the normalised step is 0/0.  The kernel
    # must not raise (numba's default division would) and gives NaN, as numpy does.  The two
    # fits are made identical here: fitted to a constant, their difference is rounding that
    # depends on the BLAS, not an exact zero
    from rattle_lab.detect._jump_kernels import FIT_HEAD, _step_centroid

    v = np.full(400, 0.25)
    row = np.full(FIT_HEAD + 3, np.nan)
    row[:FIT_HEAD] = [200.0, 50.0, 2.0, 0.0, 0.0]     # k0, scale, degree 2, polynomial
    row[FIT_HEAD:] = [0.0, 0.0, 0.25]
    assert np.isnan(_step_centroid(v, row, row.copy(), 190, 210))
    with np.errstate(all="ignore"):
        assert np.isnan(np.sum((v[190:211] - 0.25) / (0.25 - 0.25)))   # numpy's answer



def test_the_pooled_step_error_is_the_rows_written_out():
    from rattle_lab.detect._timing import step_error

    v, a = bouncing_record(9, contact_samples=5.0)
    spans = spans_of(v)
    jfits = _jump_fits_all(v, spans, n_fit=51, n_guard=2, degree=2,
                           omega_per_sample=2 * np.pi * F_HZ / FS, accel=a)
    t_ev = np.array([jf.t_a for jf in jfits])
    t_ev[3] = np.nan                       # an impact without a time has no row
    limits = [(lo, hi) for _, _, lo, hi in spans]
    span = 12
    taus, med, noise = step_error(v, t_ev, _fit_rows(jfits), limits, span)
    rows = []
    for jf, te, (lo, hi) in zip(jfits, t_ev, limits):
        if not np.isfinite(te):
            continue
        k = np.arange(max(lo, int(np.ceil(te - span))), min(hi, int(np.floor(te + span))) + 1)
        pk, qk = jf.p(k.astype(float)), jf.q(k.astype(float))
        r = np.where(k < te, v[k] - pk, v[k] - qk) / (qk - pk)
        row = np.full(2 * span + 1, np.nan)
        row[np.round(k - te).astype(int) + span] = r
        rows.append(row)
    m = np.array(rows)
    want = np.nanmedian(m, axis=0)
    want[np.sum(np.isfinite(m), axis=0) < 5] = np.nan
    np.testing.assert_array_equal(taus, np.arange(-span, span + 1))
    # a normalised step of order one from fits ~10 times the jump: 1e-12 is ~1e3 roundings
    np.testing.assert_allclose(med, want, rtol=0, atol=1e-12)
    assert np.isfinite(med).sum() >= 2 * span      # the bins are filled
    assert np.all(noise[np.isfinite(med)] > 0)


def test_sound_peaks_with_a_start_time_a_delay_silence_and_a_repeated_impact():
    from rattle_lab.detect import sound_peaks
    from rattle_lab.exceptions import ParameterError

    rng = np.random.default_rng(4)
    fs, t0, delay = 25600.0, 12.5, 1.2e-3
    p = 0.02 * rng.standard_normal(int(0.2 * fs))
    p[2000:2600] = 0.0                       # a silent stretch
    t_imp = t0 + np.array([0.01, 0.03, 0.03, 0.0785, 0.12, 0.199])
    t_imp[4] = t0 + 2000 / fs + 0.002        # its window is silent
    n_win, n_base = round(5e-3 * fs), round(3e-3 * fs)
    got = sound_peaks(p, fs, t_imp, start_time_s=t0, delay_s=delay, excitation_freq_hz=95.0)
    want = reference_sound_peaks(p, fs, t_imp, n_win, n_base, 2 * np.pi * 95.0 / fs, 0.5,
                                 t0=t0, delay=delay)
    assert np.isnan(got.p_max_pa[1])         # the first of two equal times has no window
    assert np.isnan(got.p_max_pa[4]) and got.p_rms_pa[4] == 0.0
    for g, w in ((got.t_first_s, want[:, 0]), (got.t_max_s, want[:, 1])):
        np.testing.assert_allclose(g, w, rtol=0, atol=1e-12)
    for g, w in ((got.p_first_pa, want[:, 2]), (got.p_max_pa, want[:, 3]),
                 (got.p_rms_pa, want[:, 4])):
        np.testing.assert_allclose(g, w, rtol=1e-11, atol=1e-15)
    with pytest.raises(ParameterError, match="impact_t_s"):
        sound_peaks(p, fs, [0.01, np.nan], start_time_s=0.0)


def reference_onsets(cf, on, off, n_min_sep):
    """The trigger rule written out (ObsPy's on/off design with merging)."""
    out = []
    k = 0
    while k < cf.size:
        if cf[k] <= on:
            k += 1
            continue
        start = k
        while start > 0 and cf[start - 1] > off:
            start -= 1
        end = k
        while end + 1 < cf.size and cf[end + 1] > off:
            end += 1
        peak = start + int(np.argmax(cf[start:end + 1]))
        if out and peak - out[-1][1] < n_min_sep:
            s0, p0, e0 = out[-1]
            out[-1] = (s0, p0 if cf[p0] >= cf[peak] else peak, max(end, e0))
        else:
            out.append((start, peak, end))
        k = end + 1
    return out


@pytest.mark.parametrize("seed", range(4))
def test_the_compiled_trigger_is_the_rule_written_out(seed):
    rng = np.random.default_rng(seed)
    cf = np.abs(rng.standard_normal(20000))
    hits = rng.choice(cf.size, 300, replace=False)
    cf[hits] += rng.uniform(5, 40, hits.size)        # events, some close enough to merge
    cf[hits[:50] + 1] += 20.0                         # and some two samples wide
    cf[np.clip(hits[:20] + 3, 0, cf.size - 1)] = cf[hits[:20]]   # equal peaks: the first wins
    got = trigger_onsets(cf, 8.0, 2.5, 30)
    assert got == reference_onsets(cf, 8.0, 2.5, 30)
    assert 150 < len(got) < 300
    assert trigger_onsets(np.zeros(10), 8.0, 2.5, 30) == []


def test_the_coarse_lag_is_the_fft_cross_correlations():
    # the direct sums over the accelerometer's event samples against numpy's FFT
    # correlation of the same clipped functions; the peak lag the same, the values to the
    # FFT's rounding (~1e-16 times the total energy, ~1e-9 here)
    from rattle_lab.detect._jump_kernels import lag_correlation
    from rattle_lab.detect._timing import coarse_lag

    rng = np.random.default_rng(8)
    for lag_true in (0, 3, -7, 40):
        a = np.abs(rng.standard_normal(30000))
        ev = rng.choice(np.arange(100, 29800), 60, replace=False)
        a[ev] += rng.uniform(10, 50, ev.size)
        v = np.abs(rng.standard_normal(a.size))
        v[ev + lag_true] += a[ev] * rng.uniform(0.5, 1.5, ev.size)
        assert coarse_lag(v, a, 51, 3.0) == lag_true
        x, y = np.clip(a - 3.0, 0, None), np.clip(v - 3.0, 0, None)
        m = 1 << int(np.ceil(np.log2(2 * x.size)))
        c = np.fft.irfft(np.conj(np.fft.rfft(x, m)) * np.fft.rfft(y, m), m)
        want = np.r_[c[:52], c[m - 51:]]
        np.testing.assert_allclose(lag_correlation(x, y, 51), want, rtol=0,
                                   atol=1e-12 * np.sum(x * x + y * y))
    assert coarse_lag(np.zeros(50), np.zeros(50), 51, 3.0) == 0


def test_a_clipped_contact_pulse_is_found_where_the_smooth_fit_drifts_away():
    # A start-up impact on the independent generator: the plate's acceleration steepens
    # (here an exponential) and the contact pulse clips at the ADC's range.
    # The smooth fit before the search window (degree 1 here) extrapolated over it drifts
    # by more than the clipped pulse stands out; the pulse is the largest residual that
    # falls below half its height on both sides inside the window, the drift at the
    # window's end does not fall again.
    from rattle_lab.detect._jump_kernels import pulse_peak
    from rattle_lab.detect._local_fits import contact_pulse

    k = np.arange(400.0)
    k_imp = 300
    a = 200.0 * np.exp((k - 300.0) / 5.5)
    a[k_imp:k_imp + 2] = -2000.0                 # the pulse, clipped: centroid 300.5
    n_half, n_fit = 14, 60
    lo, hi = k_imp - n_half, k_imp + n_half
    kk = np.arange(lo - n_fit, lo)
    line = np.polyval(np.polyfit(kk, a[lo - n_fit:lo], 1), np.arange(lo, hi + 1.0))
    r = a[lo:hi + 1] - line
    # the test means something: the drift at the window's end outgrows the clipped pulse
    assert abs(r[-1]) > np.abs(r[n_half:n_half + 2]).max()
    assert int(np.argmax(np.abs(r))) == r.size - 1
    assert pulse_peak(np.ascontiguousarray(r)) in (n_half, n_half + 1)
    t1, a_lo, a_hi, sign = contact_pulse(a, k_imp, n_half, 0, n_fit=n_fit, degree=1)
    # the two clipped samples' centroid; the ramp removed after the pulse moves it a little
    assert t1 == pytest.approx(k_imp + 0.5, abs=0.1)
    assert sign == -1.0 and a_lo <= k_imp and a_hi >= k_imp + 1
    # a residual that never falls again (no pulse): the largest, as before; so where the
    # only bump that falls again is under half the drift (noise, not a pulse)
    ramp = np.linspace(0.0, 5.0, 20)
    assert pulse_peak(ramp) == 19
    ramp[3] += 1.5          # 2.29, falls to half both sides, under half of 5
    assert pulse_peak(ramp) == 19
    ramp[3] += 1.0          # 3.29: now the pulse
    assert pulse_peak(ramp) == 3
    assert pulse_peak(np.zeros(5)) == 0


def test_a_step_centroid_held_at_its_window_edge_does_not_centre_the_pulse_search():
    # Fits that read ringing rather than the approach and rebound: here no net jump
    # (q - p is a thousandth of the excursion), so the normalised step's centroid runs off
    # and is held at the pre window's edge, further from the jump's region than the region
    # is wide.  The contact pulse, at the end of the jump's region, is then searched around
    # that region, not around the edge (which put the search window's end on the pulse:
    # impacts of the independent generator timed 6.7-8.4 samples early).  The compiled
    # batch and the Python rule agree.
    from rattle_lab.detect._local_fits import _jump_fits, _jump_fits_all

    n = 600
    v = np.zeros(n)
    j_lo, j_hi = 300, 306
    v[j_lo:j_hi + 1] = 0.3 * np.sin(np.pi * (np.arange(7) + 1) / 8)   # an excursion
    v[j_hi + 1:] = 1e-3
    a = np.zeros(n)
    a[j_hi - 1:j_hi + 1] = -500.0                  # the pulse: centroid j_hi - 0.5
    kw = dict(n_fit=60, n_guard=4, degree=1, omega_per_sample=None, accel=a)
    jf = _jump_fits(v, j_lo, j_hi, 0, n - 1, **kw)
    n_pad = (j_hi - j_lo + 1) + 4
    assert jf.t_v == j_lo - 1 - n_pad              # held at the pre window's edge
    assert jf.t_a == pytest.approx(j_hi - 0.5, abs=1e-9)
    batch = _jump_fits_all(v, [(j_lo, j_hi, 0, n - 1)], **kw)[0]
    assert batch.t_v == jf.t_v and batch.t_a == pytest.approx(jf.t_a, abs=1e-9)
