"""The opt-in proposers that read the tracker: the road seen from the car, remembered bases,
re-acquisition, the asphalt edge, a faded line.

Each is a proposer (the protocol in ``lanelib.proposers``): it says ``where`` it has something
to look for in a frame and ``propose``s candidate searches there. ``AsphaltEdge`` serves a single
image (``LanePipeline.detect``) and the tracker; the others read the tracker.

- ``RoadView``: when a line is refused, the look-ahead is also cut where the lane's interior
  stops looking like the road near the car (beyond a crest, a vehicle on the road).
- ``RememberedBases``: without a track, a weak histogram peak is replaced by the median of the
  recent accepted bases on that side (``TrackerConfig.base_history_frames``).
- ``Reacquire``: a line the track has inferred for several frames is looked for in a band
  around its inference that widens with those frames (``reacquired``).
- ``AsphaltEdge``: a lane with one line and no paint at all on the other side takes the
  unpainted asphalt edge there as its line (``edge_search``).
- ``Shoulder``: while both lines are seen, each painted line's distance out to the asphalt edge
  is measured near the car (``measure_shoulders``, on one frame in ``shoulder_every``) and
  remembered; when the paint then fades, the line is placed that far inside the edge where the
  edge is seen, joined beyond to the inference or nearer the car to returning paint.

The pipeline and the tracker are passed in (duck-typed): this package sits below both in the
layers. ``TRACKER_FIRST``, ``TRACKER_LATER`` and ``DETECT`` are where these and those of
``roads.fallbacks`` go in the tracker's chain and in a single image's, in their order;
``detect_again`` runs a single image's chain (``LanePipeline.detect``).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..fit import joined_fit, offset_line, parallel_fits
from ..proposers import Candidate, Frame, choose, passes
from ..records import LaneSearch, LineFit, Window, near_row_px
from ..search import fit_side, search_around
from ..thresholds import Made
from .edge import VergeGrid, grid_rows_px, road_edge, road_view_interior, road_view_top_px, verge_grid
from .fallbacks import FallbackMasks, OtherPeaks, ShorterViews

SIDES = ("left", "right")


class RoadView:
    """A line refused: search again in the view that ends where the road stops looking like the
    road seen from the car (``TrackerConfig.road_view_run_m``); a pair there is taken."""

    name, rule, moves_lookahead = "road view", "a pair", True

    def where(self, frame):
        t = frame.tracker
        if frame.track is None or not frame.best.failed or t.config.road_view_run_m <= 0:
            return None
        cap = road_view_top(t, frame.raw, frame.track)
        return cap if cap > frame.top else None

    def propose(self, frame, where):
        t = frame.tracker
        return [(frame.search(frame.prior, bases=t.bases(frame.track), top_px=where), "")]


def road_view_top(tracker, raw: np.ndarray, track: tuple[np.ndarray, np.ndarray]) -> int:
    """Return the first row (px) of the road seen continuously from the car in a RAW frame,
    between the tracked lines ``track`` (``roads.edge.road_view_top_px``), 0 for the whole view.

    Only every ``road_view_step_px``-th row of the bird's-eye view, and only the columns the
    lane's interior covers on them, are remapped (``LanePipeline.birdseye_rows``); the
    saturation step that is unlike the road is ``EdgeConfig.min_saturation_step``.
    """
    pipe = tracker.pipeline
    w, h = pipe.size
    rows = np.arange(h - 1, -1, -tracker.config.road_view_step_px)
    lo, hi = road_view_interior(rows, track, w)
    c0, c1 = int(lo.min()), int(max(hi.max(), lo.min() + 1))  # the columns an interior covers
    if c0 >= w:
        return 0
    return road_view_top_px(pipe.birdseye_rows(raw, rows, (c0, c1)), rows, track, tracker.ym,
                            pipe.config.edge.min_saturation_step, tracker.config.road_view_run_m, w, c0)


class RememberedBases:
    """Without a track, when a histogram peak is weak (``min_base_peak``): windows started
    from the median of the recent accepted bases (``base_history_frames``) on that side."""

    name, rule, moves_lookahead = "remembered bases", "more lines", False

    def where(self, frame):
        if frame.track is not None or frame.best.pair:
            return None
        t = frame.tracker
        remembered, search = remembered_bases(t), frame.first
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

    def propose(self, frame, where):
        return [(frame.search(bases=where),
                 "windows started from the remembered bases (weak histogram peak)")]


def remembered_bases(tracker) -> tuple[float, float] | None:
    """Return the median x (px, bottom row) of each line over the tracker's remembered frames
    (``TrackerConfig.base_history_frames``), or None."""
    if not tracker.state.base_history:
        return None
    left, right = np.median(np.array(tracker.state.base_history), axis=0)
    return float(left), float(right)


class Reacquire:
    """A line the track has inferred for ``reacquire_after_frames`` frames, looked for in a band
    around its inference that widens with the frames it has been inferred (up to
    ``reacquire_band_m``): an inference drifts while nothing shows the line."""

    name, rule, moves_lookahead = "re-acquire", "more lines", False

    def where(self, frame):
        if frame.track is None:
            return None
        best = frame.best
        for i, (mine, other) in enumerate(((best.left, best.right), (best.right, best.left))):
            if mine is None and other is not None and reacquire_half_px(frame.tracker, i) > 0:
                return i
        return None

    def propose(self, frame, where):
        return [(reacquired(frame.tracker, frame.best.search, frame.mask(), frame.pixels(),
                            frame.track, where, frame.top), "")]


def reacquired(tracker, search: LaneSearch, binary: np.ndarray,
               pixels: tuple[np.ndarray, np.ndarray], track, side: int, top_px: int) -> LaneSearch | None:
    """Return ``search`` with line ``side`` looked for again in ``binary``, the whole view, or
    None when no line could lie within ``reacquire_half_px`` of its inference. ``pixels``: the
    mask's ``search.lane_pixels`` (``Frame.pixels``, extracted once for the frame's searches).

    The inference is moved across to the median distance of the lane pixels in the bin nearest
    it (bins ``prior_margin_px`` wide, every half margin, out to the band's half width) that
    holds ``min_line_pixels``, and the line is searched within ``prior_margin_px`` of it
    (``search.search_around``), its curvature shared with the other line when it is short
    (``fit.parallel_fits``). The band goes into the search's windows, so the line's band checks
    compare it with the band it was searched in.
    """
    cfg = tracker.pipeline.config.search
    half = reacquire_half_px(tracker, side)
    margin = cfg.prior_margin_px
    ys, xs = pixels
    keep = ys >= top_px
    dx = xs[keep] - np.polyval(track[side], ys[keep])
    dx = dx[np.abs(dx) <= half]
    if len(dx) < cfg.min_line_pixels:
        return None
    steps = np.arange(margin / 2, half - margin / 2 + 1.0, margin / 2)
    for centre in [0.0] + [c for step in steps for c in (-step, step)]:  # nearest first
        near = dx[np.abs(dx - centre) <= margin / 2]
        if len(near) >= cfg.min_line_pixels:
            break
    else:
        return None
    moved = np.array(track[side], float)
    moved[2] += float(np.median(near))
    name = ("left", "right")[side]
    priors = [LineFit(None), LineFit(None)]
    priors[side] = LineFit(tuple(moved))
    found = search_around(binary, priors[0], priors[1], cfg, top_px)
    h = tracker.pipeline.size[1]
    slabs = np.linspace(float(h), float(top_px), cfg.n_windows + 1).round().astype(int)
    band = tuple(Window(name, int(x - margin), int(x + margin), int(lo), int(hi))
                 for hi, lo in zip(slabs[:-1], slabs[1:])
                 for x in [float(np.polyval(moved, (lo + hi) / 2))])
    merged = replace(search, **{name: getattr(found, name), f"{name}_pixels": getattr(found, f"{name}_pixels")},
                     windows=tuple(w for w in search.windows if w.side != name) + band)
    left, right = parallel_fits(merged.left, merged.right, merged.left_pixels, merged.right_pixels, h, cfg)
    return replace(merged, left=left, right=right)


def reacquire_half_px(tracker, side: int) -> float:
    """Return the half width (px) of the band a line inferred for ``reacquire_after_frames``
    frames or more is looked for in, 0 when it is not re-acquired: it widens by a search
    margin each frame, up to ``reacquire_band_m`` (``LaneTracker.jump_limit_m`` allows as far)."""
    cfg = tracker.config
    run = tracker.state.inferred_run[side]
    if not cfg.reacquire_after_frames or run < cfg.reacquire_after_frames:
        return 0.0
    margin = tracker.pipeline.config.search.prior_margin_px
    return min(margin * (2 + run - cfg.reacquire_after_frames), cfg.reacquire_band_m / tracker.xm)


class AsphaltEdge:
    """One line kept and no paint on the other side: the asphalt edge there as the line.

    Without a track: the best search found one line and nothing on the other side. With a
    track: the other side's tracked line was the asphalt edge (no paint was tracked there), and
    what the search found there failed the checks, so it is dropped for the edge.
    """

    name, rule, moves_lookahead = "asphalt edge", "more lines", False

    def where(self, frame):
        if not frame.pipeline.config.edge.enabled:
            return None
        best, track = frame.best, frame.track
        search = best.search
        if track is None:
            return search if search.left.found != search.right.found else None
        if (best.left is None) == (best.right is None):
            return None
        side = "left" if best.left is None else "right"
        if not frame.tracker.state.edge[SIDES.index(side)]:
            return None
        return replace(search, **{side: LineFit(None, reason="refused by the checks")})

    def propose(self, frame, where):
        return [(edge_search(frame.pipeline, frame.birdseye(), where), "")]


def edge_search(pipeline, bird: np.ndarray, search: LaneSearch, guide_px=None,
                range_m: tuple[float, float] | None = None,
                shoulder_m: float | None = None) -> LaneSearch | None:
    """Return ``search`` with its missing line replaced by the asphalt edge on that side,
    when the lane then passes the checks; else None.

    Only for a search that found one line, which passes its own check, and no paint at all
    on the other side (its fit not found): a painted line that is seen is never replaced.
    The edge (``roads.edge.road_edge``, ``PipelineConfig.edge``, read in the bird's-eye image
    ``bird``, between ``range_m`` from ``guide_px``: by default a lane's width from the found
    line) is then checked with the found line as a lane (``LanePipeline.check``: width within the
    road's range, parallel, equally curved) over the rows where the edge is seen (the
    search's look-ahead, ``top_px``, ends at its farthest point: its fit is not extrapolated
    beyond); its search's ``edge`` flags the side. With ``shoulder_m`` (a painted line faded
    out, ``Shoulder``) the line is placed that far inside the edge, along its
    normal (``fit.offset_line``) where the edge is seen, joined beyond it to ``guide_px``
    (one second-order fit to both), the look-ahead and the other line kept; the search's
    ``shoulder`` flags the side instead, and it is returned unchecked: the tracker checks it
    against its track (the lane's width ahead, which a grade changes in the flat view).
    """
    cfg = pipeline.config.edge
    if not cfg.enabled or search.left.found == search.right.found:
        return None
    side, other = ("right", search.left) if search.left.found else ("left", search.right)
    first = pipeline.check(search)
    if first.left or first.right:
        return None
    p = pipeline.perspective
    fit, _ = road_edge(bird, other, side, p.xm_per_px, p.ym_per_px, pipeline.config.checks,
                       cfg, search.top_px, guide_px, range_m)
    if not fit.found:
        return None
    h = pipeline.size[1]
    seen_top = max(search.top_px, int(h - 1 - fit.gap_px - fit.span_px))
    if shoulder_m is not None:
        # the painted line the shoulder inside the edge where the edge is seen, joined beyond
        # it to the guide (one second-order fit to both); the look-ahead and the other line
        # are kept
        inward = -shoulder_m if side == "right" else shoulder_m
        placed = offset_line(fit.coeffs_px, inward, p.xm_per_px, p.ym_per_px, h, seen_top)
        if seen_top > search.top_px and guide_px is not None:
            near = np.arange(float(seen_top), float(h))
            far = np.arange(float(search.top_px), float(seen_top))
            placed = joined_fit(near, np.polyval(placed, near), guide_px, far, h)
        return replace(search, **{side: replace(fit, coeffs_px=tuple(placed))},
                       shoulder=(side == "left", side == "right"))
    # the look-ahead ends where the edge is seen: its fit is not extrapolated beyond, and
    # the other line is refitted on its pixels there (an S-bend's two halves are not one
    # second-order curve: the whole view's fit would not be parallel to the edge's)
    top = seen_top
    fits = {side: fit}
    if top > search.top_px:
        ys, xs = search.right_pixels if side == "left" else search.left_pixels
        near = ys >= top
        refit, _ = fit_side((ys[near], xs[near]), "left" if side == "right" else "right",
                            pipeline.size[1], pipeline.config.search, "no lane pixels")
        if not refit.found:
            return None
        fits["left" if side == "right" else "right"] = refit
    found = replace(search, **fits, edge=(side == "left", side == "right"), top_px=top)
    return found if pipeline.check(found).ok else None


class Shoulder:
    """A painted line faded out: placed its measured shoulder inside the asphalt edge."""

    name, rule, moves_lookahead = "shoulder", "a pair", False

    def where(self, frame):
        t = frame.tracker
        if not (t.pipeline.config.edge.enabled and frame.track is not None and t.config.shoulder_frames):
            return None
        return faded_side(t, frame.raw, frame.images.get("birdseye"), frame.best)

    def propose(self, frame, where):
        t = frame.tracker
        side, why_faded = where
        note = (f"{SIDES[side]} line {why_faded}: placed the shoulder ({shoulder_m(t, side):.2f} m) "
                "inside the asphalt edge")
        return [(placed, note + (", joined ahead to its returning paint" if joined else ""))
                for placed, joined in shoulder_search(t, frame.birdseye(), side, frame.best, frame.track)]


def shoulder_m(tracker, side: int) -> float:
    """Return the shoulder (m) of line ``side`` (0 left, 1 right): how far beyond its paint the
    asphalt edge runs, the median of the remembered measurements once at least half of
    ``shoulder_frames`` are in and their robust spread is within ``shoulder_spread_m``; NaN
    otherwise."""
    cfg = tracker.config
    found = np.array(tracker.state.shoulders[side], float)
    if not cfg.shoulder_frames or 2 * len(found) < cfg.shoulder_frames:
        return float("nan")
    median = float(np.median(found))
    if 1.4826 * float(np.median(np.abs(found - median))) > cfg.shoulder_spread_m:
        return float("nan")
    return median


def measure_shoulders(tracker, frame: Frame, index: int) -> None:
    """Remember the shoulder of each painted line of a frame (number ``index`` in the video) whose
    best candidate kept both lines at the car (``shoulder_beside``, when clearly found); only with
    the asphalt edge and ``shoulder_frames`` on, on one frame in ``shoulder_every``."""
    cfg = tracker.config
    if not (tracker.pipeline.config.edge.enabled and cfg.shoulder_frames and index % cfg.shoulder_every == 0):
        return
    left, right, search = frame.best.left, frame.best.right, frame.best.search
    if not (tracker.reach_car(left) and tracker.reach_car(right)):
        return
    grid = None
    for i, (fit, other) in enumerate(((left, right), (right, left))):
        if search.edge[i] or search.shoulder[i]:
            continue  # not paint
        grid = grid or near_grid(tracker, frame.raw, frame.images.get("birdseye"))
        shoulder = shoulder_beside(tracker, grid, fit, other, i, (search.left_pixels, search.right_pixels)[i])
        if not np.isnan(shoulder):
            tracker.state.shoulders[i].append(round(shoulder, 4))


def near_grid(tracker, raw: np.ndarray | None, bird: np.ndarray | None) -> VergeGrid:
    """Return the verge features (``roads.edge.verge_grid``) of the bird's-eye view's rows within
    ``shoulder_near_m`` of its bottom row: one row of each ``EdgeConfig.scale`` (measured on every
    frame with both lines, so cheap), from ``bird`` or those rows of RAW alone remapped."""
    pipe = tracker.pipeline
    h = pipe.size[1]
    k = pipe.config.edge.scale
    top = max(0, int(round(tracker.bottom - tracker.config.shoulder_near_m / tracker.ym))) // k * k
    sample = grid_rows_px(top, h, k)
    rows = bird[sample] if bird is not None else pipe.birdseye_rows(raw, sample)
    return verge_grid(rows, k, top, h, sampled=True)


def shoulder_beside(tracker, grid: VergeGrid, fit: LineFit, other: LineFit, side: int,
                    pixels: tuple[np.ndarray, np.ndarray] | None = None) -> float:
    """Return the shoulder (m) beyond line ``fit`` on ``side`` (0 left, 1 right), NaN where not
    clearly found.

    The median distance (along the line's normal) from the line out to the asphalt edge beyond
    it in ``grid`` (``near_grid``; ``roads.edge.road_edge`` from 0 to ``EdgeConfig.max_shoulder_m``
    beyond the line, the road surface read between ``fit`` and ``other``), on the rows within
    ``shoulder_near_m`` of the bottom row. Clearly found: edge points on at least half of those
    rows, their distances' robust spread within ``shoulder_spread_m``. With the line's
    ``pixels`` ((ys, xs) of the search) the distance on a row is from the median of its pixels
    there: on a tight bend a fit can lie centimetres outside its paint at the car.
    """
    cfg = replace(tracker.pipeline.config.edge, trace_margin_m=0.0)
    k = cfg.scale
    xm, ym, bottom = tracker.xm, tracker.ym, tracker.bottom
    top = max(0, int(round(bottom - tracker.config.shoulder_near_m / ym)))
    _, points = road_edge(None, other, SIDES[side], xm, ym, tracker.checks, cfg, top,
                          guide_px=fit.coeffs_px, range_m=(0.0, cfg.max_shoulder_m), grid=grid)
    if len(points) < 0.5 * (bottom + 1 - top) / k:
        return float("nan")
    ys = points[:, 1]
    x_line = np.polyval(fit.coeffs_px, ys)
    if pixels is not None and len(pixels[0]):
        bins = (np.asarray(pixels[0]) // k).astype(int)
        near = bins >= top // k
        rows, paint = row_medians(bins[near], np.asarray(pixels[1], float)[near])
        if len(rows):  # the paint's x on each grid row it holds
            grid_rows = (ys // k).astype(int)
            at = np.minimum(np.searchsorted(rows, grid_rows), len(rows) - 1)
            hit = rows[at] == grid_rows
            x_line[hit] = paint[at[hit]]
    slope = np.polyval(np.polyder(np.asarray(fit.coeffs_px, float)), ys) * xm / ym
    dist = np.abs(points[:, 0] - x_line) * xm / np.sqrt(1.0 + slope ** 2)
    median = float(np.median(dist))
    if 1.4826 * float(np.median(np.abs(dist - median))) > tracker.config.shoulder_spread_m:
        return float("nan")
    return median


def faded_side(tracker, raw: np.ndarray, bird: np.ndarray | None, best) -> tuple[int, str] | None:
    """Return the side (0 left, 1 right) whose painted line has faded out, with what was seen of
    it, or None.

    The side's shoulder is known (``shoulder_m``), its tracked line is no asphalt edge, the other
    line is kept, the side's paint was not seen at the car in the last accepted frame, and: this
    frame kept no line there for ``reacquire_after_frames`` frames or more (a line missing for a
    frame or two, a dash's gap, is still near its track and is inferred); or the line kept there
    is seen only far ahead (the paint returning ahead); or it is the asphalt edge itself: the edge
    lies less than half the shoulder beyond it (grass beside the edge can pass for a line).
    """
    search, state = best.search, tracker.state
    for i, (fit, other) in enumerate(((best.left, best.right), (best.right, best.left))):
        if other is None or state.edge[i] or not state.faded_run[i] or search.edge[i] or search.shoulder[i]:
            continue
        shoulder = shoulder_m(tracker, i)
        if np.isnan(shoulder):
            continue
        if fit is None:
            if state.faded_run[i] >= max(1, tracker.config.reacquire_after_frames):
                return i, "not found where its paint faded out"
            continue
        found = (search.left, search.right)[i]
        if not tracker.reach_car(found):
            return i, "seen only far ahead where its paint faded out"
        gap_m = found.gap_px * tracker.ym
        if gap_m > tracker.config.return_gap_m:
            return i, f"seen only from {gap_m:.1f} m ahead where its paint faded out"
        if shoulder_beside(tracker, near_grid(tracker, raw, bird), fit, other, i) < 0.5 * shoulder:
            return i, "seen at the asphalt edge, where its paint runs the shoulder inside it"
    return None


def shoulder_search(tracker, bird: np.ndarray, side: int, best, track) -> list[tuple[LaneSearch, bool]]:
    """Return the best search with its line ``side`` placed the remembered shoulder inside the
    asphalt edge on that side (``edge_search``), each with whether it is joined to
    the line's returning paint: first so joined (``joined_paint``) where the search has pixels on
    that side, then joined beyond the edge to the line inferred from the kept one; none where no
    edge is found. The edge is looked for from the line inferred from the kept one, within the
    shoulder plus or minus the line's jump limit beyond it."""
    search = best.search
    kept = best.right if side == 0 else best.left
    name = SIDES[side]
    guide = tracker.inferred_line(np.array(kept.coeffs_px, float), track, side, search.top_px)
    shoulder, tol = shoulder_m(tracker, side), tracker.jump_limit_m(side)
    faded = replace(search, **{name: LineFit(None, reason="paint faded out"), SIDES[1 - side]: kept})
    placed = edge_search(tracker.pipeline, bird, faded, guide, (max(0.0, shoulder - tol), shoulder + tol),
                         shoulder)
    if placed is None:
        return []
    line = getattr(placed, name)
    joined = joined_paint(tracker, (search.left_pixels, search.right_pixels)[side], line, search.top_px)
    if joined is None:
        return [(placed, False)]
    return [(replace(placed, **{name: joined}), True), (placed, False)]


def joined_paint(tracker, pixels, placed: LineFit, top_px: int) -> LineFit | None:
    """Return a faded line's returning paint ahead joined nearer the car to ``placed`` (the line
    placed the shoulder inside the asphalt edge), or None with fewer than half
    ``min_line_pixels`` paint pixels (``pixels``: (ys, xs) of the search on that side) in the
    look-ahead (from ``top_px``).

    One second-order fit (``fit.joined_fit``) to the paint's median x on each row it holds and to
    the placed line on each row between the paint's nearest (all but ``records.NEAR_SHARE`` of
    its pixels lie above it) and the bottom row: paint seen only a few metres ahead beyond a
    crest lies inside the line at the car, which an extrapolation would not follow. Its pixel
    count and rows are the edge's and the paint's together.
    """
    ys, xs = np.asarray(pixels[0]), np.asarray(pixels[1], float)
    keep = ys >= top_px
    ys, xs = ys[keep], xs[keep]
    if len(ys) < tracker.pipeline.config.search.min_line_pixels // 2:
        return None
    bottom = tracker.bottom
    near = near_row_px(ys)
    keep = ys <= near
    rows, med = row_medians(ys[keep], xs[keep])
    coeffs = joined_fit(rows.astype(float), med, placed.coeffs_px, np.arange(np.floor(near) + 1.0, bottom + 1.0),
                        tracker.pipeline.size[1])
    top = min(float(rows[0]), bottom - placed.gap_px - placed.span_px)
    return replace(placed, coeffs_px=coeffs, n_pixels=placed.n_pixels + int(keep.sum()),
                   span_px=float(bottom - placed.gap_px - top))


def row_medians(keys: np.ndarray, xs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return each distinct key of ``keys`` (a row, or a shrunk grid's row; ascending) and the
    median of the ``xs`` that share it (``np.median``'s, for all rows at once)."""
    keys, xs = np.asarray(keys), np.asarray(xs, float)
    order = np.lexsort((xs, keys))
    k, v = keys[order], xs[order]
    rows, first, counts = np.unique(k, return_index=True, return_counts=True)
    lo, hi = first + (counts - 1) // 2, first + counts // 2
    return rows, (v[lo] + v[hi]) / 2


# the opt-in proposers in the tracker's chain (``tracking.PROPOSERS``), each asking only when its
# switch is on: the road view before the tracker's own proposer (it cuts the look-ahead of the
# windows from the track), the others after it
TRACKER_FIRST = (RoadView(),)
TRACKER_LATER = (RememberedBases(), Reacquire(), FallbackMasks(), ShorterViews(), OtherPeaks(), AsphaltEdge(),
                 Shoulder())
# a single image's chain (``pipeline.DETECT_PROPOSERS``, ``detect_again``): those that need no track
DETECT = (FallbackMasks(), ShorterViews(), OtherPeaks(), AsphaltEdge())


def detect_again(pipeline, raw: np.ndarray, images: dict, first: LaneSearch, made: Made | None,
                 keep_images: bool = False) -> LaneSearch:
    """Return the search a single image's lane comes from when its first search ``first`` failed
    the checks (``LanePipeline.detect``, without a prior): the first candidate of the proposers that
    need no track (``DETECT``, through ``proposers.choose``) whose two lines pass a single image's
    checks (``proposers.passes``), else ``first``, which ``detect`` has judged already (it is not
    checked again). With ``keep_images``, a lane found so leaves the mask it came from in
    ``images["binary"]`` for the views; the fallback masks' binary is not kept.
    """
    frame = Frame(pipeline, raw, lambda search: _passing(pipeline, search), images, first=first, made=made,
                  best=Candidate(first, None, None, [], False), looked=[first])
    best = choose(frame, DETECT).search
    if best is not first and keep_images:
        images["binary"] = frame.mask()  # the views show the mask the lane came from
    images.pop("fallback binary", None)
    return best


def _passing(pipeline, search: LaneSearch) -> Candidate:
    """Return a search judged as a single image: both lines, or none when not both pass."""
    if passes(pipeline, search):
        return Candidate(search, search.left, search.right, [], False)
    return Candidate(search, None, None, [], False)
