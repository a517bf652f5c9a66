"""The road geometry a run uses, and its watch through a video.

``GeometryOptions`` says how ``--auto-geometry`` estimates the geometry (``estimate``) and, through
a video, how often it checks it; ``checked_geometry`` refuses an estimate that fails or is not
confident, with a message naming the source and the fix; ``geometry_calibration`` is the lens a
run undistorts with. ``GeometryWatch`` checks the vanishing point every few frames through a
video: it refines the point along the horizon as straight road accumulates, and estimates the
geometry again when the horizon moves (a crest, a dip, a knocked camera). A watch pickles small and
carries its evidence through a record of its checks, which the Dask segments of a video run use
(``lanelib.batch``).
"""
from __future__ import annotations

import hashlib
import math
import os
import pickle
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from ..camera import Calibration
from ..errors import ConfigError, GeometryError, naming_the_file
from ..perspective import DEFAULT_LANE_WIDTH_M
from .estimate import DEFAULT_DASH_M, DEFAULT_GAP_M, DEFAULT_LOOK_AHEAD_M, MIN_GOOD_FRAMES, estimate_geometry
from .roadgeometry import DRIFT_PX, LOW_CONFIDENCE, RoadGeometry, refined_geometry
from .vanishing import RoadLineFinder


@dataclass(frozen=True)
class GeometryOptions:
    """How ``--auto-geometry`` estimates the road geometry and, through a video, checks it.

    Parameters
    ----------
    lane_width_m, look_ahead_m, dash_m, gap_m, focal_px : as for ``autogeometry.estimate_geometry``.
    seconds : of a video read for the estimate, from its start (or from ``start_s``).
    max_frames : frames of those (or of a folder's images) used, evenly spread.
    check_every_s : through a video, the vanishing point is measured this often
        (``autogeometry.RoadLineFinder``, about 15 ms a frame); the straight checks refine it
        along the horizon (``GeometryWatch``).
    drift_checks : this many checks in a row with the vanishing point off the horizon (by more
        than ``autogeometry.DRIFT_PX`` or 1 % of the height: a crest, a dip, a knocked camera) call
        for a new estimate from those frames (fewer than ``autogeometry.MIN_GOOD_FRAMES``, 5, give
        too little confidence for a new estimate to be used).
    accept_low_confidence : use an estimate below ``autogeometry.LOW_CONFIDENCE`` (refused otherwise).
    """

    lane_width_m: float = DEFAULT_LANE_WIDTH_M
    look_ahead_m: float = DEFAULT_LOOK_AHEAD_M
    dash_m: float = DEFAULT_DASH_M
    gap_m: float = DEFAULT_GAP_M
    focal_px: float | None = None
    seconds: float = 20.0
    max_frames: int = 50
    check_every_s: float = 0.5
    drift_checks: int = 5
    accept_low_confidence: bool = False

    def __post_init__(self):
        if not (self.seconds > 0 and self.max_frames >= 1 and self.check_every_s > 0
                and self.drift_checks >= 1):
            raise ConfigError("geometry options: seconds and check_every_s must be positive, "
                              "max_frames and drift_checks 1 or more")

    def estimate(self, frames: Sequence[np.ndarray], calibration: Calibration | None,
                 hood_row_px: float | None = None, lens_from_road: bool = True) -> RoadGeometry:
        """Return ``autogeometry.estimate_geometry`` of ``frames`` with these options.

        ``lens_from_road``: with no calibration, let the estimate measure the lens from the lane
        lines' bend (``autogeometry.estimate_lens``); a run then undistorts with it
        (``geometry_calibration``). Off for callers that cannot undistort with it.
        """
        return estimate_geometry(frames, calibration, focal_px=self.focal_px,
                                          lane_width_m=self.lane_width_m, look_ahead_m=self.look_ahead_m,
                                          dash_m=self.dash_m, gap_m=self.gap_m, hood_row_px=hood_row_px,
                                          lens_from_road=lens_from_road)


def checked_geometry(frames: Sequence[np.ndarray], source: str | os.PathLike,
                     calibration: Calibration | None, options: GeometryOptions,
                     lens_from_road: bool = True) -> RoadGeometry:
    """Return the road geometry of ``frames`` (taken from ``source``, a video or a folder;
    ``lens_from_road``: as for ``GeometryOptions.estimate``).

    Raises
    ------
    GeometryError
        As ``estimate_road_geometry``: no consistent vanishing point, or a confidence below
        ``autogeometry.LOW_CONFIDENCE`` without ``options.accept_low_confidence``; the message names
        ``source`` and the fix.
    """
    try:
        geo = options.estimate(frames, calibration, lens_from_road=lens_from_road)
    except GeometryError as e:
        raise GeometryError(naming_the_file(str(e), Path(source))) from None
    if geo.low_confidence and not options.accept_low_confidence:
        fixes = ([] if calibration is not None or options.focal_px else ["a calibration (--calibration)"])
        fixes.append("frames of a longer straight stretch" + ("" if Path(source).is_dir() else
                                                              " (--geometry-seconds)"))
        raise GeometryError(f"{source}: {low_confidence(geo, len(frames))} ({'; '.join(geo.assumptions)}); "
                            f"give {' or '.join(fixes)}, or pass --accept-low-confidence to use it anyway")
    return geo


def low_confidence(geo: RoadGeometry, n_frames: int) -> str:
    """Return why ``geo``, estimated from ``n_frames`` frames, is refused for its confidence."""
    return (f"the road geometry estimated from {n_frames} frames ({len(geo.frames_used)} on straight "
            f"road) has confidence {geo.confidence:.2f}, below {LOW_CONFIDENCE}")


def geometry_calibration(calibration: Calibration | None, geo: RoadGeometry) -> Calibration | None:
    """Return the calibration to run with ``geo``: the one given, else the lens the estimate
    measured from the road's lines (``RoadGeometry.lens``; its points are for frames undistorted
    with it), else None."""
    return calibration if calibration is not None else geo.lens



# The watch refines the vanishing point's place along the horizon (the car's straight-ahead
# direction: the road's, on average over straight road) from the straight checks' points:
# at least this many of them, and at least as many as the estimate in use rests on (its
# ``frames_used``), so that a refinement rests on more straight road than the estimate it corrects
REFINE_MIN_CHECKS = 2 * MIN_GOOD_FRAMES
# ... and only when their median lies farther from the point in use than its standard error plus
# this share of the width, about the noise of one check's column from one check to the next: a
# shift smaller than one check's noise is not worth restarting the tracker for, and it is the
# hysteresis that keeps the point from going back and forth
REFINE_TOLERANCE = 0.005
# the last this many straight checks count (5 minutes of straight road at 2 checks a second), and
# the record of them a Dask joint reads holds as many: a watch pickles small however long the video
REFINE_MAX_CHECKS = 600


class _NeedsFrames(Exception):
    """A watch carried through a record of checks (no frames) reached a new estimate."""


class GeometryWatch:
    """Through a video, check the road geometry: refine the vanishing point along the horizon as
    straight road accumulates, and estimate the geometry again when the horizon moves.

    ``check(frame, index, time_s)`` measures the frame's vanishing point every
    ``options.check_every_s``; frames where the road bends say nothing (``VanishingPoint.ok``).
    It returns the geometry to use from this frame on when it changed (None otherwise); ``notes``
    says what happened and why.

    - **Drift.** After ``options.drift_checks`` checks in a row whose point lies off the horizon
      (``RoadGeometry.horizon_shift_px`` beyond ``autogeometry.DRIFT_PX`` or 1 % of the height: a
      crest, a dip, a knocked camera) it estimates the geometry from those frames. A failed or
      low-confidence new estimate keeps the old geometry. A new estimate starts the refinement
      afresh.
    - **Refinement.** The first estimate's point is where the road headed, on average, in the
      first seconds' straight frames: a gentle curve or the car's wander across its lane puts
      it a few px aside, which moves the car's column in the bird's-eye view and so the
      offset read. The points of the straight checks on the horizon (the last
      ``REFINE_MAX_CHECKS``) are kept; once there are ``REFINE_MIN_CHECKS`` of them and at least
      as many as the estimate in use rests on, and their median along the horizon lies
      farther from the point in use than its standard error (1.25 x 1.48 x MAD / sqrt(n))
      plus ``REFINE_TOLERANCE`` of the width, the point moves to the median
      (``autogeometry.refined_geometry``: the horizon, hood, scale and look-ahead are kept). The
      next move takes twice as many points (and the median off the new point by as much): the
      checks, half a second apart, follow the car's weave across its lane for seconds, so the
      standard error of n of them is too small until they span several weaves; doubling the
      evidence each time keeps the point from going back and forth and leaves at most a few
      moves in a video (10, 20, 40, ... points).

    A watch pickles without its ``finder`` (its undistortion maps and hood mask, megabytes),
    which the copy builds again on first use: a Dask segment ships it back to the driver.
    """

    def __init__(self, geo: RoadGeometry, calibration: Calibration | None, options: GeometryOptions,
                 fps: float):
        self.geometry = geo
        self.calibration = calibration
        self.options = options
        self.every = max(1, round(options.check_every_s * fps))
        self._finder: RoadLineFinder | None = None  # built on first use (``finder``)
        self.tolerance_px = max(DRIFT_PX, 0.01 * geo.size_px[1])
        self.refine_tolerance_px = REFINE_TOLERANCE * geo.size_px[0]
        self.refine_min = max(REFINE_MIN_CHECKS, len(geo.frames_used))  # points the next refinement takes
        self.off: deque[np.ndarray] = deque(maxlen=options.drift_checks)
        self.shifts: list[float] = []
        self.points: deque[tuple[float, float]] = deque(maxlen=REFINE_MAX_CHECKS)
        # a record of the straight checks (index, time, point) and the last frame the geometry
        # changed at: a Dask joint carries the evidence through a segment by them (``carried_through``)
        self.record: deque[tuple[int, float, float, float]] = deque(maxlen=REFINE_MAX_CHECKS)
        self.recorded = 0
        self.changed_at = -1
        self.notes: list[str] = []

    @property
    def finder(self) -> RoadLineFinder:
        """The frames' vanishing-point finder, built on first use: for the geometry's frame size
        and hood row (a new estimate keeps both: the hood is the car's) and the calibration."""
        if self._finder is None:
            self._finder = RoadLineFinder(self.geometry.size_px, lens=self.calibration,
                                                   hood_top_px=self.geometry.hood_row_px)
        return self._finder

    def __getstate__(self) -> dict:
        return self.__dict__ | {"_finder": None}

    def state_key(self) -> bytes:
        """Return a fingerprint of what the next checks depend on: the geometry in use, the
        horizon shifts of the checks off it in a row (their frames are those checks') and the
        straight checks' points kept for the refinement."""
        return hashlib.sha256(pickle.dumps((self.geometry, self.shifts, tuple(self.points),
                                            self.refine_min))).digest()

    def core_key(self) -> bytes:
        """Return a fingerprint of what the frames' results depend on until the geometry changes:
        the geometry in use and the horizon shifts of the checks off it in a row."""
        return hashlib.sha256(pickle.dumps((self.geometry, self.shifts))).digest()

    def carried_through(self, other: GeometryWatch, start: int) -> GeometryWatch | None:
        """Return this watch (the state before frame ``start``) carried through the straight
        checks ``other`` made from ``start`` on, or None when they would have changed the
        geometry, or called for a new estimate, or ``other`` no longer holds them all.

        A Dask segment starts with a fresh watch; when its geometry and run of checks off the
        horizon at ``start`` are this watch's (``core_key``) and it changed nothing from there,
        its frames are those this watch would have given too unless this watch's evidence
        (the points a refinement rests on) would have changed the geometry on the way.
        """
        if other.changed_at >= start:
            return None
        checks = [c for c in other.record if c[0] >= start]
        if other.recorded > len(other.record) and (not other.record or other.record[0][0] >= start):
            return None  # the record lost some of them
        got = self.replayed(checks)
        if got is None or got[1]:
            return None
        copy = got[0]
        copy.off = deque(other.off, maxlen=other.off.maxlen)  # the frames of the same checks
        copy.notes = []
        return copy

    def replayed(self, checks: Sequence[tuple[int, float, float, float]]) -> tuple[GeometryWatch, list[int]] | None:
        """Return a copy of this watch carried through straight checks ``(index, time_s, x, y)``
        (a ``record``) as ``check`` would have gone through them, and the frames at which it
        changed the geometry on the way; None where a new estimate was due (it takes frames).

        A check's point does not depend on the geometry in use (``finder``: the frame size, the
        lens and the hood row, which a refined or new estimate keeps), nor which frames are
        checked (every ``every``-th): any run's record of a frame's check is every run's. The
        copy's ``off`` holds None for the frames of checks off the horizon in a row.
        """
        copy = pickle.loads(pickle.dumps(self))
        changed = []
        for index, time_s, x, y in checks:
            copy.record.append((index, time_s, x, y))
            copy.recorded += 1
            try:
                if copy._step((x, y), None, index, time_s) is not None:
                    copy.changed_at = index
                    changed.append(index)
            except _NeedsFrames:
                return None
        return copy, changed

    def check(self, frame: np.ndarray, index: int, time_s: float) -> RoadGeometry | None:
        if index % self.every:
            return None
        vp = self.finder.vanishing_point(frame)
        if not vp.ok:
            return None  # a bend, a frame without lines: says nothing about the horizon
        point = (float(vp.point_px[0]), float(vp.point_px[1]))
        self.record.append((index, time_s) + point)
        self.recorded += 1
        new = self._step(point, frame, index, time_s)
        if new is not None:
            self.changed_at = index
        return new

    def _step(self, point: tuple[float, float], frame: np.ndarray | None, index: int,
              time_s: float) -> RoadGeometry | None:
        """Return the new geometry after a straight check's point, or None (``check``); without
        its ``frame`` (``carried_through``), raise ``_NeedsFrames`` where a new estimate is due."""
        shift = self.geometry.horizon_shift_px(point)
        if abs(shift) <= self.tolerance_px:
            self.off.clear()
            self.shifts.clear()
            self.points.append(point)
            return self._refine(index, time_s)
        self.off.append(frame)
        self.shifts.append(shift)
        if len(self.off) < self.options.drift_checks:
            return None
        if frame is None:
            raise _NeedsFrames
        where = (f"frame {index} ({time_s:.2f} s): the vanishing point lay "
                 f"{abs(float(np.median(self.shifts))):.1f} px {'below' if np.median(self.shifts) > 0 else 'above'} "
                 f"the horizon in {len(self.off)} checks in a row")
        frames = list(self.off)
        self.off.clear()
        self.shifts.clear()
        try:  # the hood is the car's: it stays where it was
            new = self.options.estimate(frames, self.calibration, self.geometry.hood_row_px)
        except GeometryError as e:
            self.notes.append(f"{where}; a new estimate failed ({e}); the geometry is kept")
            return None
        if new.low_confidence and not self.options.accept_low_confidence:
            self.notes.append(f"{where}; the new estimate has confidence {new.confidence:.2f}, "
                              "below the limit; the geometry is kept")
            return None
        self.notes.append(f"{where}; geometry estimated again: horizon row "
                          f"{self.geometry.horizon_row_px:.1f} -> {new.horizon_row_px:.1f} px, "
                          f"{new.ym_per_px:.4f} m/px along (was {self.geometry.ym_per_px:.4f})")
        self.geometry = new
        self.points.clear()  # points about the old horizon (a knocked camera turned too)
        self.refine_min = max(REFINE_MIN_CHECKS, len(new.frames_used))
        return new

    def _refine(self, index: int, time_s: float) -> RoadGeometry | None:
        """Return the geometry with its vanishing point moved to the straight checks' median
        along the horizon when they place it off the point in use (class docstring), else None."""
        n = len(self.points)
        if n < self.refine_min:
            return None
        geo = self.geometry
        r = math.radians(geo.roll_deg)
        d = np.asarray(self.points) - np.asarray(geo.vanishing_point_px)
        along = d[:, 0] * math.cos(r) - d[:, 1] * math.sin(r)
        median = float(np.median(along))
        error = 1.2533 * 1.4826 * float(np.median(np.abs(along - median))) / math.sqrt(n)
        if abs(median) <= error + self.refine_tolerance_px:
            return None
        where = (f"frame {index} ({time_s:.2f} s): the {n} straight checks so far place the vanishing point "
                 f"{abs(median):.1f} px {'right' if median > 0 else 'left'} of the one in use along the horizon "
                 f"(median; standard error {error:.1f} px, tolerance {self.refine_tolerance_px:.1f} px)")
        try:
            new = refined_geometry(geo, median, f"vanishing point refined by {median:+.1f} px along the "
                                                         f"horizon from {n} straight checks through the video")
        except GeometryError as e:
            self.notes.append(f"{where}; not refined: {e}")
            self.refine_min = 2 * n  # tried again on twice the evidence, not at every check
            return None
        yaw = ("" if geo.yaw_deg is None else f", yaw {geo.yaw_deg:+.2f} -> {new.yaw_deg:+.2f} deg")
        (x0, y0), (x1, y1) = geo.vanishing_point_px, new.vanishing_point_px
        self.notes.append(f"{where}; refined: vanishing point ({x0:.1f}, {y0:.1f}) -> ({x1:.1f}, {y1:.1f}) px{yaw}")
        self.geometry = new
        self.refine_min = 2 * n
        return new
