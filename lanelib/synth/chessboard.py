"""Chessboard photographs taken with the synthetic camera, for calibration with known answers.

A 9x6-inner-corner board (10 x 7 squares on white paper) is placed at 20 poses in front of a wall:
centred, near the corners and edges where the distortion is strongest, near and far, tilted, and
three cut off by the frame (OpenCV finds no board in those, as in the Udacity set). Each image is
rendered through the distorted camera with the checker pattern box-filtered over every pixel's
footprint on the board, then lit unevenly, given noise and a slight blur, and saved as JPEG.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .camera import Camera

PATTERN_SIZE = (9, 6)        # inner corners (columns, rows)
PAPER_MARGIN_SQ = 0.7        # white paper around the squares, in squares
EDGE_MARGIN_PX = 8.0         # a board is fully visible if all corners are this far inside

# (centre u, centre v as fractions of the image, distance in squares, tilt about x, about y,
#  roll, degrees). The last three boards are cut off by the frame.
BOARD_POSES = (
    (0.50, 0.50, 22, 0, 0, 0), (0.24, 0.27, 26, 20, -25, 5), (0.76, 0.27, 26, 20, 25, -5),
    (0.24, 0.73, 26, -20, -25, -8), (0.76, 0.73, 26, -20, 25, 8), (0.50, 0.24, 24, 35, 0, 3),
    (0.50, 0.76, 24, -35, 0, -3), (0.19, 0.50, 24, 0, -40, 10), (0.81, 0.50, 24, 0, 40, -10),
    (0.50, 0.50, 17, 10, 15, 20), (0.36, 0.42, 30, -15, 30, -15), (0.64, 0.58, 30, 15, -30, 15),
    (0.16, 0.21, 32, 15, -15, 0), (0.84, 0.79, 32, -15, 15, 0), (0.84, 0.21, 32, 25, 20, 12),
    (0.16, 0.79, 32, -25, -20, -12), (0.50, 0.46, 19, -30, 25, 30),
    (0.03, 0.50, 20, 0, -20, 0), (0.60, 0.97, 18, -20, 10, 5), (0.97, 0.10, 22, 10, 30, 0),
)


@dataclass(frozen=True)
class Board:
    """A board pose in camera coordinates: origin at inner corner (0, 0), axes along the rows and columns.

    Units are squares; ``rotation`` columns are the board's x, y axes and normal in the camera frame.
    """

    rotation: np.ndarray
    origin: np.ndarray

    def corners(self) -> np.ndarray:
        """Return the (54, 3) inner corners in camera coordinates, x fastest (index j * 9 + i)."""
        i, j = np.meshgrid(np.arange(PATTERN_SIZE[0]), np.arange(PATTERN_SIZE[1]))
        grid = np.column_stack([i.ravel(), j.ravel(), np.zeros(i.size)])
        return grid @ self.rotation.T + self.origin


def _rotation(tilt_x_deg: float, tilt_y_deg: float, roll_deg: float) -> np.ndarray:
    """Return the board-to-camera rotation for tilts about the camera's x and y axes and a roll."""
    rx, ry, rz = np.radians([tilt_x_deg, tilt_y_deg, roll_deg])
    rot_x = np.array([[1, 0, 0], [0, np.cos(rx), -np.sin(rx)], [0, np.sin(rx), np.cos(rx)]])
    rot_y = np.array([[np.cos(ry), 0, np.sin(ry)], [0, 1, 0], [-np.sin(ry), 0, np.cos(ry)]])
    rot_z = np.array([[np.cos(rz), -np.sin(rz), 0], [np.sin(rz), np.cos(rz), 0], [0, 0, 1]])
    return rot_x @ rot_y @ rot_z


def board_poses(camera: Camera, rng: np.random.Generator) -> list[Board]:
    """Return the 20 board poses, jittered by ``rng``."""
    w, h = camera.size_px
    boards = []
    for fu, fv, dist, tx, ty, roll in BOARD_POSES:
        fu, fv = fu + rng.uniform(-0.015, 0.015), fv + rng.uniform(-0.015, 0.015)
        dist = dist * rng.uniform(0.95, 1.05)
        rot = _rotation(*(np.array([tx, ty, roll]) + rng.uniform(-3, 3, 3)))
        ray = camera.rays(np.array([[fu * w, fv * h]]))[0] @ camera.rotation().T  # camera frame, z = 1
        centre = ray / np.linalg.norm(ray) * dist
        half = np.array([(PATTERN_SIZE[0] - 1) / 2, (PATTERN_SIZE[1] - 1) / 2, 0.0])
        boards.append(Board(rot, centre - rot @ half))
    return boards


def _coverage(a: np.ndarray, wa: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Return the share of the footprint [a - wa/2, a + wa/2] inside [lo, hi]."""
    return (np.clip(a + wa / 2, lo, hi) - np.clip(a - wa / 2, lo, hi)) / wa


def _checker(a: np.ndarray, wa: np.ndarray) -> np.ndarray:
    """Return the box-filtered square wave (+1 on even squares, -1 on odd) along one board axis."""
    def integral(x):
        m = x - 2.0 * np.floor(x / 2.0)
        return 1.0 - np.abs(m - 1.0)
    return (integral(a + wa / 2) - integral(a - wa / 2)) / wa


def camera_normals(camera: Camera) -> np.ndarray:
    """Return the normalised camera-frame ray (x, y) of every pixel (H, W, 2) of the distorted image."""
    w, h = camera.size_px
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    rays = camera.rays(np.column_stack([u.ravel(), v.ravel()])) @ camera.rotation().T
    return (rays[:, :2] / rays[:, 2:]).reshape(h, w, 2)


def render_board(camera: Camera, normals: np.ndarray, board: Board, rng: np.random.Generator) -> np.ndarray:
    """Return the RGB uint8 photograph of ``board`` (normals from ``camera_normals``)."""
    w, h = camera.size_px
    n = board.rotation[:, 2]
    rays = np.concatenate([normals, np.ones(normals.shape[:2] + (1,))], axis=2)
    with np.errstate(divide="ignore", invalid="ignore"):
        lam = (board.origin @ n) / (rays @ n)
    hit = rays * lam[..., None] - board.origin
    a, b = hit @ board.rotation[:, 0], hit @ board.rotation[:, 1]
    front = lam > 0
    a, b = np.where(front, a, -1e3), np.where(front, b, -1e3)
    wa = np.clip(np.abs(np.gradient(a, axis=1)) + np.abs(np.gradient(a, axis=0)), 1e-3, 50)
    wb = np.clip(np.abs(np.gradient(b, axis=1)) + np.abs(np.gradient(b, axis=0)), 1e-3, 50)
    nx, ny = PATTERN_SIZE
    squares = _coverage(a, wa, -1, nx) * _coverage(b, wb, -1, ny)
    paper = (_coverage(a, wa, -1 - PAPER_MARGIN_SQ, nx + PAPER_MARGIN_SQ)
             * _coverage(b, wb, -1 - PAPER_MARGIN_SQ, ny + PAPER_MARGIN_SQ))
    black = 0.5 + 0.5 * _checker(a + 1.0, wa) * _checker(b + 1.0, wb)  # square (-1..0, -1..0) is black
    wall = 120.0 + 12.0 * cv2.GaussianBlur(rng.standard_normal((h, w)), (0, 0), 6.0) * 4.0
    grey = wall + (218.0 - wall) * paper - (218.0 - 38.0) * black * squares
    u, v = np.meshgrid(np.linspace(-1, 1, w), np.linspace(-1, 1, h))
    gx, gy = rng.uniform(-0.15, 0.15, 2)
    grey = grey * (1.0 + gx * u + gy * v) * (1.0 - 0.12 * (u * u + v * v))
    tint = np.array([1.0, 0.98, 0.93]) * rng.uniform(0.92, 1.05)
    img = grey[..., None] * tint + rng.normal(0.0, 2.0, (h, w, 3))
    return cv2.GaussianBlur(np.clip(img, 0, 255).astype(np.uint8), (3, 3), 0.7)


def board_corners_px(camera: Camera, board: Board) -> np.ndarray:
    """Return the true (54, 2) raw-image positions of the board's inner corners (x fastest)."""
    cam = board.corners()
    uv, _ = cv2.projectPoints(cam.reshape(-1, 1, 3), np.zeros(3), np.zeros(3), camera.K, camera.dist)
    return uv.reshape(-1, 2)


def fully_visible(camera: Camera, corners_px: np.ndarray) -> bool:
    """Return True if every corner lies at least EDGE_MARGIN_PX inside the image."""
    w, h = camera.size_px
    x, y = corners_px[:, 0], corners_px[:, 1]
    return bool(np.all((x >= EDGE_MARGIN_PX) & (x <= w - 1 - EDGE_MARGIN_PX)
                       & (y >= EDGE_MARGIN_PX) & (y <= h - 1 - EDGE_MARGIN_PX)))
