"""Lane tracking across video frames: one loop over a pipeline, its proposers and its checks.

``LaneTracker.update(frame)`` runs one frame through a ``LanePipeline`` and returns a
``FrameResult`` whose fits are the tracked (smoothed) lane, so ``LanePipeline.annotate`` and the
debug composite work on it unchanged. Per frame:

1. **Predict.** The smoothed lane, moved along the trend of its centre line with
   ``trend_frames`` on (``roads.trend.predicted_lane``): the smoothed lane lags the road by
   about a frame.
2. **Search.** Around the predicted lane when the previous frame was accepted, with sliding
   windows otherwise, in a look-ahead that keeps the tracked lines in view
   (``LaneTracker.lookahead_top_px``).
3. **Check.** Each line alone, each line against the track (jump at the car, bend in shape, a
   line seen only far ahead joined near the car), the pair against the tracked width
   (``judge.TrackChecks``).
4. **Propose.** While no pair passes, the proposers look again, each where it has something
   to look for (``proposers``: windows from the track, remembered bases; the hard-road ones,
   each only when switched on, ``roads.proposers``: the road seen from the car,
   re-acquisition, the asphalt edge, a faded line's shoulder, and ``roads.fallbacks``: fallback
   masks, shorter views, other peaks). The best candidate is kept.
5. **Infer.** A line lost is inferred from the other at the width seen at the car.
6. **Smooth.** The reported lane is a weighted average of the last ``smooth_frames`` accepted
   frames, weight ``recency_decay ** age`` times each line's confidence. A weighted window, not
   a Kalman filter: the tracker observes neither the steering nor the road that move the lane,
   so a motion model would be "constant coefficients plus tuned noise"; the window has two plain
   parameters, a bounded memory and a lag of about a frame.
7. **Hold and reset.** With no line, the predicted lane is held for ``hold_frames`` frames with
   a falling confidence, then the track is forgotten; one line alone may restart it soon after
   (``roads.checks.restart``, when switched on), and a pair in a pitched flat view may start it.

The state carried between frames is one record, ``TrackState``: it can be compared, copied and
pickled (the Dask joints of a video's segments use it).
"""
from ..proposers import Candidate, Frame, Proposer
from .judge import TrackChecks
from .state import Accepted, LostTrack, TrackState
from .tracker import PROPOSERS, LaneTracker
from ..params.roads import TrackerConfig

__all__ = ["PROPOSERS", "Accepted", "Candidate", "Frame", "LaneTracker", "LostTrack", "Proposer",
           "TrackChecks", "TrackState", "TrackerConfig"]
