"""Every frozen parameter record of lanelib, in a leaf package: it imports nothing of lanelib but ``errors``.

The stage modules import their records from here and keep them as their public names
(``lanelib.search.SearchConfig``, ``lanelib.thresholds.ThresholdConfig``, ...); ``config``
nests them into ``PipelineConfig``. Nothing here imports a stage, so neither the stages nor
``config`` form a cycle through their parameters.

- ``stages``: ``PerspectiveConfig``, ``SearchConfig``, ``LaneChecks``, ``DrawConfig``, ``HoughConfig``;
- ``masks``: ``ChannelMask``, ``ColorRange``, ``SobelMask``, ``TopHatMask``, ``ThresholdConfig``;
- ``roads``: ``EdgeConfig``, ``LinesConfig``, ``TrackerConfig``.
"""
from .masks import ChannelMask, ColorRange, SobelMask, ThresholdConfig, TopHatMask
from .roads import EdgeConfig, LinesConfig, TrackerConfig
from .stages import DrawConfig, HoughConfig, LaneChecks, PerspectiveConfig, SearchConfig

__all__ = ["ChannelMask", "ColorRange", "DrawConfig", "EdgeConfig", "HoughConfig", "LaneChecks",
           "LinesConfig", "PerspectiveConfig", "SearchConfig", "SobelMask", "ThresholdConfig",
           "TopHatMask", "TrackerConfig"]
