"""The scenery the renderer paints around the road surface: the sky, the skyline, overpasses,
roadside barriers, and the low sun's veiling glare and wet sheen.

Each painter is a function of the scene's ``Look``, the camera grid and the frame's pose or
heading, so ``render.Renderer`` keeps only the road's mapping and shading and calls these for the
rest of the frame. Their edges are anti-aliased like the road's: box-filtered over the pixel's
footprint (``grid._box``).
"""
from __future__ import annotations

import numpy as np

from .grid import FAR_M, Z_MAX_M, Z_STEP_M, GroundGrid, _box, _lookup
from .road import CarPose
from .scene import Barrier, Look
from .textures import SKYLINE_STEP_DEG

GLARE_WIDTHS_DEG = (2.5, 12.0)   # veiling glare: core and halo fall-off angles
SHEEN_WIDTHS_DEG = (4.0, 15.0)   # wet sheen: around the sun's mirror image on the road


def sun_direction(look: Look, heading_rad: float) -> np.ndarray:
    """Return the unit direction to the sun in the car frame (x right, y down, z ahead)."""
    az = np.radians(look.sun_azimuth_deg) - heading_rad
    el = np.radians(look.sun_elevation_deg)
    return np.array([np.cos(el) * np.sin(az), -np.sin(el), np.cos(el) * np.cos(az)], np.float32)


def plain_sky(look: Look, grid: GroundGrid) -> np.ndarray:
    """Return the plain sky (sky_rows x W x 3, float32): a gradient from the horizon up."""
    f = np.clip(grid.elevation_deg / 25.0, 0.0, 1.0)[..., None] ** 0.6
    return (np.asarray(look.sky_horizon_rgb, np.float32) * (1 - f)
            + np.asarray(look.sky_top_rgb, np.float32) * f).astype(np.float32)


def paint_skyline(sky: np.ndarray, look: Look, grid: GroundGrid, tops_deg: np.ndarray,
                  heading_rad: float) -> None:
    """Draw the distant hills and the tree line into ``sky`` (in place) for the car's heading.

    ``tops_deg`` is the (N + 1, 2) table of the hills' and the trees' elevation every
    SKYLINE_STEP_DEG of azimuth, its last row a copy of its first (it wraps around).
    """
    r0, r1 = grid.skyline_rows
    el = grid.elevation_deg[r0:r1]
    n = len(tops_deg) - 1
    az = (grid.azimuth_deg[r0:r1] + float(np.degrees(heading_rad))) * (1.0 / SKYLINE_STEP_DEG)
    tops = _lookup(tops_deg, az - np.floor(az * (1.0 / n)) * n)
    px_deg = float(np.degrees(1.0 / grid.camera.K[1, 1]))
    for k, (rgb, haze) in enumerate(((look.hills_rgb, 0.45), (look.trees_rgb, 0.2))):
        cover = np.clip((tops[..., k] - el) * (1.0 / px_deg) + 0.5, 0.0, 1.0)[..., None]
        colour = np.asarray(rgb, np.float32) * (1 - haze) + np.asarray(look.haze_rgb, np.float32) * haze
        sky[r0:r1] += (colour - sky[r0:r1]) * cover


def paint_bridges(sky: np.ndarray, look: Look, grid: GroundGrid, pose: CarPose) -> None:
    """Draw the overpasses ahead of (or above) the car into ``sky`` in place, anti-aliased.

    A bridge is a deck (its underside ``height_m`` above the road, ``length_m`` deep) with a
    1.6 m high front face, square to the car's axis ``s_m - pose.s_m`` ahead.
    """
    cam = grid.camera
    ry, rz = grid.rays[..., 1], grid.rays[..., 2]
    for bridge in look.bridges:
        z0 = bridge.s_m - pose.s_m
        z1 = z0 + bridge.length_m
        if z1 < 0 or z0 > Z_MAX_M:
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            deck_z = np.where(ry < 0, (cam.height_m - bridge.height_m) / ry * rz, -1e6)
            surfaces = [(deck_z, z0, z1, (60.0, 60.0, 62.0))]
            if z0 > 0:
                face_h = np.where(rz > 0, cam.height_m - z0 / rz * ry, -1e6)
                surfaces.append((face_h, bridge.height_m, bridge.height_m + 1.6, (150.0, 148.0, 142.0)))
        for values, lo, hi, rgb in surfaces:
            values = values.astype(np.float32)
            w = np.abs(np.gradient(values, axis=0)) + np.abs(np.gradient(values, axis=1))
            w = np.clip(w, 1e-4, 1e3)
            cover = _box(values + w / 2, values - w / 2, 1.0 / w, lo, hi)[..., None]
            sky += (np.asarray(rgb, np.float32) - sky) * cover


def barrier_faces(barriers: tuple[Barrier, ...], t_m: np.ndarray, s_m: np.ndarray, centre: np.ndarray,
                  pose: CarPose, grid: GroundGrid,
                  above: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Return the barriers' coverage and their faces' grey under full light (band, float32).

    ``t_m`` and ``s_m`` are the band's road coordinates (``render.RoadCoords``), ``centre`` the
    centre line every Z_STEP_M ahead (x, s, sin, cos, curvature), ``above`` the road's height
    H(z) on the same steps (``Renderer.heights_ahead``; None on a flat road).

    A pixel's ray runs over the ground from the car to its road point (x, z), at offset t; it
    crosses the face at t_b after the share f of its run where the offset of (f x, f z) is t_b
    (three secant steps from the straight-road share (t_car - t_b) / (t_car - t)), at the
    height h_cam (1 - f) + f H(z) - H(f z) above the road there. Only rays whose end lies beyond
    the face are tested, so a face never covers the road on the car's side of it.
    """
    t_car, h_cam = pose.offset_m, grid.camera.height_m
    z_grid = np.arange(len(centre)) * Z_STEP_M
    x_c, cos_c = centre[:, 0], centre[:, 3]

    def offset(f: np.ndarray) -> np.ndarray:
        z = f * grid.z_m
        return (f * grid.x_m - np.interp(z, z_grid, x_c)) * np.interp(z, z_grid, cos_c)

    cover = np.zeros_like(t_m)
    grey = np.zeros_like(t_m)
    for b in barriers:
        side = t_car - b.t_m
        beyond = ((t_m - b.t_m) * side < 0) & (np.abs(t_m) < FAR_M / 2)
        f0, g0 = np.zeros_like(t_m), np.full_like(t_m, side)
        f1, g1 = np.ones_like(t_m), np.where(beyond, t_m - b.t_m, -side)
        for _ in range(3):
            with np.errstate(divide="ignore", invalid="ignore"):
                f2 = np.clip(f1 - g1 * (f1 - f0) / (g1 - g0), 0.0, 1.0)
            f2 = np.where(np.isfinite(f2), f2, f1)
            f0, g0, f1, g1 = f1, g1, f2, offset(f2) - b.t_m
        f = np.where(beyond, f1, 2.0)
        height = h_cam * (1.0 - f)
        if above is not None:
            height += f * np.interp(grid.z_m, z_grid, above) - np.interp(f * grid.z_m, z_grid, above)
        height = height.astype(np.float32)
        s_cross = pose.s_m + f * s_m
        inside = ((s_cross >= b.s_from_m) & (s_cross <= b.s_to_m)).astype(np.float32)
        w = np.clip(np.abs(np.gradient(height, axis=0)) + np.abs(np.gradient(height, axis=1)), 1e-4, 10.0)
        a, lo = height + w / 2, height - w / 2
        face = _box(a, lo, 1.0 / w, b.bottom_m, b.height_m) * inside
        top = _box(a, lo, 1.0 / w, b.height_m - b.top_m, b.height_m) * inside
        grey += (b.grey * (face - top) + b.top_grey * top) * (1.0 - cover)
        cover += face * (1.0 - cover)
    return cover, grey


def sheen(look: Look, band_rays: np.ndarray, heading_rad: float) -> np.ndarray:
    """Return the wet road's specular sheen (grey levels, band): the sun's blurred mirror image.

    ``band_rays`` are the unit rays of the ground band's pixels (car frame).
    """
    sun = sun_direction(look, heading_rad) * np.array([1.0, -1.0, 1.0], np.float32)
    angle = np.degrees(np.arccos(np.clip(band_rays @ sun, -1.0, 1.0)))
    core, halo = SHEEN_WIDTHS_DEG
    return look.wet * (np.exp(-angle / core) + 0.35 * np.exp(-angle / halo))


def glare(look: Look, unit_rays: np.ndarray, heading_rad: float) -> np.ndarray:
    """Return the veiling glare (grey levels, whole frame): a core and a halo round the sun,
    the sun's disc (0.5 deg) and a tenth of it everywhere (the lens's stray light)."""
    angle = np.degrees(np.arccos(np.clip(unit_rays @ sun_direction(look, heading_rad), -1.0, 1.0)))
    core, halo = GLARE_WIDTHS_DEG
    veil = 0.7 * np.exp(-angle / core) + 0.2 * np.exp(-angle / halo) + 0.1 + 4.0 * (angle < 0.5)
    return (look.glare * veil).astype(np.float32)
