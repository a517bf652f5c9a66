"""Lane tracking across video frames: sanity checks, smoothing, fall back and reset."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class TrackerConfig:
    """Parameters of ``LaneTracker``.

    Parameters
    ----------
    min_width_m, max_width_m : a detection whose lane width at the car lies outside is rejected.
    max_width_spread_m : largest difference of the lane width between the bottom and top rows
        (lines roughly parallel).
    max_curvature_diff_1pm : largest difference of the two lines' curvature.
    max_jump_m : largest change of a line's position at the car from one frame to the next.
    smooth_frames : good frames averaged (weighted towards the newest) for the reported fit.
    hold_frames : frames the last good lane is kept after detection fails, before a reset.
    """

    min_width_m: float = 3.0
    max_width_m: float = 4.5
    max_width_spread_m: float = 0.7
    max_curvature_diff_1pm: float = 0.004
    max_jump_m: float = 0.5
    smooth_frames: int = 5
    hold_frames: int = 12
