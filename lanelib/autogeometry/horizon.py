"""Coordinates about the horizon, the ego lane, and the camera's roll from the lanes' spacing.

- **Coordinates** (``_Basis``): about the vanishing point, turned by the roll: u along the
  horizon, v the distance below it. A road line at lateral offset t (m) from the camera, seen
  from height H, runs from the vanishing point at atan(t / H) from straight down; in these
  coordinates it is u = k v (``_k``).
- **The ego lane** (``_ego_frames``). Its two lines are one on either side among the two nearest
  there, each 20-80 deg from straight down. Its width r is the one the road's lines agree on
  (lanes are equally wide): the width of the most frames' pairs plus frames with two adjacent
  lines on one side that far apart, so that neither the neighbour lanes' outer lines (three
  lanes wide, as centred on a car in a middle lane as its own) nor a dashed line not seen (two
  lanes wide) nor a bright seam in the lane is taken for the ego lane; each frame takes its most
  centred pair within 20 % of r, and frames with none are left out.
- **Horizon and roll** (``_roll_from_spacing``). The vanishing point of the road lies on the
  horizon. Its slope is the camera's roll, which lane lines of one direction cannot show by
  themselves: it is measured from the spacing of three or more lines (the ego lane's two and
  any line beyond them up to 80 deg from straight down), assuming every lane has the same
  width. Along any image line parallel to the horizon, lines equally spaced on the road are
  equally spaced in the image (that image line is the picture of a road line whose own
  vanishing point is at infinity, so the map between them is affine); the roll that makes the
  lines' spacings whole multiples of the ego lane's in all frames is used when at least 3
  frames give it one by one within 0.3 deg. Otherwise the roll is assumed 0 and the assumptions
  say so: ignoring a roll moves the horizon at the image centre by |w/2 - vp_x| tan(roll), and
  puts the lane width and the scale along the road off with it (the dashes are measured square
  to the wrong horizon).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

MAX_ROLL_DEG = 4.0
ROLL_MAX_LINE_ANGLE_DEG = 80.0  # lines flatter than this (|k| > 5.7) tell the roll too loosely
EGO_ANGLES_DEG = (20.0, 80.0)


@dataclass(frozen=True)
class _Basis:
    vp: np.ndarray
    eh: np.ndarray   # along the horizon (to the right)
    ev: np.ndarray   # down, perpendicular to the horizon

    def to_uv(self, p: np.ndarray) -> np.ndarray:
        d = np.asarray(p, np.float64) - self.vp
        return np.stack([d @ self.eh, d @ self.ev], axis=-1)

    def to_xy(self, u, v) -> np.ndarray:
        return self.vp + np.multiply.outer(u, self.eh) + np.multiply.outer(v, self.ev)


def _basis(vp, roll_deg: float) -> _Basis:
    r = math.radians(roll_deg)
    return _Basis(np.asarray(vp, np.float64), np.array([math.cos(r), -math.sin(r)]),
                  np.array([math.sin(r), math.cos(r)]))


def _k(angle_deg: np.ndarray, roll_deg: float) -> np.ndarray:
    """Return k = du/dv of lines at ``angle_deg`` about the vanishing point, in coordinates rotated by the roll."""
    return np.tan(np.radians(np.asarray(angle_deg) - roll_deg))


def _ego_frames(angle_lists: dict[int, np.ndarray], roll_deg: float) -> dict[int, tuple[int, int, float]]:
    """Return {frame: (left line, right line, r = k_right - k_left)} of the ego lane in the frames
    where it is seen.

    The candidates of each frame are the pairs of one line on either side of the camera's line
    among the two nearest there, each EGO_ANGLES_DEG from straight down (atan of half a lane
    over the camera's height: 56 deg for 3.7 m lanes seen from 1.25 m; 37 deg from a 2.5 m
    truck cab). Some pairs are not the ego lane: a dashed line not seen or a bright seam in the
    lane make the nearest pair two lanes wide or part of one, and on a road of three lanes or
    more a car in a middle lane sees the neighbour lanes' outer lines as a pair three lanes wide,
    centred on it as well as its own. So the lane's width r is chosen by the road's other lines
    too: lanes are equally wide, so neighbour lines lie one lane width apart. A width's support
    is the number of frames with a candidate pair within 20 % of it plus the number of frames
    with two adjacent lines on one side of the camera (up to ROLL_MAX_LINE_ANGLE_DEG from
    straight down) that far apart; r is the median width of the frames' pairs within 20 % of
    the candidate width of the most support (ties: the narrowest), or of a half or a third of it
    (within 10 %) when a width there has a third of its support or more (lanes whose dashed lines
    are missed in most frames). Each frame takes its most nearly
    centred pair within 20 % of r (a car drives near its lane's centre); frames with none are
    left out.
    """
    lo, hi = (math.tan(math.radians(a)) for a in EGO_ANGLES_DEG)
    k_far = math.tan(math.radians(ROLL_MAX_LINE_ANGLE_DEG))
    pairs: dict[int, list[tuple[float, int, int, float]]] = {}
    gaps: dict[int, np.ndarray] = {}
    for i, ang in angle_lists.items():
        k = _k(ang, roll_deg)
        # an ego line lies EGO_ANGLES_DEG from straight down: atan(half a lane / camera height)
        left = [j for j in np.argsort(-k) if -hi <= k[j] <= -lo][:2]
        right = [j for j in np.argsort(k) if lo <= k[j] <= hi][:2]
        found = sorted((abs(k[a] + k[b]) / (k[b] - k[a]), int(a), int(b), float(k[b] - k[a]))
                       for a in left for b in right)
        if found:
            pairs[i] = found
        ks = np.sort(k[np.abs(k) <= k_far])
        same_side = ks[:-1] * ks[1:] > 0
        gaps[i] = np.diff(ks)[same_side]
    if not pairs:
        return {}
    widths = sorted({p[3] for found in pairs.values() for p in found})

    def support(c: float) -> int:
        near = lambda v: np.abs(np.asarray(v) / c - 1) <= 0.2  # noqa: E731
        return (sum(bool(near([p[3] for p in found]).any()) for found in pairs.values())
                + sum(bool(near(g).any()) for g in gaps.values() if len(g)))

    def centre(c: float) -> float:
        """The median of each frame's candidate width nearest ``c`` (within 20 % of it)."""
        near = [min((p[3] for p in found), key=lambda v: abs(v / c - 1)) for found in pairs.values()]
        return float(np.median([v for v in near if abs(v / c - 1) <= 0.2] or [c]))

    scored = {c: support(c) for c in widths}
    best = max(widths, key=lambda c: (scored[c], -c))
    r = centre(best)
    for n in (3, 2):       # a half or a third of it, seen often enough: the lanes' own width
        part = [c for c in widths if abs(c * n / r - 1) <= 0.1 and 3 * scored[c] >= scored[best]]
        if part:
            r = centre(max(part, key=lambda c: (scored[c], -c)))
            break
    chosen = {i: next((p for p in found if abs(p[3] / r - 1) <= 0.2), None) for i, found in pairs.items()}
    return {i: (c[1], c[2], c[3]) for i, c in chosen.items() if c is not None}


def _roll_from_spacing(frames: list[tuple[np.ndarray, tuple[int, int]]]) -> tuple[float, int] | None:
    """Return (roll deg, lines used) that makes the lines of every frame (their angles about the
    frame's vanishing point, and which two are the ego lane's) equally spaced along the horizon,
    whole multiples of the ego lane's width apart, or None when no frame shows a line beyond the
    ego lane's.

    The cost, summed over the frames' lines outside the ego lane, is each line's distance from a
    whole multiple (capped at 0.15, so that a line of another spacing, e.g. a shoulder, weighs
    little), on a grid of rolls within MAX_ROLL_DEG; its minimum is refined by least squares
    with the multiples fixed.
    """
    grid = np.arange(-MAX_ROLL_DEG, MAX_ROLL_DEG + 1e-9, 0.01)
    terms = []          # (angles, ego pair, other line indices)
    for ang, pair in frames:
        ang = np.asarray(ang, np.float64)
        lo, hi = sorted(ang[list(pair)])
        # lines beyond the ego lane's, not so flat that a hundredth of a degree moves them a lane
        others = [j for j in range(len(ang)) if (ang[j] < lo or ang[j] > hi)
                  and abs(ang[j]) <= ROLL_MAX_LINE_ANGLE_DEG]
        if others:
            terms.append((ang, pair, others))
    if not terms:
        return None

    def multiples(rolls: np.ndarray, ang, pair, others) -> np.ndarray:
        k = _k(ang[None, :], rolls[:, None])
        return (k[:, others] - k[:, [pair[0]]]) / (k[:, [pair[1]]] - k[:, [pair[0]]])

    cost = np.zeros(len(grid))
    for ang, pair, others in terms:
        n = multiples(grid, ang, pair, others)
        cost += np.minimum(np.abs(n - np.round(n)), 0.15).sum(1)
    b = int(np.argmin(cost + 1e-3 * np.abs(grid)))   # a tie goes to the smaller roll
    roll = float(grid[b])
    # least squares around it with the multiples fixed
    fixed = []
    for ang, pair, others in terms:
        n = multiples(np.array([roll]), ang, pair, others)[0]
        keep = [(j, round(v)) for j, v in zip(others, n) if abs(v - round(v)) < 0.1 and round(v) not in (0, 1)]
        if keep:
            fixed.append((ang, pair, [j for j, _ in keep], np.array([m for _, m in keep], np.float64)))
    if not fixed:
        return None
    fine = roll + np.arange(-0.05, 0.05 + 1e-9, 0.001)
    sq = np.zeros(len(fine))
    for ang, pair, idx, m in fixed:
        sq += ((multiples(fine, ang, pair, idx) - m) ** 2).sum(1)
    return float(fine[int(np.argmin(sq))]), sum(len(f[2]) for f in fixed)
