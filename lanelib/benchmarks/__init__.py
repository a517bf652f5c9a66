"""Public lane benchmarks: their file formats and their official metrics.

``tusimple`` (JSON lines of lanes at ``h_samples``) and ``culane`` (list files and ``.lines.txt``
lanes) read the labels, write predictions in the benchmark's own layout and score a prediction
set; ``metrics`` holds the official TuSimple accuracy / FP / FN and CULane F1, which
``lanelib.evaluate`` shares for its synthetic truth. ``why`` and ``why_images`` (imported by
name: they run the pipeline and ``batch``, which import this package) say what became of each
labelled line of a frame, draw it, and count the classes over a set.
"""
from . import culane, metrics, tusimple

__all__ = ["culane", "metrics", "tusimple", "written", "WRITTEN"]

# which lines a benchmark labels, so ``predict`` writes no others
WRITTEN = {"culane": f"the nearest {culane.LINES_PER_SIDE} on each side of the car",
           "tusimple": f"the {tusimple.MAX_LINES} nearest the car"}


def written(benchmark: str | None, lines: list) -> list:
    """Return the lines (left to right, each with its ``offset_m`` from the car) that ``predict``
    writes for ``benchmark``: those it labels (``WRITTEN``), the others being false lines there
    however real their paint; every line for any other benchmark or None.

    Examples
    --------
    >>> from types import SimpleNamespace as Line
    >>> seen = [Line(offset_m=x) for x in (-9.4, -5.6, -2.5, 1.3, 5.0, 8.8)]
    >>> [l.offset_m for l in written("culane", seen)], [l.offset_m for l in written("tusimple", seen)]
    ([-5.6, -2.5, 1.3, 5.0], [-5.6, -2.5, 1.3, 5.0])
    >>> [l.offset_m for l in written("tusimple", seen[:4])]  # no lane right of the car's: 3 left
    [-9.4, -5.6, -2.5, 1.3]
    """
    if benchmark == "culane":
        n = culane.LINES_PER_SIDE
        return [l for l in lines if l.offset_m < 0][-n:] + [l for l in lines if l.offset_m >= 0][:n]
    if benchmark == "tusimple":
        nearest = sorted(range(len(lines)), key=lambda i: abs(lines[i].offset_m))[:tusimple.MAX_LINES]
        return [lines[i] for i in sorted(nearest)]
    return list(lines)
