"""Perspective transform between the (undistorted) road image and a bird's-eye view.

The default points belong to the Udacity highway camera at 1280x720 (and lanelib's synthetic
camera, built to match it), chosen on the undistorted ``straight_lines1.jpg`` and
``straight_lines2.jpg``: the trapezoid's sides run through the point that balances the two
images' vanishing points, so a straight lane becomes two vertical lines (tests/test_perspective.py).
The top row lies 51 px below that point, as a row nearer the horizon magnifies a one-pixel
error there into a visible slant; the bottom corners lie on a 3.7 m lane centred on the camera,
so the two dst lines are 3.7 m apart, and the view covers 23.5 m of road.

Geometry is a set of transforms in the style of scikit-image's ``ProjectiveTransform``
(``Transform``): callable on (N, 2) points, with an ``inverse``, composed by ``+`` (``Chain``).
``Perspective`` is a ``Homography``; ``camera.Lens`` is the lens distortion. The pipeline's one
remap is ``(lens.inverse + perspective).remap_maps(size)``; the overlay and the evaluation map
bird's-eye points to the raw frame by its ``inverse``. ``straight_line_check`` measures how
straight a set of points makes a straight road (the perspective notebook, the tuner).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from . import io
from .errors import ConfigError
from .params import SearchConfig
from .search import sliding_windows
# the default points and scale are perspective's public names too (geometry, runs, synth use them)
from .params.stages import (DEFAULT_DST_1280x720, DEFAULT_LANE_WIDTH_M, DEFAULT_SRC_1280x720,
                             DEFAULT_VISIBLE_LENGTH_M, PerspectiveConfig, Point)


def trapezoid_src(top_y: float, bottom_y: float, top_width: float, bottom_width: float,
                  centre_x: float) -> tuple[Point, ...]:
    """Return src points (tl, bl, br, tr) of a symmetric trapezoid; all arguments in pixels."""
    return ((centre_x - top_width / 2, top_y), (centre_x - bottom_width / 2, bottom_y),
            (centre_x + bottom_width / 2, bottom_y), (centre_x + top_width / 2, top_y))


def _row_widths(src_px) -> tuple[float, float]:
    """Return the (top, bottom) widths in px of a src trapezoid (tl, bl, br, tr)."""
    (tlx, _), (blx, _), (brx, _), (trx, _) = src_px
    top, bottom = trx - tlx, brx - blx
    if not 0 < top < bottom:
        raise ConfigError(f"perspective.src_px {src_px!r}: the top must be narrower than the "
                          "bottom and both wider than 0 (a trapezoid of road ahead)")
    return top, bottom


def road_length_m(src_px, lane_width_m: float, focal_px: float) -> float:
    """Return the road length (m) from the bottom to the top row of a src trapezoid: over a flat road
    a lane ``lane_width_m`` wide spanning ``w`` px on a row lies ``focal_px * lane_width_m / w`` m
    ahead (``focal_px``: the undistorted image's horizontal focal length).
    """
    top, bottom = _row_widths(src_px)
    return focal_px * lane_width_m * (1.0 / top - 1.0 / bottom)


def implied_focal_px(config: PerspectiveConfig) -> float:
    """Return the focal length (px) for which ``config.visible_length_m`` fits its trapezoid."""
    top, bottom = _row_widths(config.src_px)
    return config.visible_length_m / (config.lane_width_m * (1.0 / top - 1.0 / bottom))


def scaled(config: PerspectiveConfig, size_px: tuple[int, int]) -> PerspectiveConfig:
    """Return ``config`` with its points scaled to images of ``size_px`` (w, h)."""
    sx = size_px[0] / config.size_px[0]
    sy = size_px[1] / config.size_px[1]
    sc = lambda pts: tuple((x * sx, y * sy) for x, y in pts)  # noqa: E731
    return PerspectiveConfig(sc(config.src_px), sc(config.dst_px), tuple(size_px),
                             config.lane_width_m, config.visible_length_m,
                             None if config.car_x_px is None else config.car_x_px * sx)


# --------------------------------------------------------------------------- transforms of points

def as_points(points) -> np.ndarray:
    """Return ``points`` ((x, y) pairs in px) as an (N, 2) float64 array."""
    return np.asarray(points, dtype=np.float64).reshape(-1, 2)


class Transform:
    """A map of image points, in the style of scikit-image's ``ProjectiveTransform``.

    ``tform(points)`` maps (N, 2) points (x, y) in px to an (N, 2) float64 array; ``tform.inverse``
    maps back; ``a + b`` applies ``a``, then ``b`` (a ``Chain``). ``valid(points)`` says where the
    map is trusted (a lens model folds back far outside its frame), ``checked(points)`` gives the
    mapped points and that in one pass, ``remap_maps`` the ``cv2.remap`` grids of the transform.
    """

    def __call__(self, points) -> np.ndarray:
        raise NotImplementedError

    @property
    def inverse(self) -> "Transform":
        """Return the transform back."""
        raise NotImplementedError

    def valid(self, points) -> np.ndarray:
        """Return an (N,) bool array: True where ``points`` map to a trustworthy position (finite here)."""
        p = as_points(points)
        return np.isfinite(p[:, 0]) & np.isfinite(p[:, 1])

    def checked(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Return the mapped points ((N, 2) float64) and ``valid(points)`` ((N,) bool)."""
        return self(points), self.valid(points)

    def __add__(self, other: "Transform") -> "Chain":
        return Chain(self, other)

    def remap_maps(self, out_size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """Return the ``cv2.remap`` maps (CV_16SC2) that warp an image by this transform: output pixel q
        of the ``out_size`` (w, h) image samples the source at ``self.inverse(q)``, or black where that
        is not valid. Every pixel is mapped: made once per configuration, not per frame.
        """
        w, h = int(out_size[0]), int(out_size[1])
        xs, ys = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        src, ok = self.inverse.checked(np.stack([xs.ravel(), ys.ravel()], axis=1))
        src[~ok] = -1.0
        mx = src[:, 0].reshape(h, w).astype(np.float32)
        my = src[:, 1].reshape(h, w).astype(np.float32)
        return cv2.convertMaps(mx, my, cv2.CV_16SC2)


class Homography(Transform):
    """The projective map of the plane by the 3x3 matrix ``params`` (scikit-image's ``params``);
    ``inverse_params`` (default: the matrix inverse) is kept as given, so ``h.inverse.inverse`` has
    the very same matrix as ``h``.
    """

    def __init__(self, params: np.ndarray, inverse_params: np.ndarray | None = None):
        self.params = np.asarray(params, dtype=np.float64)
        if self.params.shape != (3, 3):
            raise ConfigError(f"homography: needs a 3x3 matrix, got shape {self.params.shape}")
        self.inverse_params = (np.linalg.inv(self.params) if inverse_params is None
                               else np.asarray(inverse_params, dtype=np.float64))

    def __call__(self, points) -> np.ndarray:
        p = as_points(points)
        if not len(p):
            return p.copy()
        return cv2.perspectiveTransform(p.reshape(-1, 1, 2), self.params).reshape(-1, 2)

    @property
    def inverse(self) -> "Homography":
        """Return the homography back (matrices swapped)."""
        return Homography(self.inverse_params, self.params)

    def __repr__(self) -> str:
        return f"Homography({np.round(self.params, 6).tolist()})"


class Chain(Transform):
    """Transforms applied in order: ``Chain(a, b)(p) == b(a(p))``, what ``a + b`` makes; a point is
    valid where every step finds it valid.
    """

    def __init__(self, *transforms: Transform):
        steps: list[Transform] = []
        for t in transforms:
            steps.extend(t.transforms if isinstance(t, Chain) else [t])
        if not steps:
            raise ConfigError("chain: needs at least one transform")
        self.transforms = tuple(steps)

    def __call__(self, points) -> np.ndarray:
        p = as_points(points)
        for t in self.transforms:
            p = t(p)
        return p

    @property
    def inverse(self) -> "Chain":
        """Return the chain back: each step's inverse, in reverse order."""
        return Chain(*(t.inverse for t in reversed(self.transforms)))

    def checked(self, points) -> tuple[np.ndarray, np.ndarray]:
        p = as_points(points)
        ok = np.ones(len(p), bool)
        for t in self.transforms:
            p, step_ok = t.checked(p)
            ok &= step_ok
        return p, ok

    def valid(self, points) -> np.ndarray:
        return self.checked(points)[1]

    def __repr__(self) -> str:
        return " + ".join(repr(t) for t in self.transforms)


class Perspective(Homography):
    """Warp between the undistorted image and the bird's-eye view, with its metric scale.

    ``perspective(points)`` maps undistorted points to the view and ``perspective.inverse`` back;
    ``M`` (= ``params``) and ``Minv`` are the two matrices. ``lens.inverse + perspective`` takes
    raw-frame points to the view.
    """

    def __init__(self, config: PerspectiveConfig = PerspectiveConfig()):
        self.config = config
        src = np.float32(config.src_px)
        dst = np.float32(config.dst_px)
        if abs(cv2.contourArea(src)) < 1 or abs(cv2.contourArea(dst)) < 1:
            raise ConfigError("perspective: the src or dst points are collinear or repeated; "
                              "choose four corners of a trapezoid")
        self.M = cv2.getPerspectiveTransform(src, dst)
        self.Minv = cv2.getPerspectiveTransform(dst, src)
        super().__init__(self.M, self.Minv)
        self.size = tuple(int(v) for v in config.size_px)
        self.xm_per_px = config.xm_per_px
        self.ym_per_px = config.ym_per_px
        w, h = self.size
        # the car's centre line in the bird's-eye view (``PerspectiveConfig.car_x_px``)
        self.car_x_px = (float(config.car_x_px) if config.car_x_px is not None
                         else float(self([(w / 2, h - 1)])[0, 0]))

    def _check(self, image: np.ndarray) -> None:
        io.check_rgb(image, "image", self.size, owner="the perspective",
                     fix="use perspective.scaled() or a config made for this camera", mask_ok=True)

    def warp(self, image: np.ndarray, interpolation: int = cv2.INTER_LINEAR) -> np.ndarray:
        """Return the bird's-eye view of an undistorted image (same size)."""
        self._check(image)
        return cv2.warpPerspective(image, self.M, self.size, flags=interpolation)

    def unwarp(self, image: np.ndarray, interpolation: int = cv2.INTER_LINEAR) -> np.ndarray:
        """Return a bird's-eye image mapped back into the undistorted camera view."""
        self._check(image)
        return cv2.warpPerspective(image, self.Minv, self.size, flags=interpolation)

    def warp_points(self, pts: np.ndarray) -> np.ndarray:
        """Map (N, 2) undistorted-image points to bird's-eye points (``perspective(pts)``)."""
        return self(pts)

    def unwarp_points(self, pts: np.ndarray) -> np.ndarray:
        """Map (N, 2) bird's-eye points back to undistorted-image points (``perspective.inverse(pts)``)."""
        return self.inverse(pts)

    def __repr__(self) -> str:
        return f"Perspective({self.size[0]}x{self.size[1]}, src_px={self.config.src_px})"


# --------------------------------------------------------------------------- straight-line check

@dataclass(frozen=True)
class StraightLineCheck:
    """How straight a straight lane comes out in the bird's-eye view: ``left_slope``/``right_slope``,
    each line's x drift in px per 100 px of height (0: vertical; NaN: not found); ``lane_width_m``,
    the fits' distance on the bottom row; ``left_fit``/``right_fit``, (slope, intercept) of
    x = slope * y + intercept in bird's-eye px, or None.
    """

    left_slope: float
    right_slope: float
    lane_width_m: float
    left_fit: tuple[float, float] | None
    right_fit: tuple[float, float] | None

    def __str__(self) -> str:
        return (f"left {_fmt(self.left_slope, 2, ' px/100 px', True)}, right "
                f"{_fmt(self.right_slope, 2, ' px/100 px', True)}, lane width "
                f"{_fmt(self.lane_width_m, 2, ' m')}")


def straight_line_check(binary: np.ndarray, xm_per_px: float,
                        search: SearchConfig = SearchConfig(),
                        car_x: float | None = None) -> StraightLineCheck:
    """Return the straight-line check of a bird's-eye lane mask of a straight road.

    Parameters
    ----------
    binary : the 0/255 bird's-eye lane mask of a frame of a straight road.
    xm_per_px : metres per bird's-eye pixel across the road.
    search : the sliding-window search that finds each line's pixels; a line needs
        ``min_line_pixels`` pixels over ``min_found_span_fraction`` of the height to get a fit.
    car_x : the car's x (px) in the bird's-eye view, where the search splits left from right.
    """
    found = sliding_windows(binary, search, car_x=car_x)
    h = binary.shape[0]
    fits = []
    for ys, xs in (found.left_pixels, found.right_pixels):
        if len(ys) < search.min_line_pixels or ys.max() - ys.min() < search.min_found_span_fraction * h:
            fits.append(None)
            continue
        slope, intercept = np.polyfit(ys.astype(np.float64), xs.astype(np.float64), 1)
        fits.append((float(slope), float(intercept)))
    nan = float("nan")
    slopes = [100 * f[0] if f else nan for f in fits]
    width = nan
    if fits[0] and fits[1]:
        x_at = [f[0] * (h - 1) + f[1] for f in fits]
        width = (x_at[1] - x_at[0]) * xm_per_px
    return StraightLineCheck(slopes[0], slopes[1], width, fits[0], fits[1])


def _fmt(v: float, nd: int = 2, unit: str = "", sign: bool = False) -> str:
    """Return ``v`` rounded to ``nd`` decimals with its unit ("not found" for NaN, no "-0.00")."""
    if math.isnan(v):
        return "not found"
    return f"{round(v, nd) + 0.0:{'+' if sign else ''}.{nd}f}{unit}"
