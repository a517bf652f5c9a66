"""The scale along the road from the period of the dashed lines (``_dash_scale``).

The distance ahead of a point v px below the horizon is s = C / v + s0 (a pinhole over a flat
road), so along each lane line the dashes fall at even steps of q = 1/v, (dash_m + gap_m) / C
apart. The runs of paint along the lane lines are sampled at even steps of q
(``_dash_runs_of``); only lines a whole lane width from the ego lane's count, runs that are not
a dash's length once the blur is allowed for (raised markers, flecks, merged dashes) are
dropped, and the period must hold without any one frame.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from .horizon import _basis, _k

DASH_DISAGREEMENT = 0.08
DASH_V_MIN_FRACTION = 0.02
DASH_MIN_PERIODS = 1.5
DASH_MIN_FIT = 0.5             # mean cos of the dash pairs' phase at the period found
DASH_MIN_PAIRS = 3
DASH_LANE_TOLERANCE = 0.25     # lane widths: a line this near a whole number of lanes from the ego lane's is a lane line
DASH_BLUR_MIN_RUNS = 5         # long single dashes it takes to fit the blur (b); fewer: b = 0
DASH_LENGTH_WINDOW = (0.6, 1.6)  # a run less its blur, in dash lengths, to be a dash
DASH_CONSISTENCY = DASH_DISAGREEMENT  # a sub-sample's best period within this fraction of the period found
# The period is searched from C / DASH_LENGTH_RANGE to C * DASH_LENGTH_UP, C what the dashes'
# lengths say. Higher up because a dash's length in the image is biased long (blur, a smeared or
# dilated mask, a raised marker at its end), so its C low; never up to 2: the period's harmonic
# at twice C fits the dash pairs as well as the period itself.
DASH_LENGTH_RANGE = 1.35
DASH_LENGTH_UP = 1.7


def _dash_runs(on: np.ndarray, q0: float, dq: float) -> tuple[np.ndarray, np.ndarray]:
    """Return the (centres, lengths) in q of the runs of paint in an on/off signal sampled at
    q0 + dq * i (0 at both ends), joined across gaps under 3 px, at least 2 px long and wholly
    inside the signal (``_dash_scale`` keeps those that may be dashes)."""
    edges = np.diff(on.astype(np.int8))
    starts, ends = np.flatnonzero(edges == 1) + 1, np.flatnonzero(edges == -1) + 1   # [start, end)
    if len(starts) == 0:
        return np.zeros(0), np.zeros(0)
    qs, qe = q0 + dq * starts, q0 + dq * ends
    # join runs whose gap is under 3 px (v = 1/q, so a step dq is v^2 dq px)
    gap_px = (qs[1:] - qe[:-1]) / (qs[1:] * qe[:-1])
    first = np.flatnonzero(np.r_[True, gap_px >= 3.0])
    qs, qe = np.minimum.reduceat(qs, first), np.maximum.reduceat(qe, first)
    inner = np.ones(len(qs), bool)
    inner[0] = starts[0] > 1
    inner[-1] &= ends[-1] < len(on) - 1
    length_px = (qe - qs) / (qs * qe)
    centre = (qs + qe) / 2
    keep = inner & (length_px >= 2.0)
    return centre[keep], (qe - qs)[keep]


def _dash_lines(analyses, used, ego: dict[int, tuple[int, int, float]], roll: float) -> list[tuple[int, int]]:
    """Return the (frame, line) of the lines whose dashes measure the dash period: in the frames
    that show the ego lane, the lines a whole lane width (within DASH_LANE_TOLERANCE of one) from
    its left line, from one lane left of the ego lane to one lane right of it. A barrier, a kerb
    or a shoulder's edge is no lane line (its flecks and joints are no dashes), and lines farther
    out are seen at a grazing angle that merges their dashes."""
    out = []
    for i in used:
        if i not in ego:
            continue
        left, _, r = ego[i]
        lines = analyses[i].vp.lines
        k = _k(np.array([l.angle_deg for l in lines]), roll)
        n = (k - k[left]) / r
        for j in np.flatnonzero((np.abs(n - np.round(n)) <= DASH_LANE_TOLERANCE)
                                & (np.round(n) >= -1) & (np.round(n) <= 2)):
            out.append((i, int(j)))
    return out


def dash_length_model(centre: np.ndarray, length: np.ndarray) -> tuple[float, float] | None:
    """Return (a, b): a run of a dash at q = 1/v is a + b q^2 long in q (a = dash_m / C, b the px
    the blur and the mask add to its ends), fitted to the long runs (10 px or more) that are
    single dashes (at most twice their median: merged dashes are three times as long), robustly
    (Theil-Sen: the median of the pairwise slopes); None with fewer than two such runs."""
    long = length * centre ** -2 >= 10.0
    if long.sum() < 2:
        return None
    single = long & (length <= 2 * np.median(length[long]))
    q2, y = centre[single] ** 2, length[single]
    b = 0.0
    if len(y) >= DASH_BLUR_MIN_RUNS:
        jj, kk = np.triu_indices(len(y), 1)
        dq2 = q2[kk] - q2[jj]
        ok = dq2 > 1e-3 * q2.max()
        if ok.any():
            b = max(0.0, float(np.median((y[kk] - y[jj])[ok] / dq2[ok])))
    a = float(np.median(y - b * q2))
    return (a, b) if a > 0 else None


def _dash_pairs(runs: list[np.ndarray]) -> np.ndarray:
    """Return the pairs of dashes of one line, 3 x N: their distance in q, weight (the inverse
    variance of their centres: a centre's error in q is its error in px times q^2) and the index
    of their line in ``runs``."""
    out = [np.zeros((3, 0))]
    for n, centre in enumerate(runs):
        if len(centre) >= 2:
            jj, kk = np.triu_indices(len(centre), 1)
            out.append(np.stack([centre[kk] - centre[jj], 1.0 / (centre[kk] ** 4 + centre[jj] ** 4),
                                 np.full(len(jj), float(n))]))
    return np.concatenate(out, axis=1)


def _dash_fit_curve(pairs: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """Return the fit of each frequency ``nu`` (1 / period in q) to the pairs (``_dash_pairs``):
    their weighted mean of cos(2 pi nu distance)."""
    d, weight = pairs[0], pairs[1]
    return np.cos(2 * np.pi * np.multiply.outer(nu, d)) @ (weight / weight.sum())


@dataclass(frozen=True)
class _DashRuns:
    """The runs of paint along the lane lines whose dashes may measure the dash period
    (``_dash_runs_of``): per line its (frame, line) and its runs' centres and lengths in q = 1/v
    (``_dash_runs``); ``span`` the stretch of q the lines were sampled over."""

    span: float
    runs: tuple[tuple[tuple[int, int], np.ndarray, np.ndarray], ...]


def _dash_runs_of(analyses, used, ego: dict[int, tuple[int, int, float]], hood: np.ndarray, roll: float,
                  size: tuple[int, int]) -> _DashRuns | None:
    """Return the runs of paint along the lane lines of the frames that show the ego lane
    (``_dash_lines``), sampled along their length at even steps of q = 1/v (v: px below the
    frame's horizon) above the hood (``_dash_runs``), or None when no line reaches far enough
    below the horizon; ``_dash_scale`` finds the dash period in them."""
    w, h = size
    v_min = max(6.0, DASH_V_MIN_FRACTION * h)
    signals_meta = []
    v_max = 0.0
    for i, j in _dash_lines(analyses, used, ego, roll):
        a = analyses[i]
        fb = _basis(a.vp.point_px, roll)
        c, d, _, bottom = a.line_fits[j]
        v_line = float(fb.to_uv(c + d * (bottom - c[1]) / d[1])[1])
        if v_line <= 2 * v_min:
            continue
        v_max = max(v_max, v_line)
        signals_meta.append((i, j, fb, c, d, v_line))
    if not signals_meta:
        return None
    q_lo, q_hi = 1.0 / v_max, 1.0 / v_min
    dq = 0.5 / v_max ** 2
    n = int((q_hi - q_lo) / dq) + 1
    if n > 40000:
        n = 40000
        dq = (q_hi - q_lo) / (n - 1)
    q = q_lo + dq * np.arange(n)
    v = 1.0 / q
    kernel = np.ones((1, 5), np.uint8)
    dilated = {}
    runs = []
    for i, j, fb, c, d, v_line in signals_meta:
        if i not in dilated:
            dilated[i] = cv2.dilate(analyses[i].mask, kernel)
        m = dilated[i]
        # points of the line at distance v below the frame's horizon
        c_v = float((c - fb.vp) @ fb.ev)
        tau = (v - c_v) / float(d @ fb.ev)
        xi = np.round(c[0] + tau * d[0]).astype(int)
        yi = np.round(c[1] + tau * d[1]).astype(int)
        inside = (xi >= 0) & (xi < w) & (yi >= 0) & (v <= v_line + 1)
        inside[inside] &= yi[inside] < hood[xi[inside]] - 1
        idx = np.flatnonzero(inside)
        if len(idx) < 0.2 * n:
            continue
        stretch = slice(idx[0], idx[-1] + 1)
        on = np.zeros(idx[-1] - idx[0] + 3, np.int8)
        on[1:-1] = (m[np.clip(yi[stretch], 0, h - 1), np.clip(xi[stretch], 0, w - 1)] > 0) & inside[stretch]
        runs.append(((i, j),) + _dash_runs(on, q[idx[0]] - dq, dq))
    return _DashRuns(q_hi - q_lo, tuple(runs))


def _dash_scale(dashes: _DashRuns | None, dash_m: float, gap_m: float,
                c_range: tuple[float, float]) -> tuple[float | None, float]:
    """Return (C from the dash period, how well the dashes fit it), or (None, fit) without a
    clear dash period; C is searched within ``c_range``.

    ``dashes`` are the runs of paint along the lane lines (``_dash_runs_of``), sampled at even
    steps of q = 1/v, where s = C q + s0 makes a dash pattern periodic; those no longer than a
    dash of the shortest period searched and far enough below the horizon for a gap to show
    (3 px at the smallest C searched) may be dashes. Their lengths give a + b q^2 (``dash_length_model``): a first
    C = dash_m / a, and b, what blur adds to a run. A run is a dash when its length less b q^2
    is within DASH_LENGTH_WINDOW of a: far away a raised marker in a gap or a fleck blurs to
    half a dash's length in q, and a marker beside a dash merges with it; either would put a
    "dash" half a period off. For a period P in q, the fit is the weighted mean over all pairs
    of dashes of one line of cos(2 pi (q_j - q_k) / P): 1 when every pair lies a whole number of
    periods apart (``_dash_fit_curve``); the period is the best fit within a factor
    DASH_LENGTH_RANGE below and DASH_LENGTH_UP above what the lengths say (which rules out the
    harmonic at twice C), used from a fit of DASH_MIN_FIT and only when it holds without any one
    frame (or, from one frame, any one line): each such sub-sample's best period within
    DASH_CONSISTENCY of it and fitting it from DASH_MIN_FIT; C = (dash_m + gap_m) / P.
    """
    if dashes is None:
        return None, 0.0
    period_m = dash_m + gap_m
    span = dashes.span
    lo = max(DASH_MIN_PERIODS / span, c_range[0] / period_m)
    hi = c_range[1] / period_m
    if hi <= lo:
        return None, 0.0
    runs = _short_runs(dashes, lo, c_range[0], gap_m)
    if not runs:
        return None, 0.0
    model = dash_length_model(np.concatenate([r[1] for r in runs]), np.concatenate([r[2] for r in runs]))
    if model is None:
        return None, 0.0
    a_q, b_q = model
    c_len = dash_m / a_q
    lo = max(lo, c_len / DASH_LENGTH_RANGE / period_m)
    hi = min(hi, c_len * DASH_LENGTH_UP / period_m)
    if hi <= lo:
        return None, 0.0
    found = _dashes_of(runs, a_q, b_q, c_len, gap_m)
    step = 1.0 / (40 * span)
    nu = np.arange(lo, hi + step, step)
    if len(nu) < 3:
        return None, 0.0
    pairs = _dash_pairs([c for _, c in found])
    if pairs.shape[1] < DASH_MIN_PAIRS:
        return None, 0.0
    fit = _dash_fit_curve(pairs, nu)
    b = int(np.argmax(fit))
    if fit[b] < DASH_MIN_FIT or b in (0, len(nu) - 1):
        return None, float(fit[b])
    c0, c1, c2 = fit[b - 1], fit[b], fit[b + 1]
    den = c0 - 2 * c1 + c2
    f = nu[b] + (0.5 * (c0 - c2) / den * step if den < 0 else 0.0)
    holds, worst = _period_holds(pairs, [key for key, _ in found], nu, b, f, float(c1))
    return (float(f * period_m), float(c1)) if holds else (None, worst)


def _short_runs(dashes: _DashRuns, lo: float, c_low: float, gap_m: float) -> list:
    """Return the runs that may be dashes: no longer than a dash of the shortest period searched
    (1 / ``lo``), and far enough below the horizon for a gap to span 3 px at the smallest C
    searched (``c_low``)."""
    v_resolved = math.sqrt(3.0 * c_low / gap_m)
    runs = []
    for key, centre, length in dashes.runs:
        keep = (length <= 0.6 / lo) & (1.0 / centre >= v_resolved)
        runs.append((key, centre[keep], length[keep]))
    return runs


def _dashes_of(runs: list, a_q: float, b_q: float, c_len: float, gap_m: float) -> list:
    """Return (key, centres) of the runs that are dashes, for the lines with two or more: a run
    whose length less its blur (b q^2) is within DASH_LENGTH_WINDOW of a dash's (a), and, with
    C known roughly (``c_len``), below where a gap spans 6 px."""
    out = []
    for key, centre, length in runs:
        own = length - b_q * centre ** 2
        ok = ((own >= DASH_LENGTH_WINDOW[0] * a_q) & (own <= DASH_LENGTH_WINDOW[1] * a_q)
              & (centre <= 1.0 / math.sqrt(6.0 * c_len / gap_m)))
        if ok.sum() >= 2:
            out.append((key, centre[ok]))
    return out


def _period_holds(pairs: np.ndarray, keys: list, nu: np.ndarray, b: int, f: float, fit: float) -> tuple[bool, float]:
    """Return (whether the period 1 / ``f`` holds without any one frame (or, from one frame,
    without any one line), the worst fit at ``nu[b]`` of those sub-samples): each sub-sample's
    best period within DASH_CONSISTENCY of it and its fit there from DASH_MIN_FIT. ``keys``:
    each line's (frame, line); ``fit``: the fit of all the pairs."""
    line = pairs[2].astype(int)
    frames = np.array([key[0] for key in keys])[line]
    group = frames if len(np.unique(frames)) > 1 else line
    if len(np.unique(group)) < 2:
        return False, fit
    worst = fit
    for g in np.unique(group):
        keep = group != g
        sub = _dash_fit_curve(pairs[:, keep], nu)
        sb = int(np.argmax(sub))
        worst = min(worst, float(sub[b]))
        if sub[b] < DASH_MIN_FIT or abs(nu[sb] / f - 1) > DASH_CONSISTENCY:
            return False, worst
    return True, worst
