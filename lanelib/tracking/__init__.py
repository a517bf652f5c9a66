"""Lane tracking across video frames: one loop over a pipeline, its proposers and its checks.

``LaneTracker.update(frame)`` returns a ``FrameResult`` whose fits are the tracked lane, so
``LanePipeline.annotate`` and the debug view work on it unchanged. Per frame:

1. **Predict.** The smoothed lane, which lags the road by about a frame, moved along its centre
   line's trend with ``trend_frames`` on (``roads.trend.predicted_lane``).
2. **Search.** Around the predicted lane when the previous frame was accepted, else sliding
   windows, in a look-ahead that keeps the lines in view (``LaneTracker.lookahead_top_px``).
3. **Check.** Each line alone and against the track (jump at the car, bend, a line seen only far
   ahead), the pair against the tracked width (``judge.TrackChecks``).
4. **Propose.** While no pair passes, the proposers look again (``proposers``: windows from the
   track; when switched on, ``roads.proposers``: the road seen from the car, remembered bases,
   re-acquisition, the asphalt edge, a faded line's shoulder, and ``roads.fallbacks``: fallback
   masks, shorter views, other peaks). The best candidate is kept.
5. **Infer.** A line lost is inferred from the other at the width seen at the car.
6. **Smooth.** The last ``smooth_frames`` accepted frames, weighted by ``recency_decay ** age``
   times each line's confidence. Not a Kalman filter: the tracker observes neither the steering
   nor the road, so a motion model would be "constant coefficients plus tuned noise"; the window
   has two plain parameters, a bounded memory and a lag of about a frame.
7. **Hold and reset.** With no line the predicted lane is held ``hold_frames`` frames with a
   falling confidence, then forgotten; one line may restart it soon after
   (``roads.checks.restart``, when on), and a pitched pair may start it.

The state carried between frames is one record, ``TrackState`` (compared, copied, pickled).
"""
from ..proposers import Candidate, Frame, Proposer
from .judge import TrackChecks
from .state import Accepted, LostTrack, TrackState
from .tracker import PROPOSERS, LaneTracker
from ..params.roads import TrackerConfig

__all__ = ["PROPOSERS", "Accepted", "Candidate", "Frame", "LaneTracker", "LostTrack", "Proposer",
           "TrackChecks", "TrackState", "TrackerConfig"]
