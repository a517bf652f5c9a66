"""Chessboard camera calibration, the ``Calibration`` record, and undistortion by precomputed maps.

A calibration belongs to one image size, the most common among the images with a board. A
photo up to 2 px larger or smaller each way is the same sensor with a row or column more or
less at the right/bottom edge, which moves no pixel: its corners are used as they are. Any
other size is skipped; every skipped photo is named, with why, in ``Calibration.skipped`` and
``skip_reasons`` (nothing is only warned about).

A frame of another size with the same aspect ratio (within 0.5 %) gets the camera matrix
rescaled (focal lengths and principal point scale; the distortion coefficients act on
normalised coordinates and stay); otherwise ``Calibration.for_size`` raises
``CalibrationError`` naming both sizes.

``Lens`` is the distortion as a transform of points (``perspective.Transform``, in the style of
scikit-image); ``Lens.valid`` is the one rule for where the model is trusted.
"""
from __future__ import annotations

import os
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path

import cv2
import numpy as np

from . import io
from .errors import CalibrationError, InputError
from .perspective import Homography, Transform, as_points

SIZE_TOLERANCE_PX = 2
ASPECT_TOLERANCE = 0.005
MIN_BOARDS = 3


@dataclass(frozen=True)
class Calibration:
    """A calibrated pinhole camera with radial/tangential distortion.

    Parameters
    ----------
    camera_matrix : 3x3 intrinsic matrix (pixels).
    dist_coeffs : OpenCV distortion coefficients (k1, k2, p1, p2, k3).
    image_size : (width, height) in pixels the matrix belongs to.
    rms_px : RMS reprojection error of the calibration (pixels).
    used, skipped : image file names used and skipped; ``skip_reasons`` says why each was skipped.
    estimated : '' when measured on boards; else how it was estimated (``estimate_geometry``'s lens
        from the road's lines: the distortion only, the focal length not measured).
    """

    camera_matrix: np.ndarray
    dist_coeffs: np.ndarray
    image_size: tuple[int, int]
    rms_px: float = float("nan")
    used: tuple[str, ...] = ()
    skipped: tuple[str, ...] = ()
    skip_reasons: dict = field(default_factory=dict)
    estimated: str = ""

    def to_dict(self) -> dict:
        """Return the record as JSON-able lists and numbers."""
        return ({"estimated": self.estimated} if self.estimated else {}) | {
            "camera_matrix": np.asarray(self.camera_matrix, float).round(6).tolist(),
            "dist_coeffs": np.asarray(self.dist_coeffs, float).ravel().round(8).tolist(),
            "image_size": [int(v) for v in self.image_size],
            "rms_px": round(float(self.rms_px), 4),
            "used": list(self.used),
            "skipped": list(self.skipped),
            "skip_reasons": dict(self.skip_reasons),
        }

    @classmethod
    def from_dict(cls, d: dict, source: str = "calibration") -> "Calibration":
        """Return a Calibration from ``to_dict`` output; a missing or malformed key raises."""
        try:
            K = np.array(d["camera_matrix"], dtype=np.float64)
            dist = np.array(d["dist_coeffs"], dtype=np.float64).ravel()
            size = tuple(int(v) for v in d["image_size"])
        except KeyError as e:
            raise CalibrationError(f"{source}: missing key {e.args[0]!r}; regenerate it with "
                                   "`python -m lanelib calibrate`") from None
        except (TypeError, ValueError) as e:
            raise CalibrationError(f"{source}: malformed value ({e}); regenerate it with "
                                   "`python -m lanelib calibrate`") from None
        if K.shape != (3, 3) or dist.size not in (4, 5, 8, 12, 14) or len(size) != 2:
            raise CalibrationError(f"{source}: camera_matrix must be 3x3, dist_coeffs 4/5/8/12/14 "
                                   "numbers, image_size [w, h]")
        return cls(K, dist, size, float(d.get("rms_px", float("nan"))), tuple(d.get("used", ())),
                   tuple(d.get("skipped", ())), dict(d.get("skip_reasons", {})), str(d.get("estimated", "")))

    def save(self, path: str | os.PathLike) -> Path:
        """Write the record as JSON (atomically); return the path."""
        return io.write_json(path, self.to_dict())

    @classmethod
    def load(cls, path: str | os.PathLike) -> "Calibration":
        """Read a record written by ``save``."""
        return cls.from_dict(io.read_json(path, "calibration file"), source=str(path))

    def for_size(self, size: tuple[int, int]) -> "Calibration":
        """Return this calibration for frames of ``size`` (w, h), rescaled if the aspect matches."""
        size = (int(size[0]), int(size[1]))
        if size == tuple(self.image_size):
            return self
        w0, h0 = self.image_size
        sx, sy = size[0] / w0, size[1] / h0
        if abs(sx / sy - 1) > ASPECT_TOLERANCE:
            raise CalibrationError(
                f"frame is {size[0]}x{size[1]} but the calibration is for {w0}x{h0} with another "
                "aspect ratio; calibrate this camera at this size (`python -m lanelib calibrate`)")
        K = self.camera_matrix.copy()
        K[0, :] *= sx
        K[1, :] *= sy
        return replace(self, camera_matrix=K, image_size=size)


@dataclass(frozen=True)
class BoardDetection:
    """Chessboard corners found in one image (sub-pixel, (N, 2) float32), or None and why."""

    file: str
    size: tuple[int, int] | None
    corners: np.ndarray | None
    reason: str = ""


def board_points(pattern: tuple[int, int], square: float = 1.0) -> np.ndarray:
    """Return the (N, 3) float32 board coordinates of a ``pattern`` (cols, rows) of inner corners."""
    cols, rows = pattern
    obj = np.zeros((cols * rows, 3), np.float32)
    obj[:, :2] = np.mgrid[0:cols, 0:rows].T.reshape(-1, 2) * square
    return obj


def find_corners(rgb: np.ndarray, pattern: tuple[int, int] = (9, 6)) -> np.ndarray | None:
    """Return the sub-pixel inner corners ((N, 2) float32, OpenCV order) of a board, or None."""
    gray = cv2.cvtColor(rgb, cv2.COLOR_RGB2GRAY) if rgb.ndim == 3 else rgb
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    ok, corners = cv2.findChessboardCorners(gray, pattern, flags=flags)
    if not ok:
        return None
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.001)
    corners = cv2.cornerSubPix(gray, corners, (11, 11), (-1, -1), criteria)
    return corners.reshape(-1, 2)


def detect_boards(folder: str | os.PathLike, pattern: tuple[int, int] = (9, 6)) -> list[BoardDetection]:
    """Return one detection per image of ``folder`` (corners None, with a reason, where none)."""
    out = []
    for f in io.list_images(folder):
        try:
            rgb = io.read_image(f)
        except InputError:
            out.append(BoardDetection(f.name, None, None, "unreadable image"))
            continue
        corners = find_corners(rgb, pattern)
        reason = "" if corners is not None else f"no {pattern[0]}x{pattern[1]} board found"
        out.append(BoardDetection(f.name, (rgb.shape[1], rgb.shape[0]), corners, reason))
    return out


def calibrate(folder: str | os.PathLike, pattern: tuple[int, int] = (9, 6),
              detections: list[BoardDetection] | None = None) -> Calibration:
    """Return the camera calibrated from the chessboard images in ``folder``.

    Images with no board (or of another size) are skipped and listed with the reason in
    ``skipped`` and ``skip_reasons``; fewer than 3 usable boards raise ``CalibrationError``.

    Parameters
    ----------
    folder : folder of chessboard photos from one camera.
    pattern : inner corners per row and per column, e.g. (9, 6).
    detections : corners found earlier by ``detect_boards`` (to avoid finding them twice).

    Examples
    --------
    >>> from lanelib import data
    >>> camera = calibrate(data.bundled("camera_cal"))  # the generator's chessboards
    >>> len(camera.used), camera.image_size, camera.rms_px < 0.5
    (17, (1280, 720), True)
    """
    dets = detections if detections is not None else detect_boards(folder, pattern)
    reasons = {d.file: d.reason for d in dets if d.corners is None}
    found = [d for d in dets if d.corners is not None]
    if found:
        size = Counter(d.size for d in found).most_common(1)[0][0]
        for d in found:
            if max(abs(d.size[0] - size[0]), abs(d.size[1] - size[1])) > SIZE_TOLERANCE_PX:
                reasons[d.file] = f"image is {d.size[0]}x{d.size[1]}, the others {size[0]}x{size[1]}"
        found = [d for d in found if d.file not in reasons]
    if len(found) < MIN_BOARDS:
        raise CalibrationError(
            f"{folder}: only {len(found)} image(s) show a {pattern[0]}x{pattern[1]} chessboard, "
            f"{MIN_BOARDS} or more are needed; add photos of the board or check --pattern "
            "(inner corners per row x per column)")
    obj = board_points(pattern)
    rms, K, dist, _, _ = cv2.calibrateCamera([obj] * len(found), [d.corners for d in found], size,
                                             None, None)
    return Calibration(K, dist.ravel(), size, float(rms), tuple(d.file for d in found),
                       tuple(sorted(reasons)), reasons)


def distort_points(calibration: Calibration, pts: np.ndarray) -> np.ndarray:
    """Map (N, 2) undistorted pixel positions to where they lie in the raw (distorted) image."""
    K = calibration.camera_matrix
    p = np.asarray(pts, np.float64).reshape(-1, 2)
    x = (p[:, 0] - K[0, 2]) / K[0, 0]
    y = (p[:, 1] - K[1, 2]) / K[1, 1]
    d = np.asarray(calibration.dist_coeffs, np.float64).ravel()
    if d.size in (4, 5) and K[0, 1] == 0:
        # OpenCV's model (k1, k2, p1, p2[, k3]) in numpy: projectPoints gives the same to
        # rounding but is ~30x slower on the million points of a remap grid
        k1, k2, p1, p2 = d[:4]
        k3 = d[4] if d.size == 5 else 0.0
        r2 = x * x + y * y
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        return np.column_stack([K[0, 0] * xd + K[0, 2], K[1, 1] * yd + K[1, 2]])
    norm = np.column_stack([x, y, np.ones(len(p))])
    out, _ = cv2.projectPoints(norm, np.zeros(3), np.zeros(3), K, d)
    return out.reshape(-1, 2)


# OpenCV's undistortion iteration run to convergence: at most 50 steps, or 1e-10 px
EXACT_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10)


def undistort_points(calibration: Calibration, pts: np.ndarray, exact: bool = False) -> np.ndarray:
    """Map (N, 2) raw-image pixel positions to their undistorted positions.

    OpenCV's fixed-point iteration stops after 5 steps, which leaves errors of a fraction of a
    pixel near a frame's corners; ``exact`` iterates until the result distorts back to within
    1e-10 px (at most 50 steps), as ``Lens.inverse`` does.
    """
    K = calibration.camera_matrix
    p = np.asarray(pts, np.float64).reshape(-1, 1, 2)
    if exact:
        return cv2.undistortPoints(p, K, calibration.dist_coeffs, None, None, K,
                                   EXACT_UNDISTORT_CRITERIA).reshape(-1, 2)
    return cv2.undistortPoints(p, K, calibration.dist_coeffs, P=K).reshape(-1, 2)


# A lens model is trusted within this fraction of the frame's width and height beyond its edges.
MODEL_MARGIN = 0.25


class Lens(Transform):
    """The lens distortion as a transform: undistorted-image points -> raw-frame points.

    ``lens(points)`` is ``distort_points``, ``lens.inverse(points)`` ``undistort_points`` run to
    convergence (a ``LensInverse``). ``lens.inverse + perspective`` maps raw-frame points to the
    bird's-eye view, its ``inverse`` back, and its ``remap_maps(size)`` take a raw frame to the view
    in one ``cv2.remap``. ``undistort_maps`` are the lens's own remap grids.

    Parameters
    ----------
    calibration : the camera's calibration (rescaled to ``size`` by ``Calibration.for_size``), or
        None for the identity lens (an ideal or an uncalibrated camera).
    size : (width, height) of the frames in px; default the calibration's ``image_size``.
    """

    def __init__(self, calibration: Calibration | None, size: tuple[int, int] | None = None):
        if size is None:
            if calibration is None:
                raise CalibrationError("Lens(None): the identity lens needs the frame size, "
                                       "Lens(None, (width, height))")
            size = calibration.image_size
        self.size = (int(size[0]), int(size[1]))
        self.calibration = calibration.for_size(self.size) if calibration is not None else None

    @property
    def is_identity(self) -> bool:
        """Return True for the lens of no calibration (points and frames pass unchanged)."""
        return self.calibration is None

    def __call__(self, points) -> np.ndarray:
        if self.calibration is None:
            return as_points(points).copy()
        return distort_points(self.calibration, points)

    @property
    def inverse(self) -> "LensInverse":
        """Return the undistortion: raw-frame points -> undistorted-image points."""
        return LensInverse(self)

    def valid(self, points) -> np.ndarray:
        """Return where undistorted ``points`` lie in the region the lens model is trusted in.

        The one rule for every use (the pipeline's remap, the evaluation's fits): within
        ``MODEL_MARGIN`` of the frame's size beyond its edges. Farther out the distortion polynomial,
        fitted inside the frame, folds back and lands far points inside the raw frame. The identity
        lens keeps the same region, so a pipeline samples the same area with or without a calibration.
        """
        p = as_points(points)
        w, h = self.size
        m = MODEL_MARGIN
        return (p[:, 0] >= -m * w) & (p[:, 0] <= (1 + m) * w) & (p[:, 1] >= -m * h) & (p[:, 1] <= (1 + m) * h)

    def undistort_maps(self, pad: tuple[int, int] = (0, 0), m1type: int = cv2.CV_16SC2):
        """Return the ``cv2.remap`` maps (map1, map2) that undistort a raw frame onto a canvas ``pad``
        (px in x, y) larger on each side: (0, 0) for the frame's undistortion (``Undistorter``), more
        to hold what moves beyond the frame (``widgets.perspective.FastBirdseye``). ``m1type``:
        OpenCV's map type (``cv2.CV_32FC2`` gives map2 None). The identity lens gives the plain pixel
        grid.
        """
        w, h = self.size
        px, py = int(pad[0]), int(pad[1])
        cw, ch = w + 2 * px, h + 2 * py
        if self.calibration is None:
            xs, ys = np.meshgrid(np.arange(cw, dtype=np.float32) - px, np.arange(ch, dtype=np.float32) - py)
            grid = np.dstack([xs, ys])
            return (grid, None) if m1type == cv2.CV_32FC2 else cv2.convertMaps(grid, None, m1type)
        K = self.calibration.camera_matrix
        shifted = K.copy()
        shifted[0, 2] += px
        shifted[1, 2] += py
        return cv2.initUndistortRectifyMap(K, self.calibration.dist_coeffs, None, shifted, (cw, ch), m1type)

    def __repr__(self) -> str:
        return "Lens(identity)" if self.calibration is None else f"Lens({self.size[0]}x{self.size[1]})"


class LensInverse(Transform):
    """A ``Lens``'s inverse: raw-frame points -> undistorted-image points (``undistort_points``),
    valid where their undistorted position is (``Lens.valid``).
    """

    def __init__(self, lens: Lens):
        self.lens = lens

    def __call__(self, points) -> np.ndarray:
        p = as_points(points)
        if self.lens.calibration is None or not len(p):
            return p.copy()
        return undistort_points(self.lens.calibration, p, exact=True)

    @property
    def inverse(self) -> Lens:
        """Return the lens."""
        return self.lens

    def checked(self, points) -> tuple[np.ndarray, np.ndarray]:
        out = self(points)
        return out, self.lens.valid(out)

    def valid(self, points) -> np.ndarray:
        return self.checked(points)[1]

    def __repr__(self) -> str:
        return f"{self.lens!r}.inverse"


class Undistorter:
    """Undistort frames of one size with remap maps computed once (``lens``: the calibration's
    ``Lens`` at this size; ``calibration`` None: an ideal camera, frames pass unchanged).
    """

    def __init__(self, calibration: Calibration | None, size: tuple[int, int]):
        self.size = (int(size[0]), int(size[1]))
        self.lens = Lens(calibration, self.size)
        self.calibration = self.lens.calibration
        self._maps = None if self.lens.is_identity else self.lens.undistort_maps()

    def check(self, image: np.ndarray, name: str = "frame") -> None:
        """Return None; raise InputError if ``image`` is not an RGB frame of this size (``io.check_rgb``)."""
        io.check_rgb(image, name, self.size)

    def undistort(self, image: np.ndarray) -> np.ndarray:
        """Return the undistorted frame (same size)."""
        self.check(image)
        if self._maps is None:
            return image
        return cv2.remap(image, self._maps[0], self._maps[1], cv2.INTER_LINEAR)

    def maps_through(self, Minv: np.ndarray, out_size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """Return remap maps that take a RAW frame straight to the view ``Minv`` (a perspective's,
        output pixels -> undistorted pixels) maps back from, undistortion included: the same as
        ``(self.lens.inverse + perspective).remap_maps(out_size)``.
        """
        to_raw = Homography(Minv) + self.lens
        return to_raw.inverse.remap_maps(out_size)
