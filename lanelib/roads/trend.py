"""The lane trend: the tracked lane moved along the trend of its centre line.

A hard-road part (``TrackerConfig.trend_frames``, off by default, 5 in the ``hard-roads`` and
``country`` presets): on a bend that tightens or opens, the smoothed lane lags the road by about a
frame, and the lane predicted for the next frame follows the trend instead. The tracker's state
(``tracking.state.TrackState``) is passed in (duck-typed): this package sits below it in the
layers.
"""
from __future__ import annotations

import numpy as np


def predicted_lane(state, config, frame: int | None = None) -> tuple[np.ndarray, np.ndarray] | None:
    """Return the smoothed lane of ``state`` moved along the trend of its centre line to ``frame``
    (default: ``state.frame``); the smoothed lane itself while ``config.trend_frames`` is below 3.

    The smoothed lane averages past frames, so it shows the lane as it was a frame or so ago
    (the weighted mean of its frames' numbers). From the third accepted frame on, each pixel
    coefficient of the centre line over the last ``trend_frames`` accepted frames is fitted
    by a straight line in the frame number, and both lines are moved by that rate times the
    frames from the average's time to ``frame`` (the width is kept). While the lane is not
    seen the trend is followed no further than the frame after the last accepted one: a held
    lane that followed it through a whole hold would drift from the lines that come back.
    """
    lane = state.lane(config.recency_decay)
    if lane is None or config.trend_frames < 3 or len(state.trend) < 3:
        return lane
    frames = np.array([acc.frame for acc in state.trend], float)
    centres = np.array([(acc.left + acc.right) / 2.0 for acc in state.trend])
    rate = np.polyfit(frames - frames[-1], centres, 1)[0]  # per frame, for a, b and c
    # frame numbers counted from the last accepted frame: the same floats wherever the
    # tracker started (a Dask segment warms up from a later frame than one process)
    last = frames[-1]
    w = state.smoothing_weights(config.recency_decay)
    times = w.T @ (np.array([acc.frame for acc in state.history], float) - last) / w.sum(axis=0)
    target = min(float(state.frame if frame is None else frame) - last, 1.0)
    return lane[0] + rate * (target - times[0]), lane[1] + rate * (target - times[1])
