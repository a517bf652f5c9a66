"""The tracker's own proposer: where the tracker looks again in a frame with a track.

The protocol and chain are ``lanelib.proposers``, shared with ``LanePipeline.detect``. This one
needs what the tracker remembers: windows from the tracked lines. The opt-in ones (the crest's
road view, remembered bases, re-acquisition, the asphalt edge, a faded line's shoulder,
``roads.fallbacks``) live in ``lanelib.roads``.
"""
from __future__ import annotations

from ..proposers import Frame


class WindowsFromTrack:
    """With a track and no pair: sliding windows started from the tracked lines' bases."""

    name, rule, moves_lookahead = "windows from the track", "more lines", False

    def where(self, frame: Frame):
        return frame.tracker.bases(frame.track) if frame.track is not None and not frame.best.pair else None

    def propose(self, frame: Frame, where):
        return [(frame.search(bases=where, top_px=frame.top), "")]
