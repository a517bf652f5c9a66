"""Ground truth of the synthetic data: what it holds, how it is computed, written and loaded.

Beside every image ``NAME.jpg`` lies ``NAME.json``; beside every video ``NAME.mp4`` lie
``NAME.csv`` (one row per frame) and ``NAME.json`` (what is the same for every frame: the camera,
the perspective points, the rows sampled). Sign conventions are the pipeline's: curvature is
positive when the road bends to the right, the offset is positive when the car is right of the
lane centre. Line positions are the centres of the painted lines in the RAW (distorted) image at
fixed rows (TuSimple's h_samples), -2 where the line is not visible: outside the image, under the
hood, farther than ``TRUTH_RANGE_M`` ahead, or beyond where the road turns out of the renderer's
reach. Dashed lines are reported through their gaps, as TuSimple marks lane boundaries.

``lines_truth`` gives every painted line of the layout the same way (at any rows and range:
the benchmark samples of ``datasets``); ``lane_truth`` the ego lane's two.

The ego lane's lines are at offsets -w/2 and +w/2 (w = ``Layout.lane_width_m``): under a double
yellow centre line the left one is the inner (right-hand) stripe, and where the right edge is not
painted (``Layout.right_line=False``) the right one is the asphalt edge. On a road with a vertical
profile (``Scene.grades``) every line point is projected at the height of the surface the renderer
draws (``Renderer.heights_ahead``); a point a crest hides is not reported (the first crossing of
each row, going away from the car, is the visible one). The lane width stays the plan-view width.
"""
from __future__ import annotations

import csv
import io as _io
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..camera import Calibration
from ..errors import InputError
from ..io import read_json, write_json, write_text
from ..perspective import DEFAULT_DST_1280x720, DEFAULT_LANE_WIDTH_M, DEFAULT_SRC_1280x720, PerspectiveConfig
from .camera import Camera
from .render import MAX_ROAD_ANGLE_RAD, Renderer
from .road import CarPose, car_frame, world_to_car

H_SAMPLES_PX = tuple(range(420, 720, 10))   # the bundled 1280x720 camera's rows (h_samples_px for others)
NOT_VISIBLE = -2.0
TRUTH_RANGE_M = 100.0
# undistorted rows of the default perspective trapezoid (top, bottom)
BIRD_EYE_ROWS_PX = (DEFAULT_SRC_1280x720[0][1], DEFAULT_SRC_1280x720[1][1])
# distance ahead (m) of the default trapezoid's top row seen by the bundled camera: the top row of
# other cameras' default truth trapezoid
BIRD_EYE_TOP_M = 28.25
IMAGE_FORMAT = "lanelib-synth-image-truth/1"
VIDEO_FORMAT = "lanelib-synth-video-truth/1"
FRAME_COLUMNS = ("frame", "time_s", "curvature_per_m", "radius_m", "offset_m", "heading_rad", "lane_width_m")

Point = tuple[float, float]


# --------------------------------------------------------------------------- records

@dataclass(frozen=True)
class PerspectiveTruth:
    """The exact bird's-eye points of the synthetic camera and the metric scale they carry.

    ``src_px`` are where a straight ``lane_width_m`` lane centred on the car crosses the
    trapezoid's top and bottom rows in the undistorted image (tl, bl, br, tr); ``dst_px`` are the
    default bird's-eye corners. ``visible_length_m`` is the road length between the two rows.
    """

    src_px: tuple[Point, ...]
    dst_px: tuple[Point, ...]
    size_px: tuple[int, int]
    lane_width_m: float
    visible_length_m: float
    xm_per_px: float
    ym_per_px: float

    def config(self) -> PerspectiveConfig:
        """Return the PerspectiveConfig with these points and scale."""
        return PerspectiveConfig(self.src_px, self.dst_px, self.size_px, self.lane_width_m,
                                 self.visible_length_m)


@dataclass(frozen=True)
class CameraTruth:
    """The true camera: intrinsics, distortion, mounting, and its exact perspective points.

    ``roll_deg`` is written to the truth files only when it is not 0 (the bundled camera's files
    do not hold it). ``vanishing_point_px``, ``horizon_px`` and ``birdseye_scale`` give the true
    road geometry that ``lanelib.autogeometry`` estimates.
    """

    camera_matrix: tuple[tuple[float, ...], ...]
    dist_coeffs: tuple[float, ...]
    size_px: tuple[int, int]
    height_m: float
    pitch_deg: float
    yaw_deg: float
    perspective: PerspectiveTruth
    roll_deg: float = 0.0

    def camera(self) -> Camera:
        """Return the synthetic ``Camera`` this record describes."""
        return Camera(tuple(tuple(r) for r in self.camera_matrix), tuple(self.dist_coeffs),
                      tuple(int(v) for v in self.size_px), self.height_m, self.pitch_deg, self.yaw_deg,
                      self.roll_deg)

    def vanishing_point_px(self) -> tuple[float, float]:
        """Return where the car's forward direction vanishes in the undistorted image (x, y px)."""
        return self.camera().vanishing_point_px()

    def horizon_px(self) -> tuple[float, float]:
        """Return the horizon's row at the image centre column (px) and its slope (rows per column)."""
        return self.camera().horizon_px()

    def birdseye_scale(self, src_px, dst_px) -> tuple[float, float]:
        """Return the exact (xm_per_px, ym_per_px) of any bird's-eye points (``birdseye_scale``)."""
        return birdseye_scale(self.camera(), src_px, dst_px)

    def calibration(self) -> Calibration:
        """Return this camera as a ``camera.Calibration`` (exact: RMS reprojection error 0 px)."""
        return Calibration(np.asarray(self.camera_matrix, np.float64),
                           np.asarray(self.dist_coeffs, np.float64),
                           tuple(int(v) for v in self.size_px), 0.0)


@dataclass(frozen=True)
class LaneTruth:
    """The true ego lane in one image or video frame.

    Parameters
    ----------
    curvature_per_m : signed curvature of the lane centre line at the car, positive to the right.
    radius_m : 1 / |curvature| (inf on a straight).
    offset_m : the car's distance from the lane centre, positive when the car is right of it.
    heading_rad : the car's heading relative to the lane, positive when it points to the right.
    lane_width_m : distance between the centres of the two lines.
    h_samples_px : the image rows sampled.
    left_x_px, right_x_px : each line's x in the raw image at those rows, -2 where not visible.
    """

    curvature_per_m: float
    radius_m: float
    offset_m: float
    heading_rad: float
    lane_width_m: float
    h_samples_px: tuple[int, ...]
    left_x_px: tuple[float, ...]
    right_x_px: tuple[float, ...]

    def points(self, side: str) -> np.ndarray:
        """Return the visible (x, y) raw-image points (N, 2) of the ``"left"`` or ``"right"`` line."""
        xs = np.asarray(self.left_x_px if side == "left" else self.right_x_px, dtype=np.float64)
        ys = np.asarray(self.h_samples_px, dtype=np.float64)
        keep = xs != NOT_VISIBLE
        return np.column_stack([xs[keep], ys[keep]])


@dataclass(frozen=True)
class ImageTruth:
    """Ground truth of one synthetic image."""

    path: Path
    seed: int
    lane: LaneTruth
    camera: CameraTruth


@dataclass(frozen=True)
class VideoTruth:
    """Ground truth of one synthetic video: one LaneTruth per frame."""

    path: Path
    seed: int
    fps: float
    frames: tuple[LaneTruth, ...]
    camera: CameraTruth


# --------------------------------------------------------------------------- computing

def h_samples_px(size_px: tuple[int, int]) -> tuple[int, ...]:
    """Return the truth rows of a camera of ``size_px``: H_SAMPLES_PX at 1280x720, else every 10th
    row from the same share of the height (7/12) to the bottom."""
    h = int(size_px[1])
    if h == 720:
        return H_SAMPLES_PX
    return tuple(range(int(round(h * 420 / 720 / 10)) * 10, h, 10))


def default_rows_px(camera: Camera) -> tuple[float, float]:
    """Return the (top, bottom) undistorted rows of ``camera``'s default truth trapezoid.

    A 1280x720 camera's (the bundled one's) are the default points' rows (470, 720), unless its
    horizon comes within 20 px of row 470; another camera's are the row where the road
    BIRD_EYE_TOP_M ahead is seen and the bottom row.
    """
    if tuple(camera.size_px) == (1280, 720) and camera.horizon_px()[0] < BIRD_EYE_ROWS_PX[0] - 20:
        return BIRD_EYE_ROWS_PX
    top = camera.project(np.array([[0.0, 0.0, BIRD_EYE_TOP_M]]), distort=False)[0, 1]
    return float(top), float(camera.size_px[1])


def default_dst_px(size_px: tuple[int, int]) -> tuple[Point, ...]:
    """Return the default bird's-eye rectangle for images of ``size_px``: columns w/4 and 3w/4, all rows."""
    w, h = float(size_px[0]), float(size_px[1])
    return ((w / 4, 0.0), (w / 4, h), (3 * w / 4, h), (3 * w / 4, 0.0))


def birdseye_scale(camera: Camera, src_px, dst_px) -> tuple[float, float]:
    """Return the exact (xm_per_px, ym_per_px) that bird's-eye points give with ``camera``.

    ``src_px`` (tl, bl, br, tr, undistorted image) are cast onto the road: across, the mean of the
    top and bottom edges' lateral extent (m) over their widths in the bird's-eye view; along, the
    mean of the left and right edges' extent ahead (m) over their heights. For src points that
    are the image of a road rectangle (or of any parallelogram with two sides along the road)
    these are the scale of the whole bird's-eye view.
    """
    g = camera.ground_points(np.asarray(src_px, np.float64), distorted=False)
    d = np.asarray(dst_px, np.float64)
    x_m = (abs(g[2, 0] - g[1, 0]) + abs(g[3, 0] - g[0, 0])) / 2
    z_m = (abs(g[0, 1] - g[1, 1]) + abs(g[3, 1] - g[2, 1])) / 2
    w_px = (abs(d[2, 0] - d[1, 0]) + abs(d[3, 0] - d[0, 0])) / 2
    h_px = (abs(d[0, 1] - d[1, 1]) + abs(d[3, 1] - d[2, 1])) / 2
    return float(x_m / w_px), float(z_m / h_px)


def perspective_truth(camera: Camera, lane_width_m: float = DEFAULT_LANE_WIDTH_M,
                      rows_px: tuple[float, float] | None = None,
                      dst_px: tuple[Point, ...] | None = None) -> PerspectiveTruth:
    """Return the exact bird's-eye src points and scale of ``camera`` for a centred straight lane.

    ``rows_px`` are the trapezoid's (top, bottom) undistorted rows (default ``default_rows_px``);
    ``dst_px`` the bird's-eye corners (default: the default points' at 1280x720, else
    ``default_dst_px``).
    """
    top_row, bottom_row = default_rows_px(camera) if rows_px is None else rows_px
    half = lane_width_m / 2
    corners = []
    for row, x_m in ((top_row, -half), (bottom_row, -half), (bottom_row, half), (top_row, half)):
        z = camera.ground_z_on_line(row, x_m)
        u, v = camera.project(np.array([[x_m, 0.0, z]]), distort=False)[0]
        corners.append((round(float(u), 4), round(float(v), 4)))
    length = camera.ground_z_on_line(top_row, 0.0) - camera.ground_z_on_line(bottom_row, 0.0)
    if dst_px is None:
        dst_px = DEFAULT_DST_1280x720 if tuple(camera.size_px) == (1280, 720) else default_dst_px(camera.size_px)
    dst = tuple((float(x), float(y)) for x, y in dst_px)
    cfg = PerspectiveConfig(tuple(corners), dst, tuple(camera.size_px), lane_width_m, length)
    return PerspectiveTruth(cfg.src_px, cfg.dst_px, cfg.size_px, lane_width_m, length,
                            cfg.xm_per_px, cfg.ym_per_px)


def camera_truth(camera: Camera) -> CameraTruth:
    """Return the CameraTruth record of ``camera``."""
    return CameraTruth(tuple(tuple(r) for r in camera.camera_matrix), tuple(camera.dist_coeffs),
                       tuple(camera.size_px), camera.height_m, camera.pitch_deg, camera.yaw_deg,
                       perspective_truth(camera), camera.roll_deg)


def line_x_px(renderer: Renderer, pose: CarPose, t_m: float, rows_px: tuple[int, ...] | None = None,
              range_m: float = TRUTH_RANGE_M) -> tuple[float, ...]:
    """Return the raw-image x (px) of the road line at offset ``t_m`` on each row (-2: not visible).

    Parameters
    ----------
    renderer, pose : the scene, its camera, and where the car stands.
    t_m : the line's offset from the ego lane's centre (m, positive right; ``Line.t_m``).
    rows_px : the image rows (default ``h_samples_px`` of the camera).
    range_m : how far ahead the line is reported (default ``TRUTH_RANGE_M``; at most about
        ``render.LOOK_AHEAD_M`` - 20 m, the road the renderer holds ahead of the car).
    """
    road, camera, grid = renderer.road, renderer.grid.camera, renderer.grid
    origin, heading = car_frame(road, pose)
    pts = world_to_car(road.offset_points(t_m, pose.s_m, pose.s_m + range_m + 20.0), origin, heading)
    i0 = int(np.floor(road.index(pose.s_m)))
    angle = road.heading_rad[i0:i0 + len(pts)] - heading
    ok = ((np.abs(angle) < MAX_ROAD_ANGLE_RAD) & (np.diff(pts[:, 1], prepend=-np.inf) > 0)
          & (pts[:, 1] <= range_m))
    pts = pts[:len(ok) if ok.all() else int(np.argmin(ok))]
    pts = pts[pts[:, 1] > 0.5]
    if road.height_m is None:
        height = np.zeros(len(pts))
    else:  # a pitched road: the surface the renderer draws (Renderer.heights_ahead), y is down
        z_grid, above = renderer.heights_ahead(pose)
        height = -np.interp(pts[:, 1], z_grid, above)
    uv = camera.project(np.column_stack([pts[:, 0], height, pts[:, 1]]))
    w = camera.size_px[0]
    out = []
    for row in (h_samples_px(camera.size_px) if rows_px is None else rows_px):
        v = uv[:, 1] - row
        cross = np.flatnonzero((v[:-1] >= 0) & (v[1:] < 0))
        if cross.size == 0:
            out.append(NOT_VISIBLE)
            continue
        i = cross[0]
        f = v[i] / (v[i] - v[i + 1])
        x = uv[i, 0] + f * (uv[i + 1, 0] - uv[i, 0])
        hidden = not 0.0 <= x <= w - 1 or row > grid.hood_top[int(round(x))]
        out.append(NOT_VISIBLE if hidden else round(float(x), 2))
    return tuple(out)


def lines_truth(renderer: Renderer, pose: CarPose, rows_px: tuple[int, ...] | None = None,
                range_m: float = TRUTH_RANGE_M) -> tuple[tuple[float, tuple[float, ...]], ...]:
    """Return every painted line of the scene as (offset t_m, x px per row), left to right.

    Each line of ``Layout.lines()`` (the stripes of a double centre line are two lines, the
    ``extra_lines`` included), sorted by its offset, with its x on each of ``rows_px`` as
    ``line_x_px`` gives it (-2 where not visible); a line with no visible row is kept, all -2.
    """
    lines = sorted(renderer.scene.layout.lines(), key=lambda line: line.t_m)
    return tuple((line.t_m, line_x_px(renderer, pose, line.t_m, rows_px, range_m)) for line in lines)


def lane_truth(renderer: Renderer, pose: CarPose) -> LaneTruth:
    """Return the true ego lane seen from ``pose`` in ``renderer``'s scene."""
    _, _, curvature = renderer.road.at(pose.s_m)
    half = renderer.scene.layout.lane_width_m / 2
    return LaneTruth(
        curvature_per_m=curvature, radius_m=math.inf if curvature == 0 else 1.0 / abs(curvature),
        offset_m=pose.offset_m, heading_rad=pose.heading_rad,
        lane_width_m=renderer.scene.layout.lane_width_m,
        h_samples_px=h_samples_px(renderer.grid.camera.size_px),
        left_x_px=line_x_px(renderer, pose, -half), right_x_px=line_x_px(renderer, pose, half))


# --------------------------------------------------------------------------- writing

def camera_json(cam: CameraTruth) -> dict:
    """Return the JSON form of a CameraTruth."""
    p = cam.perspective
    return {
        "camera_matrix": [list(r) for r in cam.camera_matrix], "dist_coeffs": list(cam.dist_coeffs),
        "image_size": list(cam.size_px), "height_m": cam.height_m, "pitch_deg": cam.pitch_deg,
        "yaw_deg": cam.yaw_deg, **({"roll_deg": cam.roll_deg} if cam.roll_deg else {}),
        "perspective": {"src_px": [list(q) for q in p.src_px], "dst_px": [list(q) for q in p.dst_px],
                        "size_px": list(p.size_px), "lane_width_m": p.lane_width_m,
                        "visible_length_m": round(p.visible_length_m, 6),
                        "xm_per_px": round(p.xm_per_px, 9), "ym_per_px": round(p.ym_per_px, 9)},
    }


def _lane_values(lane: LaneTruth) -> dict:
    """Return the per-frame scalars of a LaneTruth, rounded for the files (radius None when straight)."""
    return {"curvature_per_m": round(lane.curvature_per_m, 9),
            "radius_m": None if math.isinf(lane.radius_m) else round(lane.radius_m, 3),
            "offset_m": round(lane.offset_m, 5), "heading_rad": round(lane.heading_rad, 6),
            "lane_width_m": round(lane.lane_width_m, 4)}


def write_image_truth(image_path: str | os.PathLike, seed: int, lane: LaneTruth, camera: CameraTruth) -> Path:
    """Write the JSON truth beside ``image_path`` and return its path."""
    image = Path(image_path)
    obj = {"format": IMAGE_FORMAT, "image": image.name, "seed": seed, **_lane_values(lane),
           "h_samples_px": list(lane.h_samples_px),
           "lines_x_px": {"left": list(lane.left_x_px), "right": list(lane.right_x_px)},
           "camera": camera_json(camera)}
    return write_json(image.with_suffix(".json"), obj)


def write_video_truth(video_path: str | os.PathLike, seed: int, fps: float, lanes: list[LaneTruth],
                      camera: CameraTruth, extra: dict | None = None) -> tuple[Path, Path]:
    """Write the per-frame CSV and the JSON of constants beside ``video_path``; return both paths."""
    video = Path(video_path)
    h = lanes[0].h_samples_px
    buf = _io.StringIO()
    out = csv.writer(buf, lineterminator="\n")
    out.writerow(FRAME_COLUMNS + tuple(f"left_x_{r}" for r in h) + tuple(f"right_x_{r}" for r in h))
    for i, lane in enumerate(lanes):
        v = _lane_values(lane)
        radius = "inf" if v["radius_m"] is None else v["radius_m"]
        out.writerow([i, round(i / fps, 4), v["curvature_per_m"], radius, v["offset_m"], v["heading_rad"],
                      v["lane_width_m"], *lane.left_x_px, *lane.right_x_px])
    csv_path = write_text(video.with_suffix(".csv"), buf.getvalue())
    meta = {"format": VIDEO_FORMAT, "video": video.name, "seed": seed, "fps": fps, "frames": len(lanes),
            **(extra or {}), "h_samples_px": list(h), "camera": camera_json(camera)}
    return csv_path, write_json(video.with_suffix(".json"), meta)


# --------------------------------------------------------------------------- loading

def _truth_file(data_path: str | os.PathLike, suffix: str) -> Path:
    """Return the truth file with ``suffix`` beside ``data_path``; InputError if it is missing."""
    data = Path(data_path)
    truth = data.with_suffix(suffix)
    if not truth.is_file():
        raise InputError(f"{truth}: no ground truth beside {data.name}; synthetic data carries its truth "
                         "in a file of the same name (regenerate with `python -m lanelib synth --all`)")
    return truth


def camera_from_json(obj: dict, where: Path) -> CameraTruth:
    """Return the CameraTruth stored in a truth file's ``camera`` entry."""
    try:
        p = obj["perspective"]
        persp = PerspectiveTruth(tuple(tuple(q) for q in p["src_px"]), tuple(tuple(q) for q in p["dst_px"]),
                                 tuple(p["size_px"]), float(p["lane_width_m"]), float(p["visible_length_m"]),
                                 float(p["xm_per_px"]), float(p["ym_per_px"]))
        return CameraTruth(tuple(tuple(r) for r in obj["camera_matrix"]), tuple(obj["dist_coeffs"]),
                           tuple(obj["image_size"]), float(obj["height_m"]), float(obj["pitch_deg"]),
                           float(obj["yaw_deg"]), persp, float(obj.get("roll_deg", 0.0)))
    except (KeyError, TypeError, ValueError) as e:
        raise InputError(f"{where}: the camera entry is incomplete ({e!r}); regenerate the truth") from None


def load_image_truth(image_path: str | os.PathLike) -> ImageTruth:
    """Return the ground truth of a synthetic image, read from the JSON beside it.

    Raises
    ------
    InputError
        If the JSON is missing, malformed, or lacks a field.
    """
    path = _truth_file(image_path, ".json")
    obj = read_json(path, "ground-truth file")
    try:
        radius = obj["radius_m"]
        lane = LaneTruth(float(obj["curvature_per_m"]), math.inf if radius is None else float(radius),
                         float(obj["offset_m"]), float(obj["heading_rad"]), float(obj["lane_width_m"]),
                         tuple(int(r) for r in obj["h_samples_px"]),
                         tuple(float(x) for x in obj["lines_x_px"]["left"]),
                         tuple(float(x) for x in obj["lines_x_px"]["right"]))
        seed = int(obj["seed"])
        camera = obj["camera"]
    except (KeyError, TypeError, ValueError) as e:
        raise InputError(f"{path}: not an image ground-truth file (missing or bad {e!r}); "
                         "regenerate it") from None
    return ImageTruth(Path(image_path), seed, lane, camera_from_json(camera, path))


def load_video_truth(video_path: str | os.PathLike) -> VideoTruth:
    """Return the per-frame ground truth of a synthetic video, read from the CSV and JSON beside it.

    Raises
    ------
    InputError
        If either file is missing or malformed.
    """
    csv_path, meta_path = _truth_file(video_path, ".csv"), _truth_file(video_path, ".json")
    meta = read_json(meta_path, "ground-truth file")
    try:
        h = tuple(int(r) for r in meta["h_samples_px"])
        fps, seed, camera = float(meta["fps"]), int(meta["seed"]), meta["camera"]
        with open(csv_path, newline="") as f:
            rows = list(csv.DictReader(f))
        frames = tuple(LaneTruth(float(r["curvature_per_m"]), float(r["radius_m"]), float(r["offset_m"]),
                                 float(r["heading_rad"]), float(r["lane_width_m"]), h,
                                 tuple(float(r[f"left_x_{y}"]) for y in h),
                                 tuple(float(r[f"right_x_{y}"]) for y in h)) for r in rows)
    except (KeyError, TypeError, ValueError) as e:
        raise InputError(f"{csv_path}: not a video ground-truth file (missing or bad {e!r}); "
                         "regenerate it") from None
    if not frames:
        raise InputError(f"{csv_path}: holds no frames; regenerate it")
    return VideoTruth(Path(video_path), seed, fps, frames, camera_from_json(camera, meta_path))


@dataclass(frozen=True)
class BoardTruth:
    """Ground truth of the chessboard photographs: the true camera and every board's inner corners.

    ``corners_px`` maps an image name to its (54, 2) raw-image corners, row by row, x fastest;
    ``fully_visible`` says whether all of them lie inside the image.
    """

    camera_matrix: np.ndarray
    dist_coeffs: np.ndarray
    size_px: tuple[int, int]
    pattern_size: tuple[int, int]
    corners_px: dict[str, np.ndarray]
    fully_visible: dict[str, bool]


def load_board_truth(cal_dir: str | os.PathLike) -> BoardTruth:
    """Return the truth of a folder of synthetic chessboards, read from its ``camera_truth.json``.

    Raises
    ------
    InputError
        If the file is missing, malformed, or lacks a field.
    """
    path = Path(cal_dir) / "camera_truth.json"
    if not path.is_file():
        raise InputError(f"{path}: no ground truth in {cal_dir}; the synthetic chessboards carry "
                         "camera_truth.json (regenerate with `python -m lanelib synth --all`)")
    obj = read_json(path, "ground-truth file")
    try:
        images = obj["images"]
        return BoardTruth(np.asarray(obj["camera_matrix"], np.float64),
                          np.asarray(obj["dist_coeffs"], np.float64),
                          tuple(obj["image_size"]), tuple(obj["pattern_size"]),
                          {k: np.asarray(v["corners_px"], np.float64) for k, v in images.items()},
                          {k: bool(v["fully_visible"]) for k, v in images.items()})
    except (KeyError, TypeError, ValueError) as e:
        raise InputError(f"{path}: not a chessboard ground-truth file (missing or bad {e!r}); "
                         "regenerate it") from None
