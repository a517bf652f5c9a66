"""Public lane benchmarks: their file formats and their official metrics.

``tusimple`` (JSON lines of lanes at ``h_samples``) and ``culane`` (list files and ``.lines.txt``
lanes) read the labels, write predictions in the benchmark's own layout and score a prediction
set; ``metrics`` holds the official TuSimple accuracy / FP / FN and CULane F1, which
``lanelib.evaluate`` shares for its synthetic truth. ``why`` and ``why_images`` (imported by
name: they run the pipeline and ``batch``, which import this package) say what became of each
labelled line of a frame, draw it, and count the classes over a set.
"""
from . import culane, metrics, tusimple

__all__ = ["culane", "metrics", "tusimple"]
