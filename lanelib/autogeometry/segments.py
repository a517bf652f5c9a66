"""The painted lines of a frame as short straight segments, and where segments meet.

- **The paint mask** (``paint_mask_config``): pixels 25 grey levels brighter than the road beside
  them, through a horizontal top-hat as wide as 12 % of the image height.
- **Band segments** (``_segments``): the mask is cut into horizontal bands (1/24 of the height);
  every connected piece of a band is a segment, described by the centres of its horizontal runs
  (one per row), so a segment is thin whatever the line's width. Segments that are not straight
  and thin (RMS off their axis above 1 px), shorter than 1.2 % of the height or within 3 deg of
  horizontal are dropped.
- **Where they meet** (``_ransac``): RANSAC (fixed seed): the intersection of two segments drawn
  with probability by length, scored by the length of the segments that point at it within
  1.5 deg and lie below it; then weighted least squares on the inliers (``_intersect``: each
  segment's distance to the point, weighted by its length squared over its distance squared:
  equal weight per angle), twice, the second time with 1 deg.
- **Continuations** (``_up_links``, ``_follow_up``): the segment that continues a segment across
  the band row above it, so that a line can be followed up the image, bending or not.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from ..thresholds import ThresholdConfig, TopHatMask

RANSAC_SEED = 15
RANSAC_HYPOTHESES = 200
MAX_SEGMENTS = 250
RANSAC_TOL_DEG = 1.5
INLIER_TOL_DEG = 1.0
TOPHAT_FRACTION = 0.12
TOPHAT_GREY = 25


def paint_mask_config(size_px: tuple[int, int]) -> ThresholdConfig:
    """Return the mask of painted lines used for the geometry, for frames of ``size_px``.

    Pixels TOPHAT_GREY (25) grey levels (HLS lightness) brighter than the road beside them: a horizontal
    top-hat 12 % of the image height wide, wider than a line's run across any row of the road.
    No colour test: far from the lens centre, vignetting and haze leave white paint at a
    lightness of 100 or less, and yellow paint is brighter than asphalt too.
    """
    width = max(15, int(round(TOPHAT_FRACTION * size_px[1])) | 1)
    return ThresholdConfig(line_tophat=TopHatMask("hls", "l", width, TOPHAT_GREY, 255), rule="line_tophat")


@dataclass(frozen=True)
class _Segments:
    """Band segments of a mask: per segment centre, unit direction (down), length, count; per run
    its centre and its segment (-1: none)."""

    centre: np.ndarray      # (N, 2)
    direction: np.ndarray   # (N, 2), dy >= 0
    length: np.ndarray      # (N,)
    count: np.ndarray       # (N,)
    run_x: np.ndarray
    run_y: np.ndarray
    run_segment: np.ndarray


def _segments(mask: np.ndarray, band_px: int, max_run_px: int) -> _Segments:
    """Return the straight thin band segments of a 0/255 mask (see the module docstring)."""
    h, w = mask.shape
    cut = mask.copy()
    cut[::band_px] = 0
    _, labels = cv2.connectedComponents(cut, connectivity=8)
    padded = np.zeros((h, w + 2), np.int8)
    padded[:, 1:-1] = cut > 0
    d = np.diff(padded, axis=1)
    ys, x0 = np.nonzero(d == 1)
    _, x1 = np.nonzero(d == -1)
    keep = (x1 - x0) <= max_run_px
    ys, x0, x1 = ys[keep], x0[keep], x1[keep]
    xc = (x0 + x1 - 1) * 0.5
    lab = labels[ys, x0]
    n_lab = int(lab.max()) + 1 if lab.size else 1
    yf = ys.astype(np.float64)
    cnt = np.bincount(lab, minlength=n_lab).astype(np.float64)
    with np.errstate(invalid="ignore", divide="ignore"):
        mx = np.bincount(lab, xc, n_lab) / cnt
        my = np.bincount(lab, yf, n_lab) / cnt
        vxx = np.bincount(lab, xc * xc, n_lab) / cnt - mx * mx
        vyy = np.bincount(lab, yf * yf, n_lab) / cnt - my * my
        vxy = np.bincount(lab, xc * yf, n_lab) / cnt - mx * my
    half_tr = (vxx + vyy) / 2
    disc = np.sqrt(np.maximum(half_tr ** 2 - (vxx * vyy - vxy ** 2), 0.0))
    lam1, lam2 = half_tr + disc, np.maximum(half_tr - disc, 0.0)
    theta = 0.5 * np.arctan2(2 * vxy, vxx - vyy)
    dx, dy = np.cos(theta), np.sin(theta)
    flip = dy < 0
    dx[flip], dy[flip] = -dx[flip], -dy[flip]
    length = np.sqrt(12 * np.maximum(lam1, 0.0))
    ok = ((cnt >= 5) & (length >= max(8.0, 0.012 * h)) & (np.sqrt(lam2) <= 1.0)
          & (dy >= math.sin(math.radians(3.0))))
    ok[0] = False
    idx = np.flatnonzero(ok)
    if len(idx) > MAX_SEGMENTS:       # the longest: the rest are flecks of asphalt, leaves, noise
        idx = np.sort(idx[np.argsort(-length[idx], kind="stable")[:MAX_SEGMENTS]])
    seg_of_label = np.full(n_lab, -1)
    seg_of_label[idx] = np.arange(len(idx))
    return _Segments(np.column_stack([mx[idx], my[idx]]), np.column_stack([dx[idx], dy[idx]]),
                     length[idx], cnt[idx], xc, yf, seg_of_label[lab])


def _normals(direction: np.ndarray) -> np.ndarray:
    return np.column_stack([-direction[:, 1], direction[:, 0]])


def _angle_errors(vp: np.ndarray, centre: np.ndarray, normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (sin of the angle between each segment and the direction to ``vp``, whether the
    segment lies below ``vp``) for vp of shape (2,) or (K, 2) (then (K, N) arrays)."""
    dv = vp[..., None, :] - centre                      # (..., N, 2)
    dist = np.hypot(dv[..., 0], dv[..., 1])
    sin = np.abs((dv * normal).sum(-1)) / np.maximum(dist, 1e-9)
    return sin, dv[..., 1] < -2.0


def _intersect(centre: np.ndarray, normal: np.ndarray, weight: np.ndarray, start: np.ndarray,
               iterations: int = 3) -> np.ndarray:
    """Return the weighted least-squares intersection of lines (centre, normal), re-weighted by
    1 / distance^2 from the current point (equal weight per angle)."""
    p = start.astype(np.float64)
    nn = normal[:, :, None] * normal[:, None, :]            # (N, 2, 2)
    for _ in range(iterations):
        d2 = np.maximum(((centre - p) ** 2).sum(1), 1.0)
        wt = weight / d2
        a = (wt[:, None, None] * nn).sum(0)
        b = (wt[:, None, None] * nn @ centre[:, :, None])[:, :, 0].sum(0)
        if abs(np.linalg.det(a)) < 1e-12 * max(np.abs(a).max(), 1e-300) ** 2:
            break
        p = np.linalg.solve(a, b)
    return p


def _ransac(seg: _Segments, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray] | None:
    """Return (vanishing point, inlier mask) of the segments, or None when no point gathers them."""
    n = len(seg.length)
    normal = _normals(seg.direction)
    prob = seg.length / seg.length.sum()
    pairs = rng.choice(n, size=(RANSAC_HYPOTHESES, 2), p=prob)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]
    lines = np.column_stack([normal, -(normal * seg.centre).sum(1)])
    hom = np.cross(lines[pairs[:, 0]], lines[pairs[:, 1]])
    good = np.abs(hom[:, 2]) > 1e-9
    if not good.any():
        return None
    vps = hom[good, :2] / hom[good, 2:3]
    sin, below = _angle_errors(vps, seg.centre, normal)
    inl = (sin < math.sin(math.radians(RANSAC_TOL_DEG))) & below
    score = (inl * seg.length).sum(1)
    best = int(np.argmax(score))
    vp, inliers = vps[best], inl[best]
    for tol in (RANSAC_TOL_DEG, INLIER_TOL_DEG):
        if inliers.sum() < 2:
            return None
        vp = _intersect(seg.centre[inliers], normal[inliers], seg.length[inliers] ** 2, vp)
        sin, below = _angle_errors(vp, seg.centre, normal)
        inliers = (sin < math.sin(math.radians(tol))) & below
    return vp, inliers


def _up_links(seg: _Segments) -> np.ndarray:
    """Return, for every segment, the segment that continues it in the band above (-1: none).

    The continuation's bottom end lies within 3 px (plus 2 px per unit of the line's slant) of
    the segment's top end and points the same way within 10 deg: the same painted line across
    the cut row, straight or bending.
    """
    n = len(seg.length)
    if n < 2:
        return np.full(n, -1)
    half = seg.direction * (seg.length / 2)[:, None]
    top, bottom = seg.centre - half, seg.centre + half
    dist = np.hypot(*(top[:, None, :] - bottom[None, :, :]).transpose(2, 0, 1))    # [j, i]
    cos = seg.direction @ seg.direction.T
    tol = 3.0 + 2.0 / np.maximum(seg.direction[:, 1], 0.1)
    ok = (dist <= tol[:, None]) & (cos >= math.cos(math.radians(10.0)))
    ok &= seg.centre[None, :, 1] < seg.centre[:, None, 1]
    np.fill_diagonal(ok, False)
    dist = np.where(ok, dist, np.inf)
    best = np.argmin(dist, axis=1)
    return np.where(np.isfinite(dist[np.arange(n), best]), best, -1)


def _follow_up(start, up: np.ndarray) -> list[int]:
    """Return ``start`` and every segment reached from it by following ``up`` links."""
    seen = set(int(i) for i in start)
    todo = list(seen)
    while todo:
        j = int(up[todo.pop()])
        if j >= 0 and j not in seen:
            seen.add(j)
            todo.append(j)
    return sorted(seen)


def _along_across(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return (unit direction pointing down, along, across) of points ``q`` about their centroid:
    the line's straight fit (SVD) and each point's coordinates along it and across it."""
    _, _, vt = np.linalg.svd(q, full_matrices=False)
    d = vt[0] if vt[0, 1] >= 0 else -vt[0]
    return d, q @ d, q @ np.array([-d[1], d[0]])


def _fit_line(x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Return (centroid, unit direction pointing down, bow px) of points along one line."""
    c = np.array([x.mean(), y.mean()])
    d, along, across = _along_across(np.column_stack([x, y]) - c)
    span = along.max() - along.min()
    bow = 0.0
    if span > 0 and len(along) >= 5:
        a2 = np.polyfit(along / span, across, 2)[0]
        bow = abs(a2) * 0.25
    return c, d, float(bow)
