"""The road-scene renderer: a textured road plane seen through the distorted camera.

Everything that depends only on the camera is computed once (``grid.GroundGrid``): the road
point (x, z) under every pixel of the raw, distorted image, the pixel's footprint on the road
(the Jacobian of (x, z) over (column, row)), the horizon coverage, the sky directions, the hood.
Everything that depends only on the scene is drawn once (``textures``). Per frame the renderer
only maps car-frame road points to road coordinates (s, t) through two table lookups along the
centre line, and shades them. Anti-aliasing is analytic: every painted line, dash, streak and
edge is box-filtered over the pixel's footprint on the road, and the maps are sampled from the
mipmap level that matches the footprint, so distant dashes fade instead of shimmering.

A scene with ``grades`` (a vertical profile) is not a plane: per frame the renderer tabulates the
road's height ahead of the car along the centre line, H(z) at every distance z ahead (car frame,
relative to the plane the car stands on: the car pitches with the road), takes the road's height
under a car-frame point (x, z) to be H(z), and finds every pixel's first hit on that surface
(crests hide what lies beyond them; a climbing road may rise above the flat horizon).
``truth`` projects the lines onto the same surface (``Renderer.heights_ahead``).
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, replace

import cv2
import numpy as np

from .grid import MAX_FOOTPRINT_M, Z_MAX_M, Z_STEP_M, GroundGrid, _box, _dash_integral, _mip_bands
from .road import CarPose, Road, car_frame, grade, world_to_car
from .scene import Line, Scene
from .textures import (AMBIENT, CONCRETE, DIRECT, GRAIN_TILE_PX, MAX_STREAKS, SKYLINE_STEP_DEG, Mipmap,
                       SurfaceMap, grain, light_table, skyline, streak_table, surface_map)

LOOK_AHEAD_M = 220.0    # centre line used ahead of the car
LOOK_BEHIND_M = 10.0    # and behind it (the bottom image corners see the road beside the car)
MAX_ROAD_ANGLE_RAD = np.radians(75.0)  # the road ahead is used until it turns this far
FAR_M = 1e3             # lateral offset given to road points off the tabulated road
CONCRETE_JOINT_M = 4.5  # transverse joints of concrete slabs
NOISE_MARGIN_PX = 16
PITCH_MARGIN_PX = 120   # rows above the flat horizon a climbing road may reach (scenes with grades)
GLARE_WIDTHS_DEG = (2.5, 12.0)   # veiling glare: core and halo fall-off angles
SHEEN_WIDTHS_DEG = (4.0, 15.0)   # wet sheen: around the sun's mirror image on the road


def _sample(mip: Mipmap, bands, band_level: int, cols: np.ndarray, rows: np.ndarray,
            wrap: bool) -> np.ndarray:
    """Return ``mip`` sampled at level-0 texel coordinates (cols, rows), each run of band rows from
    its own level; coordinates wrap around (a tile) or are clamped to the edge (a map)."""
    h, w = mip.levels[0].shape[:2]
    if wrap:
        cols = cols - np.floor(cols * (1.0 / w)) * w
        rows = rows - np.floor(rows * (1.0 / h)) * h
    else:
        cols = np.clip(cols, 0, w - 1)
        rows = np.clip(rows, 0, h - 1)
    border = cv2.BORDER_WRAP if wrap else cv2.BORDER_REPLICATE
    out = None
    for r0, r1, map_level, grain_level in bands:
        lvl = (map_level, grain_level)[band_level]
        f = 0.5 ** lvl
        c = cols[r0:r1] * f + (0.5 * f - 0.5)
        r = rows[r0:r1] * f + (0.5 * f - 0.5)
        part = cv2.remap(mip.levels[lvl], c, r, cv2.INTER_LINEAR, borderMode=border)
        if out is None:
            out = np.empty((cols.shape[0],) + part.shape[1:], part.dtype)
        out[r0:r1] = part
    return out


def _lookup(table: np.ndarray, index: np.ndarray) -> np.ndarray:
    """Return rows of ``table`` (N, C) linearly interpolated at fractional ``index`` (clamped), (B, W, C)."""
    n = table.shape[0]
    src = np.ascontiguousarray(np.broadcast_to(table.astype(np.float32)[None], (2,) + table.shape))
    index = np.clip(index, 0, n - 1).astype(np.float32, copy=False)
    return cv2.remap(src, index, np.zeros_like(index), cv2.INTER_LINEAR)


@dataclass(frozen=True)
class _PitchRays:
    """What a pitched road's per-frame grid needs from the camera: the band from ``row0`` (up to
    PITCH_MARGIN_PX above the flat grid's) with each pixel's ray slopes down (y / z) and across
    (x / z), and the flat grid's ground coverage (0 on the added rows)."""

    row0: int
    down: np.ndarray     # (B, W) ray y / z (positive below the horizon)
    across: np.ndarray   # (B, W) ray x / z
    flat_ground: np.ndarray

    @staticmethod
    def build(grid: "GroundGrid", rays: np.ndarray) -> "_PitchRays":
        """Return the pitched band of ``grid`` from the (H, W, 3) car-frame rays of every pixel."""
        row0 = max(0, grid.row0 - PITCH_MARGIN_PX)
        r = rays[row0:]
        flat = np.zeros(r.shape[:2], np.float32)
        flat[grid.row0 - row0:] = grid.ground
        return _PitchRays(row0, (r[..., 1] / r[..., 2]).astype(np.float64),
                          (r[..., 0] / r[..., 2]).astype(np.float32), flat)


@dataclass(frozen=True)
class RoadCoords:
    """Road coordinates of the ground band for one car pose: s (m, from the car), t (m), footprints (m)."""

    s_m: np.ndarray
    t_m: np.ndarray
    ws_m: np.ndarray
    wt_m: np.ndarray
    profiles: tuple[np.ndarray, ...]  # 7 x (B, W): the scene's profiles along s (streaks, light)
    centre: np.ndarray | None = None  # (Nz, 5) the centre line every Z_STEP_M ahead: x, s, sin, cos, curvature


class Renderer:
    """Render frames of one scene through one camera grid; holds only precomputed, read-only maps."""

    def __init__(self, scene: Scene, grid: GroundGrid):
        rng = np.random.default_rng(scene.seed)
        self.scene = scene
        self.grid = grid
        self.road = Road.build(scene.profile, scene.s_from_m, scene.s_to_m, scene.grades)
        self.lines: tuple[Line, ...] = scene.layout.lines()
        self.surface: SurfaceMap = surface_map(scene, rng)
        self.grain: Mipmap = grain(rng)
        self.tables = np.concatenate([streak_table(scene, self.road.s_m, rng),
                                      light_table(scene, self.road.s_m)], axis=1)
        hills, trees = skyline(rng)
        self.skyline = np.column_stack([np.append(hills, hills[0]), np.append(trees, trees[0])])
        self._noise_rng_state = rng.bit_generator.state
        self._set_grid(grid, rng)

    def _set_grid(self, grid: GroundGrid, rng: np.random.Generator) -> None:
        """Set what depends on the camera grid: the camera noise (drawn from ``rng``), haze and sky."""
        self.grid = grid
        w, h = grid.camera.size_px
        self.noise = rng.standard_normal((h + NOISE_MARGIN_PX, w + NOISE_MARGIN_PX, 3)).astype(np.float32)
        self.haze = (1.0 - np.exp(-grid.distance_m / self.scene.look.haze_m)).astype(np.float32)
        self.sky = self._sky()
        look = self.scene.look
        self.unit_rays = self.pitch = None
        if look.glare > 0 or look.wet > 0 or self.road.height_m is not None:
            u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
            rays = grid.camera.rays(np.column_stack([u.ravel(), v.ravel()])).reshape(h, w, 3)
            if look.glare > 0 or look.wet > 0:
                self.unit_rays = (rays / np.linalg.norm(rays, axis=-1, keepdims=True)).astype(np.float32)
            if self.road.height_m is not None:
                self.pitch = _PitchRays.build(grid, rays)

    def for_grid(self, grid: GroundGrid) -> "Renderer":
        """Return a renderer of the same scene through another camera grid, without drawing the
        scene's maps again: it renders exactly what ``Renderer(scene, grid)`` renders."""
        other = copy.copy(self)
        rng = np.random.default_rng()
        rng.bit_generator.state = self._noise_rng_state
        other._set_grid(grid, rng)
        return other

    # ------------------------------------------------------------------ geometry

    def _centre_ahead(self, pose: CarPose) -> tuple[float, int, int, np.ndarray]:
        """Return (car heading rad, first index, usable count, (M, 2) car-frame centre points)."""
        road = self.road
        origin, heading = car_frame(road, pose)
        i0 = int(np.floor(road.index(pose.s_m - LOOK_BEHIND_M)))
        i1 = int(np.ceil(road.index(pose.s_m + LOOK_AHEAD_M))) + 1
        if i0 < 0 or i1 > len(road.s_m):
            raise ValueError(f"car at s={pose.s_m:.1f} m needs road from {pose.s_m - LOOK_BEHIND_M:.0f} "
                             f"to {pose.s_m + LOOK_AHEAD_M:.0f} m; the scene spans "
                             f"{self.scene.s_from_m:.0f} to {self.scene.s_to_m:.0f} m")
        xz = world_to_car(road.xy_m[i0:i1], origin, heading)
        angle = road.heading_rad[i0:i1] - heading
        # Use the road ahead while it keeps coming closer and has not turned too far.
        ok = (np.abs(angle) < MAX_ROAD_ANGLE_RAD) & (np.diff(xz[:, 1], prepend=-np.inf) > 0)
        n = len(ok) if ok.all() else int(np.argmin(ok))
        return heading, i0, n, xz

    def heights_ahead(self, pose: CarPose) -> tuple[np.ndarray, np.ndarray]:
        """Return (z (m), H (m)): the road's height above the plane the car stands on at distances
        z ahead (every Z_STEP_M to Z_MAX_M), read along the centre line at that z.

        H(z) = h(s(z)) - h(s_car) - grade(s_car) z, with h the road's height and s(z) the centre
        line's arc length at distance z ahead: the car pitches with the road (a shear, the small
        angle form of its rotation). Zero everywhere on a flat road.
        """
        road = self.road
        _, i0, n, xz = self._centre_ahead(pose)
        z_grid = np.arange(int(Z_MAX_M / Z_STEP_M) + 1) * Z_STEP_M
        if road.height_m is None:
            return z_grid, np.zeros_like(z_grid)
        index = np.interp(z_grid, xz[:n, 1], np.arange(i0, i0 + n, dtype=np.float64))
        h = np.interp(index, np.arange(len(road.s_m)), road.height_m)
        h_car = float(np.interp(pose.s_m, road.s_m, road.height_m))
        return z_grid, h - h_car - float(grade(self.scene.grades, pose.s_m)) * z_grid

    def road_coords(self, pose: CarPose, grid: GroundGrid | None = None) -> tuple[RoadCoords, float]:
        """Return the ground band's road coordinates for ``pose`` and the car's world heading (rad).

        The centre line is tabulated against the distance ahead z; a road point (x, z) takes the
        centre point at its own z, steps along the tangent to its foot point, and corrects the
        offset for the curvature (second order in the step, exact to well below a millimetre for
        the lane's own lines). ``grid`` is the frame's grid (a pitched road's; default the camera's).
        """
        g, road = grid or self.grid, self.road
        heading, i0, n, xz = self._centre_ahead(pose)
        zs = xz[:n, 1]
        z_grid = np.arange(int(Z_MAX_M / Z_STEP_M) + 1) * Z_STEP_M
        index = np.interp(z_grid, zs, np.arange(i0, i0 + n, dtype=np.float64))
        at = lambda values: np.interp(index, np.arange(len(values)), values)  # noqa: E731
        columns = [np.interp(z_grid, zs, xz[:n, 0]), at(road.s_m) - pose.s_m,
                   np.sin(at(road.heading_rad) - heading), np.cos(at(road.heading_rad) - heading),
                   at(road.curvature_per_m)] + [at(col) for col in self.tables.T]
        near = cv2.split(_lookup(np.column_stack(columns), g.z_index))
        x_c, s_c, sin, cos, curv = near[:5]
        dx = g.x_m - x_c
        step = dx * sin
        t0 = dx * cos
        s = s_c + step * (1.0 + curv * t0)
        t = t0 - 0.5 * curv * step * step
        t[g.z_m > zs[-1]] = FAR_M
        dxu, dxv, dzu, dzv = g.jacobian
        wt = np.abs(dxu * cos - dzu * sin) + np.abs(dxv * cos - dzv * sin) + 1e-4
        ws = np.minimum(np.abs(dxu * sin + dzu * cos) + np.abs(dxv * sin + dzv * cos), MAX_FOOTPRINT_M) + 1e-4
        return RoadCoords(s, t, ws, wt, tuple(near[5:]), np.column_stack(columns[:5])), heading

    def frame_grid(self, pose: CarPose) -> tuple[GroundGrid, np.ndarray]:
        """Return the grid and haze of the frame at ``pose``: the camera's on a flat road; on a
        pitched one, every band pixel's first hit on the road surface of ``heights_ahead``.

        A ray of slope d = y / z (down) meets the surface where (h_cam - H(z)) / z = d; the running
        minimum of that ratio over z is monotonic, so the first hit is one interpolation. Pixels
        whose ray meets no road within Z_MAX_M are sky above the flat horizon and haze below it.
        """
        g = self.grid
        if self.pitch is None:
            return g, self.haze
        p = self.pitch
        z_grid, height = self.heights_ahead(pose)
        z = z_grid[1:]
        ratio = np.minimum.accumulate((g.camera.height_m - height[1:]) / z)
        hit = p.down >= ratio[-1]
        z_hit = np.where(hit, np.interp(p.down, ratio[::-1], z[::-1]), Z_MAX_M).astype(np.float32)
        x_hit = z_hit * p.across
        jac = np.stack([np.gradient(x_hit, axis=1), np.gradient(x_hit, axis=0),
                        np.gradient(z_hit, axis=1), np.gradient(z_hit, axis=0)])
        jac = np.clip(jac, -MAX_FOOTPRINT_M, MAX_FOOTPRINT_M)
        footprint = np.maximum(np.abs(jac[:2]).sum(axis=0), np.abs(jac[2:]).sum(axis=0))
        distance = np.where(hit, z_hit, 1e5).astype(np.float32)
        frame = replace(g, row0=p.row0, x_m=x_hit, z_m=z_hit, distance_m=distance, jacobian=jac,
                        ground=np.where(hit, 1.0, p.flat_ground).astype(np.float32),
                        z_index=z_hit * (1.0 / Z_STEP_M), bands=_mip_bands(np.median(footprint, axis=1)))
        return frame, (1.0 - np.exp(-distance / self.scene.look.haze_m)).astype(np.float32)

    def _sun_direction(self, heading_rad: float) -> np.ndarray:
        """Return the unit direction to the sun in the car frame (x right, y down, z ahead)."""
        look = self.scene.look
        az = np.radians(look.sun_azimuth_deg) - heading_rad
        el = np.radians(look.sun_elevation_deg)
        return np.array([np.cos(el) * np.sin(az), -np.sin(el), np.cos(el) * np.cos(az)], np.float32)

    def _barriers(self, rc: RoadCoords, pose: CarPose, grid: GroundGrid) -> tuple[np.ndarray, np.ndarray]:
        """Return the barriers' coverage and their faces' grey under full light (band, float32).

        A pixel's ray runs over the ground from the car to its road point (x, z), at offset t; it
        crosses the face at t_b after the share f of its run where the offset of (f x, f z) is t_b
        (three secant steps from the straight-road share (t_car - t_b) / (t_car - t)), at the
        height h_cam (1 - f) + f H(z) - H(f z) above the road there (H: ``heights_ahead``). Only
        rays whose end lies beyond the face are tested, so a face never covers the road on the
        car's side of it.
        """
        t_car, h_cam = pose.offset_m, grid.camera.height_m
        z_grid = np.arange(len(rc.centre)) * Z_STEP_M
        pitched = self.road.height_m is not None
        if pitched:
            _, above = self.heights_ahead(pose)
        x_c, cos_c = rc.centre[:, 0], rc.centre[:, 3]

        def offset(f: np.ndarray) -> np.ndarray:
            z = f * grid.z_m
            return (f * grid.x_m - np.interp(z, z_grid, x_c)) * np.interp(z, z_grid, cos_c)

        cover = np.zeros_like(rc.t_m)
        grey = np.zeros_like(rc.t_m)
        for b in self.scene.look.barriers:
            side = t_car - b.t_m
            beyond = ((rc.t_m - b.t_m) * side < 0) & (np.abs(rc.t_m) < FAR_M / 2)
            f0, g0 = np.zeros_like(rc.t_m), np.full_like(rc.t_m, side)
            f1, g1 = np.ones_like(rc.t_m), np.where(beyond, rc.t_m - b.t_m, -side)
            for _ in range(3):
                with np.errstate(divide="ignore", invalid="ignore"):
                    f2 = np.clip(f1 - g1 * (f1 - f0) / (g1 - g0), 0.0, 1.0)
                f2 = np.where(np.isfinite(f2), f2, f1)
                f0, g0, f1, g1 = f1, g1, f2, offset(f2) - b.t_m
            f = np.where(beyond, f1, 2.0)
            height = h_cam * (1.0 - f)
            if pitched:
                height += f * np.interp(grid.z_m, z_grid, above) - np.interp(f * grid.z_m, z_grid, above)
            height = height.astype(np.float32)
            s_cross = pose.s_m + f * rc.s_m
            inside = ((s_cross >= b.s_from_m) & (s_cross <= b.s_to_m)).astype(np.float32)
            w = np.clip(np.abs(np.gradient(height, axis=0)) + np.abs(np.gradient(height, axis=1)), 1e-4, 10.0)
            a, lo = height + w / 2, height - w / 2
            face = _box(a, lo, 1.0 / w, b.bottom_m, b.height_m) * inside
            top = _box(a, lo, 1.0 / w, b.height_m - b.top_m, b.height_m) * inside
            grey += (b.grey * (face - top) + b.top_grey * top) * (1.0 - cover)
            cover += face * (1.0 - cover)
        return cover, grey

    def _sheen(self, grid: GroundGrid, heading_rad: float) -> np.ndarray:
        """Return the wet road's specular sheen (grey levels, band): the sun's blurred mirror image."""
        r = self.unit_rays[grid.row0:]
        sun = self._sun_direction(heading_rad) * np.array([1.0, -1.0, 1.0], np.float32)
        angle = np.degrees(np.arccos(np.clip(r @ sun, -1.0, 1.0)))
        core, halo = SHEEN_WIDTHS_DEG
        return self.scene.look.wet * (np.exp(-angle / core) + 0.35 * np.exp(-angle / halo))

    def _glare(self, heading_rad: float) -> np.ndarray:
        """Return the veiling glare (grey levels, whole frame): a core and a halo round the sun,
        the sun's disc (0.5 deg) and a tenth of it everywhere (the lens's stray light)."""
        angle = np.degrees(np.arccos(np.clip(self.unit_rays @ self._sun_direction(heading_rad), -1.0, 1.0)))
        core, halo = GLARE_WIDTHS_DEG
        veil = 0.7 * np.exp(-angle / core) + 0.2 * np.exp(-angle / halo) + 0.1 + 4.0 * (angle < 0.5)
        return (self.scene.look.glare * veil).astype(np.float32)

    # ------------------------------------------------------------------ shading

    def _line_paint(self, rc: RoadCoords, pose: CarPose, a: np.ndarray, b: np.ndarray,
                    inv_wt: np.ndarray, paint: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return the (white, yellow) paint coverage of every band pixel (0..1)."""
        white = np.zeros_like(a)
        yellow = np.zeros_like(a)
        for line in self.lines:
            half = line.width_m / 2
            near = np.flatnonzero((np.abs(rc.t_m - line.t_m) < half + rc.wt_m).ravel())
            if near.size == 0:
                continue
            cov = _box(a.ravel()[near] - line.t_m, b.ravel()[near] - line.t_m, inv_wt.ravel()[near],
                       -half, half)
            if line.dash_m > 0:
                period = line.dash_m + line.gap_m
                s = rc.s_m.ravel()[near] + (pose.s_m % period)
                ws = rc.ws_m.ravel()[near]
                cov *= (_dash_integral(s + ws / 2, period, line.dash_m)
                        - _dash_integral(s - ws / 2, period, line.dash_m)) / ws
            target = yellow if line.yellow else white
            target.ravel()[near] += cov * paint.ravel()[near]
        return white, yellow

    def _surface_grey(self, rc: RoadCoords, pose: CarPose, tone: np.ndarray,
                      a: np.ndarray, b: np.ndarray, inv_wt: np.ndarray) -> np.ndarray:
        """Return the grey brightness of the paved surface under full sun (band, float32)."""
        look = self.scene.look
        concrete = rc.profiles[MAX_STREAKS + CONCRETE]
        grey = look.asphalt_grey + (look.concrete_grey - look.asphalt_grey) * concrete
        grey *= tone
        for k, streak in enumerate(look.streaks[:MAX_STREAKS]):
            off = rc.profiles[k]
            half = streak.width_m / 2
            grey *= 1.0 - streak.darkness * _box(a - off, b - off, inv_wt, -half, half)
        if look.concrete_m:
            s = rc.s_m + (pose.s_m % CONCRETE_JOINT_M) + 0.01
            joint = (_dash_integral(s + rc.ws_m / 2, CONCRETE_JOINT_M, 0.02)
                     - _dash_integral(s - rc.ws_m / 2, CONCRETE_JOINT_M, 0.02)) / rc.ws_m
            grey *= 1.0 - 0.5 * joint * concrete
        return grey

    def _ground(self, pose: CarPose) -> tuple[np.ndarray, float, GroundGrid]:
        """Return the ground band's lit, hazed RGB (float32, B x W x 3), the car's heading (rad) and
        the frame's grid (``frame_grid``)."""
        look = self.scene.look
        grid, haze = self.frame_grid(pose)
        rc, heading = self.road_coords(pose, grid)
        sm = self.surface
        cols = (rc.t_m - sm.t0_m) * (1.0 / sm.mip.texel_m)
        rows = (rc.s_m + (pose.s_m - sm.s0_m)) * (1.0 / sm.mip.texel_m)
        surface = _sample(sm.mip, grid.bands, 0, cols, rows, wrap=False)
        tone, sun, paint = (c.astype(np.float32) for c in cv2.split(surface))
        tone *= 1.0 / 128.0
        cols = rc.t_m * (1.0 / self.grain.texel_m)
        rows = (rc.s_m + (pose.s_m % (GRAIN_TILE_PX * self.grain.texel_m))) * (1.0 / self.grain.texel_m)
        tone *= 1.0 + look.grain * _sample(self.grain, grid.bands, 1, cols, rows, wrap=True)
        inv_wt = 1.0 / rc.wt_m
        a, b = rc.t_m + rc.wt_m / 2, rc.t_m - rc.wt_m / 2
        grey = self._surface_grey(rc, pose, tone, a, b, inv_wt)
        white, yellow = self._line_paint(rc, pose, a, b, inv_wt, paint * (1.0 / 255.0))
        grey += (look.white_grey - grey) * np.minimum(white, 1.0)
        yellow = np.minimum(yellow, 1.0)
        paved = _box(a, b, inv_wt, *self.scene.layout.paved_m)
        light = (look.ambient * rc.profiles[MAX_STREAKS + AMBIENT]
                 + look.sun * (1.0 / 255.0) * rc.profiles[MAX_STREAKS + DIRECT] * sun)
        light *= 1.0 / (look.ambient + look.sun)
        keep = (1.0 - haze) * light
        sheen = self._sheen(grid, heading) * paved * (1.0 - haze) * (sun * (1.0 / 255.0)) if look.wet > 0 else None
        if look.barriers:
            cover, face = self._barriers(rc, pose, grid)
            face *= (look.ambient * rc.profiles[MAX_STREAKS + AMBIENT]
                     + look.sun * rc.profiles[MAX_STREAKS + DIRECT]) * ((1.0 - haze) / (look.ambient + look.sun))
        channels = []
        for c in range(3):
            colour = look.grass_rgb[c] * tone
            colour += (grey + (look.yellow_rgb[c] - grey) * yellow - colour) * paved
            colour *= keep
            colour += look.haze_rgb[c] * haze
            if sheen is not None:
                colour += sheen
            if look.barriers:
                colour += (face + look.haze_rgb[c] * haze - colour) * cover
            channels.append(colour)
        return cv2.merge(channels), heading, grid

    def _sky(self) -> np.ndarray:
        """Return the plain sky (sky_rows x W x 3, float32): a gradient from the horizon up."""
        look, g = self.scene.look, self.grid
        f = np.clip(g.elevation_deg / 25.0, 0.0, 1.0)[..., None] ** 0.6
        return (np.asarray(look.sky_horizon_rgb, np.float32) * (1 - f)
                + np.asarray(look.sky_top_rgb, np.float32) * f).astype(np.float32)

    def _skyline(self, sky: np.ndarray, heading_rad: float) -> None:
        """Draw the distant hills and the tree line into ``sky`` (in place) for the car's heading."""
        look, g = self.scene.look, self.grid
        r0, r1 = g.skyline_rows
        el = g.elevation_deg[r0:r1]
        n = len(self.skyline) - 1
        az = (g.azimuth_deg[r0:r1] + float(np.degrees(heading_rad))) * (1.0 / SKYLINE_STEP_DEG)
        tops = _lookup(self.skyline, az - np.floor(az * (1.0 / n)) * n)
        px_deg = float(np.degrees(1.0 / g.camera.K[1, 1]))
        for k, (rgb, haze) in enumerate(((look.hills_rgb, 0.45), (look.trees_rgb, 0.2))):
            cover = np.clip((tops[..., k] - el) * (1.0 / px_deg) + 0.5, 0.0, 1.0)[..., None]
            colour = np.asarray(rgb, np.float32) * (1 - haze) + np.asarray(look.haze_rgb, np.float32) * haze
            sky[r0:r1] += (colour - sky[r0:r1]) * cover

    def _bridges(self, sky: np.ndarray, pose: CarPose) -> None:
        """Draw the overpasses ahead of (or above) the car into ``sky`` in place, anti-aliased.

        A bridge is a deck (its underside ``height_m`` above the road, ``length_m`` deep) with a
        1.6 m high front face, square to the car's axis ``s_m - pose.s_m`` ahead.
        """
        g, cam = self.grid, self.grid.camera
        ry, rz = g.rays[..., 1], g.rays[..., 2]
        for bridge in self.scene.look.bridges:
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

    def _hood(self, frame: np.ndarray, gain: float) -> None:
        """Draw the car hood over the bottom rows of ``frame`` (float32, in place)."""
        g = self.grid
        colour = np.asarray(self.scene.look.hood_rgb, np.float32) * g.hood_shade * gain
        frame[g.hood_row0:] += (colour - frame[g.hood_row0:]) * g.hood_alpha

    def render(self, pose: CarPose, exposure: float | None = None, noise_key: int = 0) -> np.ndarray:
        """Return the raw (distorted) RGB uint8 frame for ``pose`` at ``exposure`` (default: the look's).

        ``noise_key`` picks the camera-noise pattern (the frame number in a video).
        """
        g, look = self.grid, self.scene.look
        gain = look.exposure if exposure is None else exposure
        for s_m, factor in look.exposure_steps_m:
            if pose.s_m >= s_m:
                gain *= factor
        w, h = g.camera.size_px
        ground, heading, fg = self._ground(pose)
        sky = self.sky.copy()
        self._skyline(sky, heading)
        self._bridges(sky, pose)
        frame = np.empty((h, w, 3), np.float32)
        frame[:fg.row0] = sky[:fg.row0]
        frame[fg.row0:] = ground
        overlap = slice(fg.row0, g.sky_rows)
        alpha = fg.ground[: g.sky_rows - fg.row0, :, None]
        frame[overlap] = sky[fg.row0:] + (frame[overlap] - sky[fg.row0:]) * alpha
        frame *= (g.vignette * gain)[..., None]
        self._hood(frame, gain)
        if look.glare > 0:
            frame += (self._glare(heading) * gain)[..., None]
        dy, dx = np.random.default_rng([self.scene.seed, noise_key]).integers(0, NOISE_MARGIN_PX, 2)
        frame += self.noise[dy:dy + h, dx:dx + w] * look.sensor_noise
        out = np.clip(frame, 0, 255).astype(np.uint8)
        return cv2.GaussianBlur(out, (3, 3), 0.6)
