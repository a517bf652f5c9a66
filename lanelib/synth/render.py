"""The road-scene renderer: a textured road plane seen through the distorted camera.

Everything that depends only on the camera is computed once (``grid.GroundGrid``): the road
point (x, z) under every pixel of the raw, distorted image, the pixel's footprint on the road
(the Jacobian of (x, z) over (column, row)), the horizon coverage, the sky directions, the hood.
Everything that depends only on the scene is drawn once (``textures``). Per frame the renderer
only maps car-frame road points to road coordinates (s, t) through two table lookups along the
centre line, and shades them. Anti-aliasing is analytic: every painted line, dash, streak and
edge is box-filtered over the pixel's footprint on the road, and the maps are sampled from the
mipmap level that matches the footprint, so distant dashes fade instead of shimmering. The rest
of the frame (sky, skyline, overpasses, barriers, glare and wet sheen) is painted by ``scenery``.

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

from .grid import (FAR_M, MAX_FOOTPRINT_M, Z_MAX_M, Z_STEP_M, GroundGrid, _box, _dash_integral, _lookup,
                   _mip_bands)
from .road import CarPose, Road, car_frame, grade, world_to_car
from .scene import Line, Scene
from .scenery import barrier_faces, glare, paint_bridges, paint_skyline, plain_sky, sheen
from .textures import (AMBIENT, CONCRETE, DIRECT, GRAIN_TILE_PX, MAX_STREAKS, Mipmap, SurfaceMap, grain,
                       light_table, skyline, streak_table, surface_map)

LOOK_AHEAD_M = 220.0    # centre line used ahead of the car
LOOK_BEHIND_M = 10.0    # and behind it (the bottom image corners see the road beside the car)
MAX_ROAD_ANGLE_RAD = np.radians(75.0)  # the road ahead is used until it turns this far
CONCRETE_JOINT_M = 4.5  # transverse joints of concrete slabs
NOISE_MARGIN_PX = 16
PITCH_MARGIN_PX = 120   # rows above the flat horizon a climbing road may reach (scenes with grades)


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
        self.sky = plain_sky(self.scene.look, grid)
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
        wet = None
        if look.wet > 0:
            wet = sheen(look, self.unit_rays[grid.row0:], heading) * paved * (1.0 - haze) * (sun * (1.0 / 255.0))
        if look.barriers:
            above = self.heights_ahead(pose)[1] if self.road.height_m is not None else None
            cover, face = barrier_faces(look.barriers, rc.t_m, rc.s_m, rc.centre, pose, grid, above)
            face *= (look.ambient * rc.profiles[MAX_STREAKS + AMBIENT]
                     + look.sun * rc.profiles[MAX_STREAKS + DIRECT]) * ((1.0 - haze) / (look.ambient + look.sun))
        channels = []
        for c in range(3):
            colour = look.grass_rgb[c] * tone
            colour += (grey + (look.yellow_rgb[c] - grey) * yellow - colour) * paved
            colour *= keep
            colour += look.haze_rgb[c] * haze
            if wet is not None:
                colour += wet
            if look.barriers:
                colour += (face + look.haze_rgb[c] * haze - colour) * cover
            channels.append(colour)
        return cv2.merge(channels), heading, grid

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
        paint_skyline(sky, look, g, self.skyline, heading)
        paint_bridges(sky, look, g, pose)
        frame = np.empty((h, w, 3), np.float32)
        frame[:fg.row0] = sky[:fg.row0]
        frame[fg.row0:] = ground
        overlap = slice(fg.row0, g.sky_rows)
        alpha = fg.ground[: g.sky_rows - fg.row0, :, None]
        frame[overlap] = sky[fg.row0:] + (frame[overlap] - sky[fg.row0:]) * alpha
        frame *= (g.vignette * gain)[..., None]
        self._hood(frame, gain)
        if look.glare > 0:
            frame += (glare(look, self.unit_rays, heading) * gain)[..., None]
        dy, dx = np.random.default_rng([self.scene.seed, noise_key]).integers(0, NOISE_MARGIN_PX, 2)
        frame += self.noise[dy:dy + h, dx:dx + w] * look.sensor_noise
        out = np.clip(frame, 0, 255).astype(np.uint8)
        return cv2.GaussianBlur(out, (3, 3), 0.6)
