"""The synthetic camera: the Udacity highway camera's intrinsics, mounted on a car.

The matrix and distortion are those of the Udacity ``camera_cal`` boards, calibrated once with
plain OpenCV (``findChessboardCorners`` 9x6 + ``cornerSubPix`` + ``calibrateCamera`` on the 17
boards that are found, RMS 1.003 px) and kept here so that the generator needs no outside data.

The mounting is chosen so that lanelib's default bird's-eye points (``perspective.DEFAULT_SRC_1280x720``)
fit this camera: in the undistorted image the car's forward direction vanishes at the apex of the
default trapezoid, (640, 419.03), and a straight 3.7 m lane centred on the car crosses the bottom
row (720) at x = 192.79 and x = 1086.79 (the default corners are 193 and 1087; three mounting
angles cannot meet four pixel targets, and 0.2 px is what remains). The camera sits 1.2513 m above
the road, pitched 1.483 deg up and turned 1.551 deg to the right (the principal point is at
x = 671, right of the image centre).

Other cameras: ``Camera.pinhole`` builds an ideal (or mildly distorted) camera of any size, focal
length and mounting, including a roll about the optical axis (``roll_deg``, 0 for the bundled
camera, which stays the same bit for bit). ``vanishing_point_px`` and ``horizon_px`` give the
geometry that ``lanelib.autogeometry`` estimates from the road.

Frames: the car frame has its origin on the road surface below the camera, x to the right,
y down and z forward, in metres. The road is the plane y = 0.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

# Udacity camera_cal, 17 boards, plain OpenCV calibration (RMS 1.003 px).
UDACITY_CAMERA_MATRIX = ((1156.4576, 0.0, 671.3197),
                         (0.0, 1151.2673, 389.2167),
                         (0.0, 0.0, 1.0))
UDACITY_DIST_COEFFS = (-0.24667049, -0.025444482, -0.00067022409, 0.00013403439, 0.010671371)
IMAGE_SIZE_PX = (1280, 720)

# Mounting that makes the default perspective points fit (see the module docstring).
MOUNT_HEIGHT_M = 1.2512781
MOUNT_PITCH_DEG = -1.4834256
MOUNT_YAW_DEG = 1.5508110

_UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)


@dataclass(frozen=True)
class Camera:
    """A pinhole camera with radial and tangential distortion, mounted on a car.

    Parameters
    ----------
    camera_matrix : 3x3 intrinsic matrix (pixels).
    dist_coeffs : OpenCV distortion (k1, k2, p1, p2, k3).
    size_px : image (width, height).
    height_m : height of the optical centre above the road.
    pitch_deg : tilt of the optical axis, positive down.
    yaw_deg : turn of the optical axis from the car's forward direction, positive right.
    roll_deg : turn of the camera about its optical axis, positive when its right side dips (the
        horizon then rises to the right in the image: its row falls by tan(roll) per column).
    """

    camera_matrix: tuple[tuple[float, ...], ...] = UDACITY_CAMERA_MATRIX
    dist_coeffs: tuple[float, ...] = UDACITY_DIST_COEFFS
    size_px: tuple[int, int] = IMAGE_SIZE_PX
    height_m: float = MOUNT_HEIGHT_M
    pitch_deg: float = MOUNT_PITCH_DEG
    yaw_deg: float = MOUNT_YAW_DEG
    roll_deg: float = 0.0

    @staticmethod
    def pinhole(size_px: tuple[int, int], hfov_deg: float | None = None, focal_px: float | None = None,
                height_m: float = MOUNT_HEIGHT_M, pitch_deg: float = 0.0, yaw_deg: float = 0.0,
                roll_deg: float = 0.0, dist_coeffs: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0),
                principal_px: tuple[float, float] | None = None) -> "Camera":
        """Return a camera with square pixels of ``size_px`` (w, h), mounted as given.

        The focal length is ``focal_px``, or the one that gives a horizontal field of view of
        ``hfov_deg`` (exactly one of the two). The principal point is the image centre unless
        ``principal_px`` says otherwise; ``dist_coeffs`` (OpenCV k1, k2, p1, p2, k3) default to
        none (an ideal pinhole).
        """
        if (hfov_deg is None) == (focal_px is None):
            raise ValueError("Camera.pinhole: give exactly one of hfov_deg and focal_px")
        w, h = int(size_px[0]), int(size_px[1])
        f = float(focal_px) if focal_px is not None else w / 2 / np.tan(np.radians(hfov_deg) / 2)
        cx, cy = principal_px if principal_px is not None else (w / 2, h / 2)
        matrix = ((f, 0.0, float(cx)), (0.0, f, float(cy)), (0.0, 0.0, 1.0))
        return Camera(matrix, tuple(float(d) for d in dist_coeffs), (w, h), float(height_m),
                      float(pitch_deg), float(yaw_deg), float(roll_deg))

    @property
    def K(self) -> np.ndarray:
        """Return the 3x3 camera matrix as float64."""
        return np.asarray(self.camera_matrix, dtype=np.float64)

    @property
    def dist(self) -> np.ndarray:
        """Return the distortion coefficients as float64."""
        return np.asarray(self.dist_coeffs, dtype=np.float64)

    def rotation(self) -> np.ndarray:
        """Return R (3x3) with camera = R @ (car - centre); rows are the camera axes in the car frame."""
        p, y = np.radians(self.pitch_deg), np.radians(self.yaw_deg)
        z_axis = np.array([np.sin(y) * np.cos(p), np.sin(p), np.cos(y) * np.cos(p)])
        x_axis = np.array([np.cos(y), 0.0, -np.sin(y)])
        y_axis = np.cross(z_axis, x_axis)
        if self.roll_deg:
            r = np.radians(self.roll_deg)
            x_axis, y_axis = np.cos(r) * x_axis + np.sin(r) * y_axis, np.cos(r) * y_axis - np.sin(r) * x_axis
        return np.stack([x_axis, y_axis, z_axis])

    def vanishing_point_px(self) -> tuple[float, float]:
        """Return where the car's forward direction vanishes in the undistorted image (x, y px)."""
        d = self.K @ self.rotation()[:, 2]
        return float(d[0] / d[2]), float(d[1] / d[2])

    def horizon_px(self) -> tuple[float, float]:
        """Return the horizon in the undistorted image: (its row at the image centre column w/2,
        its slope in rows per column). The horizon is the image of every horizontal direction."""
        line = np.linalg.inv(self.K).T @ self.rotation()[:, 1]   # l . (x, y, 1) = 0
        slope = -line[0] / line[1]
        x = self.size_px[0] / 2
        return float(-(line[0] * x + line[2]) / line[1]), float(slope)

    def centre(self) -> np.ndarray:
        """Return the optical centre in the car frame (m)."""
        return np.array([0.0, -self.height_m, 0.0])

    def to_camera(self, points_car: np.ndarray) -> np.ndarray:
        """Return (N, 3) car-frame points (m) in camera coordinates (m)."""
        return (np.asarray(points_car, dtype=np.float64) - self.centre()) @ self.rotation().T

    def max_field_radius(self) -> float:
        """Return the largest normalised (undistorted) radius seen by the image corners."""
        w, h = self.size_px
        corners = np.array([[0.0, 0.0], [w - 1.0, 0.0], [0.0, h - 1.0], [w - 1.0, h - 1.0]])
        norm = cv2.undistortPoints(corners.reshape(-1, 1, 2), self.K, self.dist, None, None, None,
                                   _UNDISTORT_CRITERIA).reshape(-1, 2)
        return float(np.hypot(norm[:, 0], norm[:, 1]).max())

    def project(self, points_car: np.ndarray, distort: bool = True) -> np.ndarray:
        """Return the (N, 2) pixel positions of (N, 3) car-frame points (m).

        Points behind the camera, and (with ``distort``) points well outside the field of view,
        where the distortion polynomial folds back into the image, are NaN. ``distort=False`` gives
        positions in the undistorted image (same camera matrix).
        """
        pc = self.to_camera(points_car).reshape(-1, 3)
        dist = self.dist if distort else np.zeros(5)
        uv, _ = cv2.projectPoints(pc.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), self.K, dist)
        uv = uv.reshape(-1, 2)
        ahead = pc[:, 2] > 1e-6
        uv[~ahead] = np.nan
        if distort:
            with np.errstate(divide="ignore", invalid="ignore"):
                radius = np.hypot(pc[:, 0], pc[:, 1]) / pc[:, 2]
            uv[ahead & (radius > 1.1 * self.max_field_radius())] = np.nan
        return uv

    def rays(self, uv: np.ndarray, distorted: bool = True) -> np.ndarray:
        """Return the (N, 3) car-frame ray directions (z_cam = 1 scale) through (N, 2) pixels."""
        pts = np.asarray(uv, dtype=np.float64).reshape(-1, 1, 2)
        dist = self.dist if distorted else np.zeros(5)
        norm = cv2.undistortPoints(pts, self.K, dist, None, None, None, _UNDISTORT_CRITERIA)
        norm = norm.reshape(-1, 2)
        cam = np.column_stack([norm, np.ones(len(norm))])
        return cam @ self.rotation()

    def ground_points(self, uv: np.ndarray, distorted: bool = True) -> np.ndarray:
        """Return the (N, 2) road points (x, z) in metres seen at (N, 2) pixels; NaN above the horizon."""
        r = self.rays(uv, distorted)
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = np.where(r[:, 1] > 0, self.height_m / r[:, 1], np.nan)
        return np.column_stack([lam * r[:, 0], lam * r[:, 2]])

    def ground_z_on_line(self, row_px: float, x_m: float) -> float:
        """Return the distance ahead (m) where the road line x = ``x_m`` crosses an undistorted image row."""
        # The row's plane through the camera centre: n . (P - C) = 0 with n = R^T (0, fy, cy - row).
        n = self.rotation().T @ np.array([0.0, self.K[1, 1], self.K[1, 2] - row_px])
        c = self.centre()
        # P = (x_m, 0, z): n0 (x_m - c0) + n1 (0 - c1) + n2 z = 0
        return float(-(n[0] * (x_m - c[0]) + n[1] * (0.0 - c[1])) / n[2])
