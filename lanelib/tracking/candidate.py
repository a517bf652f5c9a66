"""A candidate search of one tracked frame and what the track's checks kept of it."""
from __future__ import annotations

from dataclasses import dataclass

from ..records import LaneSearch, LineFit

SIDES = ("left", "right")


@dataclass
class Candidate:
    """A search of one frame and what the checks kept of it: the lines that pass (None where
    refused or not found), why the others do not, and whether a check refused a found line."""

    search: LaneSearch
    left: LineFit | None
    right: LineFit | None
    why: list[str]
    failed: bool

    @property
    def lines(self) -> int:
        """Return how many lines pass."""
        return (self.left is not None) + (self.right is not None)

    @property
    def pair(self) -> bool:
        """Return whether both lines pass."""
        return self.left is not None and self.right is not None
