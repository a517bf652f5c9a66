"""What a synthetic road scene is made of: lane layout, surface, light and road geometry.

Plain frozen records; ``textures`` turns them into maps and ``render`` into pixels. Brightness is
in display grey levels (0-255) under full sun at exposure 1; positions along the road are arc
lengths s (m) on the lane centre line, across the road signed offsets t (m, positive right).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .road import CurvatureProfile

RGB = tuple[float, float, float]


@dataclass(frozen=True)
class Line:
    """One painted line: centre offset t (m), width (m), colour and dash pattern (m)."""

    t_m: float
    width_m: float
    yellow: bool
    dash_m: float = 0.0   # 0 for a solid line
    gap_m: float = 0.0


@dataclass(frozen=True)
class Layout:
    """The ego lane (leftmost, yellow line on its left), the lanes to its right and the shoulders.

    Parameters
    ----------
    lane_width_m : distance between the centres of the ego lane's two lines.
    right_lanes : number of lanes to the right of the ego lane (each ``lane_width_m`` wide).
    left_shoulder_m, right_shoulder_m : paved width beyond the outermost lines.
    line_width_m : width of every painted line.
    dash_m, gap_m : the dashed lines' paint and gap lengths.
    centre_gap_m : 0 for a single yellow line on the ego lane's left; above 0 a double yellow
        centre line: a second yellow stripe this far (clear gap, m) left of the first. The ego
        lane's left line (its truth) is the inner, right-hand stripe at -lane_width_m / 2.
    right_line : False leaves the outermost white edge line unpainted: with ``right_lanes=0`` and
        ``right_shoulder_m=0`` the ego lane ends at the asphalt edge, at +lane_width_m / 2 (its
        truth line).
    extra_lines : further painted lines (e.g. the oncoming lane's edge line).
    """

    lane_width_m: float = 3.7
    right_lanes: int = 2
    left_shoulder_m: float = 2.5
    right_shoulder_m: float = 2.5
    line_width_m: float = 0.15
    dash_m: float = 3.0
    gap_m: float = 9.0
    centre_gap_m: float = 0.0
    right_line: bool = True
    extra_lines: tuple[Line, ...] = ()

    def lines(self) -> tuple[Line, ...]:
        """Return the painted lines (left to right, then ``extra_lines``)."""
        w, half = self.lane_width_m, self.lane_width_m / 2
        out = [Line(-half, self.line_width_m, yellow=True)]
        if self.centre_gap_m > 0:
            out.insert(0, Line(-half - self.line_width_m - self.centre_gap_m, self.line_width_m, yellow=True))
        out += [Line(half + i * w, self.line_width_m, False, self.dash_m, self.gap_m)
                for i in range(self.right_lanes)]
        if self.right_line:
            out.append(Line(half + self.right_lanes * w, self.line_width_m, yellow=False))
        return tuple(out + list(self.extra_lines))

    @property
    def paved_m(self) -> tuple[float, float]:
        """Return the paved road's (left, right) edge offsets t (m)."""
        half = self.lane_width_m / 2
        return (-half - self.left_shoulder_m,
                half + self.right_lanes * self.lane_width_m + self.right_shoulder_m)


@dataclass(frozen=True)
class Streak:
    """A dark streak along the road (tar seam or crack): a line at t that wanders along s.

    Parameters
    ----------
    t_m : mean offset from the lane centre.
    width_m : width of the streak.
    darkness : fraction of the surface brightness it removes (0..1).
    wander_m : amplitude of its sideways wandering.
    s_from_m, s_to_m : where along the road it runs.
    """

    t_m: float
    width_m: float = 0.04
    darkness: float = 0.6
    wander_m: float = 0.03
    s_from_m: float = -1e9
    s_to_m: float = 1e9


@dataclass(frozen=True)
class Bridge:
    """An overpass: its front edge at arc length ``s_m``, ``length_m`` deep, deck ``height_m`` up."""

    s_m: float
    length_m: float = 18.0
    height_m: float = 5.2


@dataclass(frozen=True)
class Barrier:
    """A vertical face along the road (concrete barrier, kerb, guard rail) at offset ``t_m``.

    The face spans heights ``bottom_m`` to ``height_m`` above the road, its top ``top_m`` lit
    brighter (``top_grey``: the bright edge), between arc lengths ``s_from_m`` and ``s_to_m``. It is
    drawn where a pixel's ray crosses t = ``t_m`` before it meets the road, with the crossing
    found along the ray as if the road were straight there (exact on straights; on bends the
    face is placed approximately and never hides the road on the car's side of it, so it never
    covers a truth line). Light: the s-profile's light (clouds, bridges), not the tree shadows.
    """

    t_m: float
    height_m: float = 0.81
    bottom_m: float = 0.0
    grey: float = 168.0
    top_grey: float = 240.0
    top_m: float = 0.07
    s_from_m: float = -1e9
    s_to_m: float = 1e9


@dataclass(frozen=True)
class Look:
    """How the surface, the paint and the light look (grey levels under full sun, exposure 1).

    Parameters
    ----------
    asphalt_grey : mean asphalt brightness.
    asphalt_blotches : relative amplitude of large-scale asphalt tone variation.
    grain : relative amplitude of the fine asphalt grain.
    concrete_grey : brightness of light concrete sections.
    concrete_m : (s_from, s_to) ranges paved with concrete.
    patches_per_100m : repair patches (darker or lighter asphalt) per 100 m of road.
    resurfaced : (s_from, s_to, t_from, t_to, tone factor) strips of newer or older asphalt.
    streaks : tar seams and cracks along the road.
    white_grey, yellow_rgb : paint colours.
    paint_wear : how worn the paint is, 0 new to 1 mostly gone.
    tree_shadows_per_100m : trees beside the road whose shadows fall across it.
    bridges : overpasses (their shadow darkens the road beneath).
    light_m : (s_from, s_to, direct-light factor) ranges, e.g. clouds; ramps are 10 m long.
    sun, ambient : direct and sky light; shadows keep only the ambient part.
    haze_m : distance at which 63 % of a surface's colour has faded to the haze colour.
    sensor_noise : standard deviation of the camera noise (grey levels).
    exposure : camera gain (the video's auto exposure starts from it).
    paint_missing_m : (s_from, s_to, t_from, t_to) stretches where the paint is gone entirely.
    barriers : concrete barriers, kerbs and guard rails beside the road.
    exposure_steps_m : (s, factor) sudden camera gain changes once the car passes s (a video's auto
        exposure then recovers at its own rate).
    sun_azimuth_deg, sun_elevation_deg : the sun's direction for glare and sheen, azimuth clockwise
        from the road's initial direction.
    glare : veiling glare (grey levels at the sun, falling off with the angle from it; a tenth of
        it everywhere, which lowers contrast); 0 for none.
    wet : the wet road's specular sheen (grey levels at the sun's mirror direction); 0 for none.
    """

    asphalt_grey: float = 92.0
    asphalt_blotches: float = 0.07
    grain: float = 0.10
    concrete_grey: float = 172.0
    concrete_m: tuple[tuple[float, float], ...] = ()
    patches_per_100m: float = 1.5
    resurfaced: tuple[tuple[float, float, float, float, float], ...] = ()
    streaks: tuple[Streak, ...] = ()
    white_grey: float = 225.0
    yellow_rgb: RGB = (226, 182, 52)
    paint_wear: float = 0.1
    tree_shadows_per_100m: float = 0.0
    bridges: tuple[Bridge, ...] = ()
    light_m: tuple[tuple[float, float, float], ...] = ()
    sun: float = 1.0
    ambient: float = 0.35
    haze_m: float = 700.0
    haze_rgb: RGB = (196, 206, 218)
    sky_top_rgb: RGB = (70, 125, 200)
    sky_horizon_rgb: RGB = (175, 200, 228)
    grass_rgb: RGB = (150, 134, 92)
    hills_rgb: RGB = (160, 140, 100)
    trees_rgb: RGB = (60, 78, 45)
    hood_rgb: RGB = (92, 52, 46)
    sensor_noise: float = 1.5
    exposure: float = 1.0
    paint_missing_m: tuple[tuple[float, float, float, float], ...] = ()
    barriers: tuple[Barrier, ...] = ()
    exposure_steps_m: tuple[tuple[float, float], ...] = ()
    sun_azimuth_deg: float = 0.0
    sun_elevation_deg: float = 8.0
    glare: float = 0.0
    wet: float = 0.0


@dataclass(frozen=True)
class Scene:
    """A road and how it looks: centre-line geometry, layout, look, the arc-length span and a seed.

    The road exists from ``s_from_m`` to ``s_to_m``; a car may stand anywhere that leaves
    ``render.LOOK_AHEAD_M`` of road ahead of it and ``render.LOOK_BEHIND_M`` behind.
    ``grades`` is the vertical profile: knots (s_m, grade) joined linearly (grade = rise / run,
    0.06 for 6 % up); the road's height is its integral (``road.heights``). Empty: a flat road.
    """

    profile: CurvatureProfile = field(default_factory=CurvatureProfile)
    layout: Layout = field(default_factory=Layout)
    look: Look = field(default_factory=Look)
    s_from_m: float = -20.0
    s_to_m: float = 300.0
    seed: int = 0
    grades: tuple[tuple[float, float], ...] = ()
