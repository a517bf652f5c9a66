"""The proposers that read the track: where the tracker looks again in a frame.

The protocol and chain are ``lanelib.proposers``, shared with ``LanePipeline.detect``. These two
need what the tracker remembers: windows from the tracked lines, and from the remembered bases
where a histogram peak is weak. The hard-road ones (the crest's road view, re-acquisition, the
asphalt edge, a faded line's shoulder, ``roads.fallbacks``) live in ``lanelib.roads``.
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


class RememberedBases:
    """Without a track, when a histogram peak is weak (``min_base_peak``): windows started
    from the median of the recent accepted bases (``base_history_frames``) on that side."""

    name, rule, moves_lookahead = "remembered bases", "more lines", False

    def where(self, frame: Frame):
        if frame.track is not None or frame.best.pair:
            return None
        t = frame.tracker
        remembered, search = t.remembered_bases, frame.first
        if remembered is None or search.method != "windows":
            return None
        out, weak = [], False
        for base, conf, memory in zip(search.bases_px, search.base_confidence, remembered):
            if base is None or conf is None or conf < t.config.min_base_peak:
                out.append(memory)
                weak = True
            else:
                out.append(base)
        return (out[0], out[1]) if weak else None

    def propose(self, frame: Frame, where):
        return [(frame.search(bases=where),
                 "windows started from the remembered bases (weak histogram peak)")]
