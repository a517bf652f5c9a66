"""The camera's ground grid: what the road renderer needs of the camera alone, computed once.

``GroundGrid.build`` finds the road point (x, z) under every pixel of the raw, distorted image on
a flat road, the pixel's footprint on the road (the Jacobian of (x, z) over (column, row)), the
horizon coverage, the mipmap level of each run of rows, the sky directions, the hood and the
lens falloff. It is about a second of work that depends on nothing of the scene, so one grid
serves every frame and every scene through the same camera. ``_box`` and ``_dash_integral`` are
the box filters over a footprint with which the renderer anti-aliases lines, dashes and edges;
``_lookup`` interpolates a table at fractional rows (the centre line, the skyline).
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .camera import Camera
from .textures import GRAIN_TEXEL_M, MAP_TEXEL_M, MIP_LEVELS, hood_profile

Z_MAX_M = 200.0         # farthest road distance shaded in detail; beyond it only haze
Z_STEP_M = 0.05
MAX_FOOTPRINT_M = 50.0
FAR_M = 1e3             # lateral offset given to road points off the tabulated road
SKYLINE_BAND_DEG = (-1.0, 7.0)
HOOD_HEIGHT_REF_PX = 720  # image height at which the hood is textures.hood_profile's 26 px


def _box(a: np.ndarray, b: np.ndarray, inv_w: np.ndarray, lo, hi) -> np.ndarray:
    """Return the share of the footprint [b, a] (width 1/inv_w) that lies in [lo, hi]."""
    return (np.clip(a, lo, hi) - np.clip(b, lo, hi)) * inv_w


def _dash_integral(s: np.ndarray, period_m: float, dash_m: float) -> np.ndarray:
    """Return the painted length of a dash pattern (dashes start at multiples of the period) up to s."""
    n = np.floor(s * (1.0 / period_m))
    return n * dash_m + np.minimum(s - n * period_m, dash_m)


def _lookup(table: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Return rows of ``table`` (N, C) linearly interpolated at fractional ``index`` (clamped), (B, W, C)."""
    n = table.shape[0]
    src = np.ascontiguousarray(np.broadcast_to(table.astype(np.float32)[None], (2,) + table.shape))
    index = np.clip(index, 0, n - 1).astype(np.float32, copy=False)
    return cv2.remap(src, index, np.zeros_like(index), cv2.INTER_LINEAR)


@dataclass(frozen=True)
class GroundGrid:
    """Camera-only precomputation for rendering: rows ``row0:`` see the road, rows ``:sky_rows`` the sky."""

    camera: Camera
    row0: int
    x_m: np.ndarray          # (B, W) float32 road point under each pixel of the ground band
    z_m: np.ndarray
    distance_m: np.ndarray   # (B, W) distance ahead, not clamped (for the haze)
    jacobian: np.ndarray     # (4, B, W) dx/du, dx/dv, dz/du, dz/dv (m per px)
    ground: np.ndarray       # (B, W) share of each pixel below the horizon
    z_index: np.ndarray      # (B, W) z / Z_STEP_M
    bands: tuple[tuple[int, int, int, int], ...]  # (row from, row to, map level, grain level)
    sky_rows: int
    elevation_deg: np.ndarray  # (sky_rows, W)
    azimuth_deg: np.ndarray    # (sky_rows, W), from the car's forward axis, positive right
    rays: np.ndarray           # (sky_rows, W, 3) car-frame ray directions
    skyline_rows: tuple[int, int]
    hood_top: np.ndarray       # (W,) row of the hood's edge in every column
    hood_row0: int             # first row the hood reaches
    hood_alpha: np.ndarray     # (R, W, 1) hood coverage of the rows from hood_row0
    hood_shade: np.ndarray     # (R, 1, 1) hood brightness (darker towards the bottom)
    vignette: np.ndarray       # (H, W) float32

    @staticmethod
    def build(camera: Camera = Camera()) -> "GroundGrid":
        """Return the grid of ``camera`` (about a second of work)."""
        w, h = camera.size_px
        u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        rays = camera.rays(np.column_stack([u.ravel(), v.ravel()])).reshape(h, w, 3)
        horiz = np.hypot(rays[..., 0], rays[..., 2])
        elevation = -np.degrees(np.arctan2(rays[..., 1], horiz))
        below = rays[..., 1] > 0
        row0 = int(np.argmax(below.any(axis=1)))
        sky_rows = int(h - np.argmax((~below).any(axis=1)[::-1]))
        r = rays[row0:]
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = np.where(r[..., 1] > 0, camera.height_m / r[..., 1], np.inf)
        distance = np.minimum(lam * r[..., 2], 1e5)
        scale = np.minimum(lam, Z_MAX_M / r[..., 2])
        x, z = scale * r[..., 0], scale * r[..., 2]
        jac = np.stack([np.gradient(x, axis=1), np.gradient(x, axis=0),
                        np.gradient(z, axis=1), np.gradient(z, axis=0)])
        jac = np.clip(np.nan_to_num(jac), -MAX_FOOTPRINT_M, MAX_FOOTPRINT_M)
        elev_step = np.abs(np.gradient(elevation, axis=0))[row0:]
        ground = np.clip(0.5 - elevation[row0:] / np.maximum(elev_step, 1e-6), 0.0, 1.0)
        footprint = np.maximum(np.abs(jac[:2]).sum(axis=0), np.abs(jac[2:]).sum(axis=0))
        sky_el = elevation[:sky_rows]
        in_band = (sky_el > SKYLINE_BAND_DEG[0]) & (sky_el < SKYLINE_BAND_DEG[1])
        sky_band = np.flatnonzero(in_band.any(axis=1))
        return GroundGrid(
            camera=camera, row0=row0,
            x_m=x.astype(np.float32), z_m=z.astype(np.float32),
            distance_m=distance.astype(np.float32), jacobian=jac.astype(np.float32),
            ground=ground.astype(np.float32), z_index=(z / Z_STEP_M).astype(np.float32),
            bands=_mip_bands(np.median(footprint, axis=1)),
            sky_rows=sky_rows, elevation_deg=sky_el.astype(np.float32),
            azimuth_deg=np.degrees(np.arctan2(rays[:sky_rows, :, 0], rays[:sky_rows, :, 2])).astype(
                np.float32),
            rays=rays[:sky_rows].astype(np.float32),
            skyline_rows=(int(sky_band[0]), int(sky_band[-1]) + 1),
            **_hood(camera.size_px),
            vignette=_vignette(camera).astype(np.float32))


def _mip_bands(footprint_m: np.ndarray) -> tuple[tuple[int, int, int, int], ...]:
    """Return runs of band rows (from, to, map level, grain level) for per-row footprints (m)."""
    def level(texel_m: float) -> np.ndarray:
        ratio = np.maximum(footprint_m / texel_m, 1.0)
        return np.clip(np.floor(np.log2(ratio)), 0, MIP_LEVELS - 1).astype(int)

    # The footprint only grows towards the horizon; rows above the clamped far field keep the
    # level of the rows below them.
    far_first = lambda lv: np.maximum.accumulate(lv[::-1])[::-1]  # noqa: E731
    key = far_first(level(MAP_TEXEL_M)) * MIP_LEVELS + far_first(level(GRAIN_TEXEL_M))
    edges = np.flatnonzero(np.diff(key)) + 1
    starts = np.concatenate([[0], edges])
    ends = np.concatenate([edges, [len(key)]])
    return tuple((int(a), int(b), int(key[a] // MIP_LEVELS), int(key[a] % MIP_LEVELS))
                 for a, b in zip(starts, ends))


def _hood(size_px: tuple[int, int]) -> dict:
    """Return the hood's first row, coverage (anti-aliased) and shading for the grid.

    The hood is ``textures.hood_profile`` at 720 rows, and as high in proportion to the image at
    other heights.
    """
    top = hood_profile(size_px)
    if size_px[1] != HOOD_HEIGHT_REF_PX:
        h = float(size_px[1])
        top = (h - (h - top) * (h / HOOD_HEIGHT_REF_PX)).astype(np.float32)
    row0 = int(np.floor(top.min()))
    rows = np.arange(row0, size_px[1], dtype=np.float32)[:, None]
    alpha = np.clip(rows + 0.5 - top[None, :], 0.0, 1.0)[..., None]
    shade = (1.0 - 0.35 * (rows - row0) / max(size_px[1] - row0, 1))[..., None]
    return dict(hood_top=top, hood_row0=row0, hood_alpha=alpha.astype(np.float32),
                hood_shade=shade.astype(np.float32))


def _vignette(camera: Camera) -> np.ndarray:
    """Return the lens falloff (H, W): 45 % of the cos^4 law, about 28 % darker in the corners."""
    w, h = camera.size_px
    u, v = np.meshgrid(np.arange(w), np.arange(h))
    rr = ((u - camera.K[0, 2]) / camera.K[0, 0]) ** 2 + ((v - camera.K[1, 2]) / camera.K[1, 1]) ** 2
    cos4 = 1.0 / (1.0 + rr) ** 2
    return 1.0 - 0.45 * (1.0 - cos4)
