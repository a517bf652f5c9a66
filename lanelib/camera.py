"""Chessboard camera calibration, the ``Calibration`` record, and undistortion by precomputed maps.

Mixed image sizes: a calibration belongs to one image size, the most common one among the
images in which a board is found. A photo up to 2 px larger or smaller in each direction is
taken as the same sensor with a row or column more or less at the right/bottom edge (the
Udacity set holds two 1281x721 photos among 1280x720 ones): its corner coordinates are used as
they are, since cropping or padding at the right/bottom edge does not move a pixel. A photo of
any other size is skipped. Every skipped photo is named, with why, in the record
(``Calibration.skipped`` and ``skip_reasons``); nothing is only warned about.

Frames of another size than the calibration: when the aspect ratio matches within 0.5 %, the
camera matrix is rescaled to the frame (focal lengths and principal point scale with the image;
the distortion coefficients act on normalised coordinates and stay as they are). Otherwise
``Calibration.for_size`` raises ``CalibrationError`` naming both sizes.
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
    """

    camera_matrix: np.ndarray
    dist_coeffs: np.ndarray
    image_size: tuple[int, int]
    rms_px: float = float("nan")
    used: tuple[str, ...] = ()
    skipped: tuple[str, ...] = ()
    skip_reasons: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        """Return the record as JSON-able lists and numbers."""
        return {
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
                   tuple(d.get("skipped", ())), dict(d.get("skip_reasons", {})))

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

    Parameters
    ----------
    folder : folder of chessboard photos from one camera.
    pattern : inner corners per row and per column, e.g. (9, 6).
    detections : corners found earlier by ``detect_boards`` (to avoid finding them twice).

    Images with no board (or of another size) are skipped and listed with the reason in the
    record's ``skipped`` and ``skip_reasons``; fewer than 3 usable boards raise
    ``CalibrationError``.
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


def parse_pattern(text: str) -> tuple[int, int]:
    """Return (cols, rows) from a pattern like "9x6"; anything else raises InputError."""
    try:
        cols, rows = (int(v) for v in text.lower().split("x"))
        if cols < 2 or rows < 2:
            raise ValueError
    except ValueError:
        raise InputError(f"pattern {text!r}: give inner corners as COLSxROWS, e.g. 9x6") from None
    return cols, rows


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


def undistort_points(calibration: Calibration, pts: np.ndarray) -> np.ndarray:
    """Map (N, 2) raw-image pixel positions to their undistorted positions."""
    K = calibration.camera_matrix
    p = np.asarray(pts, np.float64).reshape(-1, 1, 2)
    return cv2.undistortPoints(p, K, calibration.dist_coeffs, P=K).reshape(-1, 2)


class Undistorter:
    """Undistort frames of one size with remap maps computed once.

    ``calibration`` None means an ideal camera (no distortion): frames pass through unchanged.
    """

    def __init__(self, calibration: Calibration | None, size: tuple[int, int]):
        self.size = (int(size[0]), int(size[1]))
        self.calibration = calibration.for_size(self.size) if calibration is not None else None
        self._maps = None
        if self.calibration is not None:
            c = self.calibration
            self._maps = cv2.initUndistortRectifyMap(c.camera_matrix, c.dist_coeffs, None,
                                                     c.camera_matrix, self.size, cv2.CV_16SC2)

    def check(self, image: np.ndarray, name: str = "frame") -> None:
        """Raise InputError if ``image`` is not a frame of this undistorter's size."""
        if not isinstance(image, np.ndarray) or image.ndim != 3 or image.shape[2] != 3 \
                or image.dtype != np.uint8:
            raise InputError(f"{name}: expected an RGB uint8 image (H x W x 3), got "
                             f"{getattr(image, 'dtype', type(image).__name__)} array of shape "
                             f"{getattr(image, 'shape', '?')}; read images with lanelib.io.read_image")
        h, w = image.shape[:2]
        if (w, h) != self.size:
            raise InputError(f"{name}: is {w}x{h} but the pipeline is set up for "
                             f"{self.size[0]}x{self.size[1]}; make a pipeline for this size "
                             "(LanePipeline(config, calibration, size=...)) or resize the frames")

    def undistort(self, image: np.ndarray) -> np.ndarray:
        """Return the undistorted frame (same size)."""
        self.check(image)
        if self._maps is None:
            return image
        return cv2.remap(image, self._maps[0], self._maps[1], cv2.INTER_LINEAR)

    def maps_through(self, Minv: np.ndarray, out_size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """Return remap maps that take a RAW frame straight to the view ``Minv`` maps back from.

        ``Minv`` maps output pixels to undistorted-image pixels (a perspective's ``Minv``); the
        maps compose it with the lens distortion, so one ``cv2.remap`` does both steps.
        """
        w, h = int(out_size[0]), int(out_size[1])
        xs, ys = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        grid = np.stack([xs.ravel(), ys.ravel()], axis=1).reshape(-1, 1, 2)
        und = cv2.perspectiveTransform(grid, Minv).reshape(-1, 2)
        src = distort_points(self.calibration, und) if self.calibration is not None else und
        # The distortion polynomial folds back far outside the frame: sample nothing there.
        fw, fh = self.size
        outside = ((und[:, 0] < -0.25 * fw) | (und[:, 0] > 1.25 * fw)
                   | (und[:, 1] < -0.25 * fh) | (und[:, 1] > 1.25 * fh))
        src[outside] = -1.0
        mx = src[:, 0].reshape(h, w).astype(np.float32)
        my = src[:, 1].reshape(h, w).astype(np.float32)
        return cv2.convertMaps(mx, my, cv2.CV_16SC2)


class FastBirdseye:
    """Bird's-eye views of raw frames for any perspective, as ``maps_through`` makes them, quickly.

    ``Undistorter.maps_through`` composes undistortion and warp into one remap exactly, which
    takes too long for a slider (the perspective tuner asks for a new one at each change). Here the
    undistortion map of a canvas a quarter of the frame larger on each side (as far as
    ``maps_through`` samples) is made once, and a perspective's remap maps are that map warped
    by ``Minv``. The view is within 2 grey levels of the pipeline's (warping the undistorted
    frame instead, two interpolations, differs by up to 80 and moves marginal line pixels).
    """

    def __init__(self, calibration: Calibration | None, size: tuple[int, int]):
        w, h = size
        self.pad = (w // 4, h // 4)
        cw, ch = w + 2 * self.pad[0], h + 2 * self.pad[1]
        if calibration is None:
            xs, ys = np.meshgrid(np.arange(cw, dtype=np.float32) - self.pad[0],
                                 np.arange(ch, dtype=np.float32) - self.pad[1])
            self.map = np.dstack([xs, ys])
        else:
            K = calibration.camera_matrix
            shifted = K.copy()
            shifted[0, 2] += self.pad[0]
            shifted[1, 2] += self.pad[1]
            self.map = cv2.initUndistortRectifyMap(K, calibration.dist_coeffs, None, shifted,
                                                   (cw, ch), cv2.CV_32FC2)[0]
        self.size = (w, h)

    def birdseye(self, raw: np.ndarray, Minv: np.ndarray) -> np.ndarray:
        """Return the bird's-eye view of a RAW frame for the perspective whose inverse is ``Minv``."""
        to_canvas = np.array([[1, 0, self.pad[0]], [0, 1, self.pad[1]], [0, 0, 1]], float) @ Minv
        maps = cv2.warpPerspective(self.map, to_canvas, self.size,
                                   flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                   borderMode=cv2.BORDER_CONSTANT, borderValue=(-1, -1, -1, -1))
        return cv2.remap(raw, maps, None, cv2.INTER_LINEAR)
