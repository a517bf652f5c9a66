"""Procedural maps of a scene: the road-surface map, the asphalt grain, profiles along the road
and the skyline. All are drawn once per scene from its seed; the renderer only samples them.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .road import SAMPLE_STEP_M
from .scene import Scene

MAP_TEXEL_M = 0.06      # road-surface map resolution
MAP_MARGIN_M = 8.0      # map extent beyond the paved edges
GRAIN_TEXEL_M = 0.015   # fine asphalt grain resolution
GRAIN_TILE_PX = 256
MIP_LEVELS = 5
SKYLINE_STEP_DEG = 0.25

# Channels of the road-surface map (uint8): surface tone (128 = 1), light (255 = sun), paint (255 = intact).
TONE, LIGHT, PAINT = 0, 1, 2
# Channels of the first profile table along s: streak offsets t (m), 4 streaks at most.
MAX_STREAKS = 4
NO_STREAK_M = 1e3
# Channels of the second profile table along s.
CONCRETE, DIRECT, AMBIENT = 0, 1, 2


@dataclass(frozen=True)
class Mipmap:
    """An image and its successive halvings (box-filtered), with the metric size of a level-0 texel."""

    levels: tuple[np.ndarray, ...]
    texel_m: float

    @staticmethod
    def build(image: np.ndarray, texel_m: float, n_levels: int = MIP_LEVELS) -> "Mipmap":
        """Return the mipmap of ``image`` with ``n_levels`` levels (level 0 is ``image``)."""
        levels = [image]
        for _ in range(n_levels - 1):
            h, w = levels[-1].shape[:2]
            levels.append(cv2.resize(levels[-1], (max(1, w // 2), max(1, h // 2)),
                                     interpolation=cv2.INTER_AREA))
        return Mipmap(tuple(levels), texel_m)


@dataclass(frozen=True)
class SurfaceMap:
    """The road-surface map over the scene: rows along s from ``s0_m``, columns across t from ``t0_m``."""

    mip: Mipmap
    s0_m: float
    t0_m: float


def _smooth_noise(rng: np.random.Generator, shape: tuple[int, int], sigma_px: float) -> np.ndarray:
    """Return Gaussian-blurred white noise of ``shape`` scaled to unit standard deviation."""
    n = rng.standard_normal(shape).astype(np.float32)
    n = cv2.GaussianBlur(n, (0, 0), sigma_px, borderType=cv2.BORDER_REFLECT)
    return n / max(float(n.std()), 1e-6)


def _wander(rng: np.random.Generator, s_m: np.ndarray) -> np.ndarray:
    """Return a smooth unit-amplitude sideways wandering along ``s_m`` (wavelengths 2.5 to 40 m)."""
    out = np.zeros_like(s_m)
    for wavelength, amp in ((40.0, 0.5), (13.0, 0.3), (5.0, 0.15), (2.5, 0.05)):
        out += amp * np.sin(2 * np.pi * s_m / wavelength + rng.uniform(0, 2 * np.pi))
    return out


def _ramp(s_m: np.ndarray, s_from: float, s_to: float, ramp_m: float) -> np.ndarray:
    """Return 1 inside [s_from, s_to] and 0 outside, with linear ramps ``ramp_m`` long."""
    return np.clip(np.minimum(s_m - s_from, s_to - s_m) / ramp_m + 0.5, 0.0, 1.0)


def _draw_patches(tone: np.ndarray, rng: np.random.Generator, scene: Scene, s_rows: np.ndarray,
                  t_cols: np.ndarray) -> None:
    """Multiply repair patches and resurfaced strips into the ``tone`` map in place."""
    look, (left, right) = scene.look, scene.layout.paved_m
    n = rng.poisson(look.patches_per_100m * (scene.s_to_m - scene.s_from_m) / 100.0)
    starts = zip(rng.uniform(scene.s_from_m, scene.s_to_m, n), rng.uniform(left, right - 1.0, n))
    patches = [(s, s + rng.uniform(1.5, 12.0), t, t + rng.uniform(0.8, 3.5), rng.uniform(0.72, 1.22))
               for s, t in starts]
    for s0, s1, t0, t1, factor in list(look.resurfaced) + patches:
        rows = slice(*np.searchsorted(s_rows, (s0, s1)))
        cols = slice(*np.searchsorted(t_cols, (t0, t1)))
        tone[rows, cols] *= factor


def _draw_tree_shadows(light: np.ndarray, rng: np.random.Generator, scene: Scene, s0_m: float,
                       t0_m: float) -> None:
    """Draw the shadows of roadside trees (sun from the left) into the ``light`` map in place.

    Each tree's crown shadow is a cluster of leafy ellipses with gaps, joined to the tree's foot
    beside the road by its trunk's shadow; ``s0_m``, ``t0_m`` locate the map's first texel.
    """
    look, (left, right) = scene.look, scene.layout.paved_m
    n = rng.poisson(look.tree_shadows_per_100m * (scene.s_to_m - scene.s_from_m) / 100.0)
    occl = np.zeros(light.shape, np.float32)
    px = 1.0 / MAP_TEXEL_M

    def texel(s_m: float, t_m: float) -> tuple[int, int]:
        return int((t_m - t0_m) * px), int((s_m - s0_m) * px)

    for s in rng.uniform(scene.s_from_m, scene.s_to_m, n):
        foot_t = left - rng.uniform(1.0, 5.0) if rng.random() < 0.7 else right + rng.uniform(0.5, 3.0)
        crown_t = foot_t + rng.uniform(3.0, 8.0)
        size_t, size_s = rng.uniform(2.5, 5.0), rng.uniform(1.8, 3.5)
        cv2.line(occl, texel(s, foot_t), texel(s + rng.uniform(-1, 1), crown_t), 1.0, max(1, int(0.35 * px)))
        for _ in range(40):
            dt, ds = rng.normal(0, 0.45, 2)
            axes = (int(rng.uniform(0.3, 1.2) * size_t * px / 2),
                    int(rng.uniform(0.3, 1.2) * size_s * px / 2))
            cv2.ellipse(occl, texel(s + ds * size_s, crown_t + dt * size_t), axes, rng.uniform(0, 180),
                        0, 360, 1.0, -1)
        for _ in range(25):  # gaps between the leaves
            dt, ds = rng.normal(0, 0.4, 2)
            radius = int(rng.uniform(0.1, 0.35) * px)
            cv2.circle(occl, texel(s + ds * size_s, crown_t + dt * size_t), radius, 0.0, -1)
    light *= 1.0 - cv2.GaussianBlur(occl, (0, 0), 1.5)


def surface_map(scene: Scene, rng: np.random.Generator) -> SurfaceMap:
    """Return the road-surface map of ``scene``: tone blotches and patches, tree shadows, paint wear."""
    look, (left, right) = scene.look, scene.layout.paved_m
    s_rows = np.arange(scene.s_from_m, scene.s_to_m, MAP_TEXEL_M)
    t_cols = np.arange(left - MAP_MARGIN_M, right + MAP_MARGIN_M, MAP_TEXEL_M)
    shape = (len(s_rows), len(t_cols))
    tone = 1.0 + look.asphalt_blotches * (0.7 * _smooth_noise(rng, shape, 12.0)
                                          + 0.3 * _smooth_noise(rng, shape, 2.0))
    tone *= (1.0 + 0.04 * _wander(rng, s_rows / 3.0))[:, None].astype(np.float32)
    lane_centres = [i * scene.layout.lane_width_m for i in range(scene.layout.right_lanes + 1)]
    for c in lane_centres:  # oil drip band down the middle of every lane
        tone *= 1.0 - 0.06 * np.exp(-((t_cols - c) / 0.35) ** 2)[None, :]
    _draw_patches(tone, rng, scene, s_rows, t_cols)
    light = np.ones(shape, np.float32)
    _draw_tree_shadows(light, rng, scene, float(s_rows[0]), float(t_cols[0]))
    wear = _smooth_noise(rng, shape, 2.5) + 0.8 * _smooth_noise(rng, shape, 25.0)
    paint = np.clip(1.0 - look.paint_wear * (1.0 + 0.9 * wear), 0.0, 1.0)
    for s0, s1, t0, t1 in look.paint_missing_m:   # stretches where the paint is gone
        paint[slice(*np.searchsorted(s_rows, (s0, s1))), slice(*np.searchsorted(t_cols, (t0, t1)))] = 0.0
    maps = np.stack([np.clip(tone * 128.0, 0, 255), light * 255.0, paint * 255.0], axis=-1)
    image = np.round(maps).astype(np.uint8)
    return SurfaceMap(Mipmap.build(image, MAP_TEXEL_M), float(s_rows[0]), float(t_cols[0]))


def grain(rng: np.random.Generator) -> Mipmap:
    """Return the mipmap of a periodic tile of fine asphalt grain (zero mean, unit std at level 0)."""
    n = rng.standard_normal((GRAIN_TILE_PX, GRAIN_TILE_PX)).astype(np.float32)
    tiled = cv2.GaussianBlur(np.tile(n, (3, 3)), (0, 0), 0.7)  # blur with wrap-around
    n = tiled[GRAIN_TILE_PX:2 * GRAIN_TILE_PX, GRAIN_TILE_PX:2 * GRAIN_TILE_PX]
    return Mipmap.build(n / float(n.std()), GRAIN_TEXEL_M)


def streak_table(scene: Scene, s_m: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Return (N, 4) float32 offsets t (m) of the streaks at arc lengths ``s_m``; far away where absent."""
    table = np.full((len(s_m), MAX_STREAKS), NO_STREAK_M, np.float32)
    for k, st in enumerate(scene.look.streaks[:MAX_STREAKS]):
        t = st.t_m + st.wander_m * _wander(rng, s_m)
        inside = (s_m >= st.s_from_m) & (s_m <= st.s_to_m)
        table[inside, k] = t[inside]
    return table


def light_table(scene: Scene, s_m: np.ndarray) -> np.ndarray:
    """Return (N, 3) float32 profiles along ``s_m``: concrete share, direct light, ambient light."""
    look = scene.look
    concrete = np.zeros_like(s_m)
    for s0, s1 in look.concrete_m:
        concrete = np.maximum(concrete, _ramp(s_m, s0, s1, SAMPLE_STEP_M))
    direct = np.ones_like(s_m)
    for s0, s1, factor in look.light_m:
        direct *= 1.0 - (1.0 - factor) * _ramp(s_m, s0, s1, 10.0)
    ambient = np.ones_like(s_m)
    for b in look.bridges:  # sun from behind-left: the shadow lies 2 m short of the deck
        direct *= 1.0 - _ramp(s_m, b.s_m - 2.0, b.s_m + b.length_m - 2.0, 1.0)
        ambient *= 1.0 - 0.7 * _ramp(s_m, b.s_m + 2.0, b.s_m + b.length_m - 2.0, 6.0)
    return np.column_stack([concrete, direct, ambient]).astype(np.float32)


def skyline(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Return (hills, trees): elevation (deg) of each skyline at azimuths 0, 0.25, ... 359.75 deg."""
    az = np.arange(0.0, 360.0, SKYLINE_STEP_DEG)
    rad = np.radians(az)
    hills = 1.6 + sum(a * np.sin(k * rad + rng.uniform(0, 2 * np.pi))
                      for k, a in ((1, 0.8), (3, 0.6), (7, 0.35), (17, 0.15)))
    crowns = np.zeros_like(az)
    for centre in rng.uniform(0, 360, 160):
        width, height = rng.uniform(0.8, 4.0), rng.uniform(0.6, 2.6)
        d = np.abs((az - centre + 180.0) % 360.0 - 180.0)
        crowns = np.maximum(crowns, height * np.sqrt(np.clip(1 - (d / width) ** 2, 0, 1)))
    return np.maximum(hills, 0.3).astype(np.float32), crowns.astype(np.float32)


def hood_profile(size_px: tuple[int, int]) -> np.ndarray:
    """Return the hood's top edge (row, px) at every image column: 26 px high in the middle."""
    w, h = size_px
    x = (np.arange(w) - w / 2) / (w / 2)
    return (h - 26.0 + 26.0 * x ** 2).astype(np.float32)

