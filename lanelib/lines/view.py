"""The lines view: the wide, long bird's-eye view in which ``lines.detect`` looks for every lane
line in sight, made from the ego view's ``perspective.Perspective`` (``LinesView``)."""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..perspective import Homography, Perspective


class LinesView(Homography):
    """The wide, long bird's-eye view in which every lane line in sight is looked for.

    Made from the ego view (a ``Perspective``): the same road plane, rescaled by an affine map of
    the ego view, so it inherits that view's geometry (from ``--config`` or ``--auto-geometry``)
    and its metric scale. It spans ``half_width_m`` either side of the car's centre line at
    ``xm_per_px`` across, and from ``behind_m`` nearer than the ego view's bottom row to
    ``ahead_m`` beyond it at ``ym_per_px`` along the road (coarser along than across: lines are
    long and thin). As a ``Homography``, ``view(points)`` maps undistorted-image points to the
    view and ``view.inverse`` maps back; ``ego_to_view`` is the affine map from the ego view.

    Parameters
    ----------
    ego : the ego view's ``Perspective``.
    half_width_m : the road seen either side of the car's centre line (m).
    xm_per_px : metres per view pixel across the road.
    ahead_m : the road seen beyond the ego view's bottom row (m).
    ym_per_px : metres per view pixel along the road.
    behind_m : the road seen nearer than the ego view's bottom row (m).
    """

    def __init__(self, ego: Perspective, half_width_m: float = 14.0, xm_per_px: float = 0.016,
                 ahead_m: float = 150.0, ym_per_px: float = 0.2, behind_m: float = 1.0):
        if min(half_width_m, xm_per_px, ahead_m, ym_per_px) <= 0 or behind_m < 0:
            raise ConfigError("LinesView: half_width_m, xm_per_px, ahead_m and ym_per_px must be "
                              "positive and behind_m 0 or more")
        self.ego = ego
        w = int(round(2 * half_width_m / xm_per_px))
        h = int(round((ahead_m + behind_m) / ym_per_px))
        self.size = (w, h)
        self.xm_per_px = float(xm_per_px)
        self.ym_per_px = float(ym_per_px)
        self.car_x_px = w / 2.0
        self.bottom_px = h - behind_m / ym_per_px  # the ego view's bottom row in this view
        sx = ego.xm_per_px / xm_per_px
        sy = ego.ym_per_px / ym_per_px
        ego_bottom = float(ego.size[1])
        a = np.array([[sx, 0.0, self.car_x_px - sx * ego.car_x_px],
                      [0.0, sy, self.bottom_px - sy * ego_bottom],
                      [0.0, 0.0, 1.0]])
        self.ego_to_view = Homography(a)
        super().__init__(a @ ego.params, ego.inverse_params @ np.linalg.inv(a))

    @property
    def scale_from_ego(self) -> float:
        """Return how many view pixels one ego-view pixel spans across the road (< 1: coarser)."""
        return self.ego.xm_per_px / self.xm_per_px

    def __repr__(self) -> str:
        return (f"LinesView({self.size[0]}x{self.size[1]}, {self.xm_per_px:g} x {self.ym_per_px:g} m/px, "
                f"from {self.ego!r})")
