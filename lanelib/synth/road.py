"""Road geometry: a centre line from a curvature profile, and the car's pose along it.

World frame (2-D, metres): X east, Y north. Headings are measured clockwise from north, so a
positive curvature turns right. Road coordinates are (s, t): s the arc length along the lane centre
line, t the signed distance from it, positive to the right. Car-frame ground coordinates are
(x, z): x to the right of the car, z ahead of it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SAMPLE_STEP_M = 0.05  # spacing of the centre-line tables


@dataclass(frozen=True)
class CurvatureProfile:
    """A curvature profile: knots (s_m, curvature_per_m) joined linearly (clothoids between arcs).

    Two knots with the same curvature make a constant arc (or a straight at 0); two with
    different curvatures make a clothoid. Before the first knot and after the last the curvature
    stays constant.
    """

    knots: tuple[tuple[float, float], ...] = ((0.0, 0.0),)

    def curvature(self, s_m: np.ndarray) -> np.ndarray:
        """Return the curvature (1/m, positive right) at arc lengths ``s_m``."""
        s, k = np.asarray(self.knots, dtype=np.float64).T
        return np.interp(s_m, s, k)

    @staticmethod
    def from_segments(start_curvature_per_m: float,
                      segments: tuple[tuple[float, float], ...]) -> "CurvatureProfile":
        """Return a profile from (length_m, end_curvature_per_m) segments, linear within each."""
        s, k = 0.0, start_curvature_per_m
        knots = [(s, k)]
        for length, end in segments:
            s += length
            knots.append((s, end))
        return CurvatureProfile(tuple(knots))


def grade(grades: tuple[tuple[float, float], ...], s_m) -> np.ndarray:
    """Return the road's grade (rise / run) at arc lengths ``s_m`` from (s_m, grade) knots (0 if none)."""
    if not grades:
        return np.zeros_like(np.asarray(s_m, dtype=np.float64))
    s, g = np.asarray(grades, dtype=np.float64).T
    return np.interp(s_m, s, g)


def heights(grades: tuple[tuple[float, float], ...], s_m: np.ndarray) -> np.ndarray:
    """Return the road's height (m, up; 0 at s = 0) at increasing arc lengths ``s_m``: the exact
    integral of the piecewise-linear grade (trapezoids between samples, exact for linear pieces
    when every knot is a sample; the tables sample every SAMPLE_STEP_M)."""
    s = np.asarray(s_m, dtype=np.float64)
    g = grade(grades, s)
    h = np.concatenate([[0.0], np.cumsum((g[1:] + g[:-1]) / 2 * np.diff(s))])
    return h - np.interp(0.0, s, h)


@dataclass(frozen=True)
class Road:
    """The lane centre line sampled every SAMPLE_STEP_M: arc length, position, heading, curvature."""

    s_m: np.ndarray
    xy_m: np.ndarray         # (N, 2) world X, Y
    heading_rad: np.ndarray  # clockwise from north
    curvature_per_m: np.ndarray
    height_m: np.ndarray | None = None   # (N,) road height (m, up); None on a flat road

    @staticmethod
    def build(profile: CurvatureProfile, s_start_m: float, s_end_m: float,
              grades: tuple[tuple[float, float], ...] = ()) -> "Road":
        """Return the centre line between two arc lengths (m), integrated from the profile, with
        its heights from the ``grades`` knots (none: flat)."""
        s = np.arange(s_start_m, s_end_m + SAMPLE_STEP_M / 2, SAMPLE_STEP_M)
        k = profile.curvature(s)
        heading = np.concatenate([[0.0], np.cumsum((k[1:] + k[:-1]) / 2 * np.diff(s))])
        # Integrate the unit tangent with the mid-point heading of each step.
        mid = (heading[1:] + heading[:-1]) / 2
        step = np.column_stack([np.sin(mid), np.cos(mid)]) * np.diff(s)[:, None]
        xy = np.vstack([[0.0, 0.0], np.cumsum(step, axis=0)])
        return Road(s, xy, heading, k, heights(grades, s) if grades else None)

    def index(self, s_m: float) -> float:
        """Return the fractional sample index of arc length ``s_m``."""
        return (s_m - self.s_m[0]) / SAMPLE_STEP_M

    def at(self, s_m: float) -> tuple[np.ndarray, float, float]:
        """Return (position (2,), heading rad, curvature 1/m) at arc length ``s_m``."""
        xy = np.array([np.interp(s_m, self.s_m, self.xy_m[:, 0]), np.interp(s_m, self.s_m, self.xy_m[:, 1])])
        heading = float(np.interp(s_m, self.s_m, self.heading_rad))
        return xy, heading, float(np.interp(s_m, self.s_m, self.curvature_per_m))

    def offset_points(self, t_m: float, s_from_m: float, s_to_m: float) -> np.ndarray:
        """Return (N, 2) world points of the curve at lateral offset ``t_m`` between two arc lengths."""
        i0 = max(0, int(np.floor(self.index(s_from_m))))
        i1 = min(len(self.s_m), int(np.ceil(self.index(s_to_m))) + 1)
        h = self.heading_rad[i0:i1]
        normal = np.column_stack([np.cos(h), -np.sin(h)])
        return self.xy_m[i0:i1] + t_m * normal


@dataclass(frozen=True)
class CarPose:
    """Where the car is: arc length, offset from the lane centre and heading relative to the road.

    Parameters
    ----------
    s_m : arc length of the car's (camera's) foot point along the centre line.
    offset_m : lateral offset of the car from the lane centre, positive right.
    heading_rad : angle of the car's forward axis from the road direction, positive right.
    """

    s_m: float
    offset_m: float = 0.0
    heading_rad: float = 0.0


def car_frame(road: Road, pose: CarPose) -> tuple[np.ndarray, float]:
    """Return (car position (2,) in the world, car heading rad clockwise from north)."""
    xy, heading, _ = road.at(pose.s_m)
    normal = np.array([np.cos(heading), -np.sin(heading)])
    return xy + pose.offset_m * normal, heading + pose.heading_rad


def world_to_car(points_xy: np.ndarray, origin_xy: np.ndarray, heading_rad: float) -> np.ndarray:
    """Return (N, 2) car-frame ground points (x right, z ahead) of (N, 2) world points (m)."""
    d = np.asarray(points_xy, dtype=np.float64) - origin_xy
    c, s = np.cos(heading_rad), np.sin(heading_rad)
    return np.column_stack([d[:, 0] * c - d[:, 1] * s, d[:, 0] * s + d[:, 1] * c])
