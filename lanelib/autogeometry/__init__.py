"""The road geometry of a camera, estimated from frames of the road itself.

``estimate_geometry(frames)`` returns a ``RoadGeometry``: the vanishing point of the road
direction, the horizon (with the camera's roll), the hood, the points of a bird's-eye view that
reaches ``look_ahead_m`` ahead, its metric scale, and when a focal length is known (given, from a
calibration, or measured from the dashes) the camera's pitch, yaw and height. It says how
confident it is, what it assumed, and which frames it used and why it left the others out.
``RoadGeometry.perspective_config()`` is the ``perspective.PerspectiveConfig`` to run with.
``vanishing_point(frame)`` is the cheap per-frame part, for a video to check every few seconds
whether the vanishing point drifts (a hill, a bump, a camera knocked) and, from the straight
frames through the video, where the road heads on average: ``refined_geometry`` moves the point
(and the bird's-eye view with it) along the horizon to there (``GeometryWatch``).

An extension of the core: it uses the core's camera, perspective and thresholds, and the core
does not import it. The modules, in the order the estimate runs:

- ``segments``: the paint mask, its straight band segments, and where segments meet (RANSAC);
- ``vanishing``: one frame's painted lines, its vanishing point and whether the road is
  straight (``RoadLineFinder``, ``vanishing_point``);
- ``hood``: the car's hood, still while the road moves (``detect_hood``);
- ``horizon``: coordinates about the horizon, the ego lane, the roll from the lanes' spacing;
- ``dashes``: the scale along the road from the dash period;
- ``lens``: the lens's radial distortion from the bend of straight lines (``estimate_lens``);
- ``road``: what the frames tell together (the frames used, the vanishing point, the roll,
  the ego lane, the hood row);
- ``view``: the bird's-eye points, and whether the ego lane runs parallel through them;
- ``estimate``: the focal length, the scale along the road, the camera's pose and the
  confidence (``estimate_geometry``);
- ``roadgeometry``: the result (``RoadGeometry``) and ``refined_geometry``;
- ``watch``: the options of a run's estimate (``GeometryOptions``), the check that refuses an
  estimate that fails or is not confident (``checked_geometry``), and the watch through a video
  that refines the point and estimates again when the horizon moves (``GeometryWatch``).

Frames that give no consistent vanishing point raise ``errors.GeometryError`` naming the reason:
no road (no line segments), too few segments, inconsistent (segments that meet in no point, or
points that disagree between frames), road not straight.
"""
from .estimate import (ASSUMED_HFOV_DEG, CAMERA_HEIGHT_RANGE_M, DEFAULT_DASH_M, DEFAULT_GAP_M,
                       DEFAULT_LOOK_AHEAD_M, MIN_GOOD_FRAMES, estimate_geometry)
from .hood import detect_hood
from .lens import LensEstimate, estimate_lens, radial_undistort
from .roadgeometry import DRIFT_PX, LOW_CONFIDENCE, RoadGeometry, refined_geometry
from .segments import paint_mask_config
from .vanishing import RoadLine, RoadLineFinder, VanishingPoint, vanishing_point
from .watch import (REFINE_MAX_CHECKS, REFINE_MIN_CHECKS, REFINE_TOLERANCE, GeometryOptions, GeometryWatch,
                    checked_geometry, geometry_calibration, low_confidence)

__all__ = ["estimate_geometry", "refined_geometry", "vanishing_point", "estimate_lens", "detect_hood",
           "radial_undistort", "paint_mask_config", "RoadGeometry", "RoadLineFinder", "RoadLine",
           "VanishingPoint", "LensEstimate", "LOW_CONFIDENCE", "DRIFT_PX", "MIN_GOOD_FRAMES",
           "DEFAULT_LOOK_AHEAD_M", "DEFAULT_DASH_M", "DEFAULT_GAP_M", "ASSUMED_HFOV_DEG",
           "CAMERA_HEIGHT_RANGE_M", "GeometryOptions", "GeometryWatch", "checked_geometry",
           "geometry_calibration", "low_confidence", "REFINE_MIN_CHECKS", "REFINE_TOLERANCE",
           "REFINE_MAX_CHECKS"]
