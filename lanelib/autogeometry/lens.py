"""The lens's radial distortion, measured from the bend of straight road lines (``estimate_lens``).

With no lens given, the bend of the lines on the straight frames measures a one-parameter radial
model about the image centre; when it is clearly non-zero and well determined the estimate
undistorts the frames with it and measures everything again in the undistorted frames
(``estimate._with_estimated_lens``), and ``RoadGeometry.lens`` holds it (a ``camera.Calibration``
marked ``estimated``, its focal length the one the geometry found or assumed). Otherwise the
assumptions say why no lens was used.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..camera import Calibration
from .segments import _along_across

LENS_KAPPA_RANGE = (-0.6, 0.3)   # searched: a point at the corner's distance moved up to 45 % in, 30 % out
LENS_KAPPA_STEP = 0.03
LENS_MIN_SIGMAS = 5.0           # kappa this many standard errors from 0 to be used
LENS_MIN_BEND_PX = 0.3           # the lines' mean bow (px) the model must explain to be used
LENS_MIN_EXPLAINED = 0.6         # share of that bow it must explain
LENS_MIN_FRAMES = 3
LENS_MAX_SPREAD = 0.35           # frames' kappas' median absolute deviation, of |kappa|
LENS_MIN_SAME_SIGN = 0.65        # share of the frames whose kappa has its sign
LENS_MIN_LINE_ROWS = 0.1         # a line spans this share of the height to count


@dataclass(frozen=True)
class LensEstimate:
    """A one-parameter radial model of a lens, measured from straight road lines (plumb lines).

    A point at distance r_u from the image centre in the undistorted image lies at
    r_d = r_u (1 + lam r_u^2) in the raw one (lam in px^-2: negative for barrel distortion,
    positive for pincushion; OpenCV's k1 is lam f^2 for a focal length f, and no focal length is
    needed to measure it). ``kappa`` is lam times the squared half-diagonal R (dimensionless: the
    relative shift of a point R from the centre). ``bend_px`` is the lines' mean bow (px,
    weighted by their points) through no model and ``residual_bend_px`` through this one;
    ``frames``, ``lines`` how many gave it; ``frame_kappas`` each frame's own kappa; ``kappa_se``
    kappa's standard error (from the points' scatter about each line's parabola).
    ``applied`` says whether it is clearly non-zero and well determined (``reason`` why not).
    """

    lam: float
    kappa: float
    kappa_se: float
    bend_px: float
    residual_bend_px: float
    frames: int
    lines: int
    frame_kappas: tuple[float, ...]
    applied: bool
    reason: str

    def calibration(self, size_px: tuple[int, int], focal_px: float) -> Calibration:
        """Return the model as a ``camera.Calibration`` (principal point at the centre, focal
        ``focal_px``, k1 and k2 fitted to the division model over the frame's radii), marked
        estimated."""
        w, h = size_px
        K = np.array([[focal_px, 0.0, w / 2], [0.0, focal_px, h / 2], [0.0, 0.0, 1.0]])
        k1 = self.lam * focal_px ** 2
        return Calibration(K, np.array([k1, 0.0, 0.0, 0.0, 0.0]), (int(w), int(h)),
                           estimated=(f"from the road's straight lines (radial model lam {self.lam:.4g} "
                                      f"px^-2, kappa {self.kappa:+.4f}); focal length "
                                      f"{focal_px:.0f} px as the geometry has it"))


def radial_undistort(points: np.ndarray, lam: float, size_px: tuple[int, int]) -> np.ndarray:
    """Return ``points`` (N, 2) of the raw image undistorted by the one-parameter radial model
    about the centre: the raw point lies at r_d = r_u (1 + lam r_u^2) (px) from the centre, r_u its
    undistorted distance. Points past the model's fold (barrel, lam < 0: r_d above
    2 / (3 sqrt(-3 lam))) are NaN (they are left out of the fits of that model)."""
    c = np.array([size_px[0] / 2, size_px[1] / 2])
    d = np.asarray(points, np.float64) - c
    rd = np.hypot(d[:, 0], d[:, 1])
    ru = rd.copy()
    for _ in range(8):   # Newton on r + lam r^3 = r_d, from r = r_d
        ru = ru - (ru + lam * ru ** 3 - rd) / (1 + 3 * lam * ru ** 2)
    if lam < 0:
        ru[rd > 2 / (3 * math.sqrt(-3 * lam))] = np.nan
    scale = np.where(rd > 0, ru / np.maximum(rd, 1e-12), 1.0)
    return c + d * scale[:, None]


def _signed_bows(points: np.ndarray, line_id: np.ndarray, n_lines: int) -> tuple[np.ndarray, np.ndarray]:
    """Return per line (signed bow px: how far the parabola fitted along it bows from its chord,
    across its own straight fit; the RMS px of its points off that parabola)."""
    bows, rms = np.zeros(n_lines), np.full(n_lines, np.inf)
    ok = np.isfinite(points[:, 0])
    for i in range(n_lines):
        p = points[(line_id == i) & ok]
        if len(p) < 10:
            continue
        _, along, across = _along_across(p - p.mean(0))
        span = max(float(np.ptp(along)), 1e-9)
        coef = np.polyfit(along / span, across, 2)
        bows[i] = coef[0] * 0.25
        rms[i] = float(np.sqrt(np.mean((across - np.polyval(coef, along / span)) ** 2)))
    return bows, rms


def estimate_lens(lines_by_frame: list[list[np.ndarray]], size_px: tuple[int, int]) -> LensEstimate | None:
    """Return the division model (``LensEstimate``) that makes the lines straight, or None when
    fewer than two lines are long enough.

    ``lines_by_frame``: per frame, the run centres (N, 2) of each painted line found on straight
    road (``_FrameAnalysis.line_points``). Each line's signed bow (the parabola fitted along it,
    from its chord) is nearly linear in kappa; kappa is the weighted least-squares zero of all
    the bows (weights: the bow's inverse variance from the points' scatter about the parabola),
    by Newton steps. Lines through the centre do not bend whatever the lens (a radial line stays
    straight), so they weigh nothing. It is applied when the lines' mean bow through no model is
    ``LENS_MIN_BEND_PX`` or more, the model removes ``LENS_MIN_EXPLAINED`` of it, kappa is
    ``LENS_MIN_SIGMAS`` standard errors from 0, and ``LENS_MIN_FRAMES`` frames or more each give
    a kappa of its sign within ``LENS_MAX_SPREAD`` (median absolute deviation) of it: a lens
    bends every line its way about the centre, a bend of the road bends them all one way.
    """
    w, h = size_px
    pts, lid, fid = [], [], []
    n_lines = 0
    for f, lines in enumerate(lines_by_frame):
        for p in lines:
            if len(p) < 20 or np.ptp(p[:, 1]) < LENS_MIN_LINE_ROWS * h:
                continue
            pts.append(p)
            lid.append(np.full(len(p), n_lines))
            fid.append(f)
            n_lines += 1
    if n_lines < 2:
        return None
    pts_all = np.concatenate(pts).astype(np.float64)
    lid_all = np.concatenate(lid)
    fid = np.array(fid)
    cnt = np.bincount(lid_all, minlength=n_lines).astype(np.float64)
    r2 = (math.hypot(w, h) / 2) ** 2

    def bows(kappa: float) -> tuple[np.ndarray, np.ndarray]:
        return _signed_bows(radial_undistort(pts_all, kappa / r2, size_px), lid_all, n_lines)

    b0, rms0 = bows(0.0)
    weight = cnt / (11.25 * np.maximum(rms0, 0.1) ** 2)     # 1 / var(bow) of a parabola's fit
    grid = np.arange(LENS_KAPPA_RANGE[0], LENS_KAPPA_RANGE[1] + 1e-9, LENS_KAPPA_STEP)
    chi = np.array([weight * bows(k)[0] ** 2 for k in grid])   # (grid, lines)
    step = float(grid[1] - grid[0])

    def best(total: np.ndarray) -> tuple[float, float]:
        """(kappa, standard error) at the least chi-square, refined by a parabola."""
        i = int(np.argmin(total))
        if 0 < i < len(grid) - 1:
            y0, y1, y2 = total[i - 1:i + 2]
            den = y0 - 2 * y1 + y2
            if den > 0:
                return float(grid[i] + 0.5 * (y0 - y2) / den * step), math.sqrt(2 * step ** 2 / den)
        return float(grid[i]), float("inf")

    kappa, se = best(chi.sum(1))
    frames = np.unique(fid)
    frame_kappas = tuple(best(chi[:, fid == f].sum(1))[0] for f in frames)
    bend = float(np.sqrt(np.average(b0 ** 2, weights=weight)))
    rest = float(np.sqrt(np.average(bows(kappa)[0] ** 2, weights=weight)))
    fk = np.array(frame_kappas)
    spread = float(np.median(np.abs(fk - kappa)))
    same = float(np.mean(np.sign(fk) == np.sign(kappa)))
    if bend < LENS_MIN_BEND_PX:
        reason = f"the lines bow {bend:.2f} px on average, under {LENS_MIN_BEND_PX:g} px: too little to measure a lens by"
    elif bend - rest < LENS_MIN_EXPLAINED * bend:
        reason = f"the model straightens the lines' {bend:.2f} px bow only to {rest:.2f} px: the bends are not a lens's"
    elif abs(kappa) < LENS_MIN_SIGMAS * se:
        reason = f"kappa {kappa:+.3f} is within {LENS_MIN_SIGMAS:g} standard errors ({se:.3f}) of 0"
    elif len(frames) < LENS_MIN_FRAMES:
        reason = f"only {len(frames)} frames show long lines (it takes {LENS_MIN_FRAMES})"
    elif same < LENS_MIN_SAME_SIGN or spread > LENS_MAX_SPREAD * abs(kappa):
        reason = (f"the frames disagree (their kappas {np.min(fk):+.3f} to {np.max(fk):+.3f}, median "
                  f"deviation {spread:.3f}): the bends are the road's, not the lens's")
    else:
        reason = ""
    return LensEstimate(kappa / r2, kappa, se, bend, rest, len(frames), n_lines, frame_kappas,
                        not reason, reason)
