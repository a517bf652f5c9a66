"""``LanePipeline``: the advanced lane-finding pipeline wired from one ``PipelineConfig``.

One frame: raw RGB -> (one remap: undistort + warp) bird's-eye view -> thresholds -> lane-pixel
search -> fits -> plausibility checks (``params.LaneChecks``, the same as the video tracker's) ->
measurements -> overlay on the undistorted frame (``detect_lines``: every lane line in view as
well, for the benchmarks, in a wider and longer view). A lane that fails the checks is not found; what
it measured is kept apart in ``FrameResult.rejected``. The notebooks, the tuners and the CLI all
use this object, so what a slider tunes is exactly what a video run uses. This module is the
per-frame engine only: runs over image folders and videos are ``batch.process_images`` and
``batch.process_video``.
"""
from __future__ import annotations

import functools
from dataclasses import replace

import cv2
import numpy as np

from . import draw, thresholds
from .camera import Calibration, Undistorter
from .checks import LaneCheck, check_lane, holds_from_px, search_bands_px
from .config import PipelineConfig
from .errors import InputError
from .fit import joined_fit, measure, offset_line
from .lines import vote
from .lines.trace import find_lines
from .params import LinesConfig
from .perspective import LinesView, Perspective, scaled
from .records import LaneMeasurement, LaneSearch, LineFit, line_source
from .result import FrameResult, LinesResult, Rejected, image_line, line_confidence
from .roads.edge import road_edge
from .search import candidate_bases, fit_side, histogram, search_around, sliding_windows


BAND_STRIPS = 4  # strips in which band_binary computes the bands around prior fits


class LanePipeline:
    """Find the lane in frames of one size with one configuration and (optional) calibration.

    Parameters
    ----------
    config : all parameters; its perspective points are scaled if ``size`` differs from theirs.
    calibration : the camera's calibration, or None for an undistorted (or uncalibrated) camera.
    size : (width, height) of the frames; defaults to the perspective's ``size_px``.

    Everything that depends only on the configuration (remap maps, matrices, the car's position
    in the bird's-eye view) is computed here, once. A pipeline pickles as (config, calibration,
    size) and is built again on unpickling (its maps too), so it can be sent to Dask workers.
    """

    def __init__(self, config: PipelineConfig = PipelineConfig(), calibration: Calibration | None = None,
                 size: tuple[int, int] | None = None):
        self.config = config
        self.size = tuple(int(v) for v in (size or config.perspective.size_px))
        pconf = config.perspective
        if tuple(pconf.size_px) != self.size:
            pconf = scaled(pconf, self.size)
        self.perspective = Perspective(pconf)
        self.undistorter = Undistorter(calibration, self.size)
        self.lens = self.undistorter.lens
        # raw frame -> bird's-eye view, and back (the overlay on the raw frame, the evaluation)
        self.raw_to_birdseye = self.lens.inverse + self.perspective
        self.birdseye_to_raw = self.raw_to_birdseye.inverse
        self._birdseye_maps = self.raw_to_birdseye.remap_maps(self.size)
        self._context_px = thresholds.context_px(config.thresholds)
        self._clahe = thresholds.make_clahe(config.thresholds, self.size)  # None when off
        self._context_masks = tuple(n for n in thresholds.rule_masks(config.thresholds)
                                    if thresholds.mask_context_px(getattr(config.thresholds, n)) != (0, 0))
        self.car_x_px = self.perspective.car_x_px
        self._lines_view = None  # (view, remap maps, thresholds), made by the first detect_lines
        self._lines_to_raw = None  # the lines view's transform back to the raw frame, made with it
        self._lines_seen = None  # the lines view's pixels that see the frame, away from its edge
        self._lines_weights = None  # how much each row of the lines view counts in the vote

    def __reduce__(self):
        return LanePipeline, (self.config, self.undistorter.calibration, self.size)

    # ---- stages ---------------------------------------------------------------------------

    def birdseye(self, raw: np.ndarray) -> np.ndarray:
        """Return the bird's-eye view of a RAW frame (undistortion and warp in one remap)."""
        self.undistorter.check(raw)
        return cv2.remap(raw, self._birdseye_maps[0], self._birdseye_maps[1], cv2.INTER_LINEAR)

    def birdseye_rows(self, raw: np.ndarray, rows_px: np.ndarray,
                      cols_px: tuple[int, int] | None = None) -> np.ndarray:
        """Return the rows ``rows_px`` (int) of the bird's-eye view of a RAW frame, (n, W, 3), or
        their columns ``cols_px`` = (first, last + 1) only: the same pixels as
        ``birdseye(raw)[rows_px, first:last + 1]`` at a fraction of its cost."""
        self.undistorter.check(raw)
        m1, m2 = self._birdseye_maps
        rows = np.asarray(rows_px, int)
        c0, c1 = (0, self.size[0]) if cols_px is None else cols_px
        return cv2.remap(raw, m1[rows, c0:c1], m2[rows, c0:c1], cv2.INTER_LINEAR)

    def undistort(self, raw: np.ndarray) -> np.ndarray:
        """Return the undistorted frame."""
        return self.undistorter.undistort(raw)

    def binary(self, birdseye: np.ndarray, fallback: bool = False) -> np.ndarray:
        """Return the combined 0/255 lane-pixel mask of a bird's-eye image.

        ``fallback``: under ``ThresholdConfig.fallback_rule`` (the fallback searches' masks), or
        the rule itself when there is none.
        """
        tc = self.config.thresholds
        rule = tc.fallback_rule if fallback and tc.fallback_rule else None
        return thresholds.combine(birdseye, tc, clahe=self._clahe, rule=rule)

    @property
    def has_fallback_masks(self) -> bool:
        """Return True when the fallback searches threshold with another rule than the cheap one."""
        tc = self.config.thresholds
        return bool(tc.fallback_rule) and tc.fallback_rule.replace(" ", "") != tc.rule.replace(" ", "")

    def search(self, binary: np.ndarray, prior: tuple[LineFit, LineFit] | None = None,
               bases: tuple[float, float] | None = None, top_px: int = 0) -> LaneSearch:
        """Return the lane search of a mask: around ``prior`` fits when given, else sliding windows.

        The windows start from ``bases``, the lines' x (px) on the bottom row, when given (e.g.
        the tracked lane's), else from the histogram peaks nearest the car. ``top_px`` is the
        first row of the look-ahead (0: the whole view; ``search.lookahead_top_px``).
        """
        if prior is not None:
            return search_around(binary, prior[0], prior[1], self.config.search, top_px)
        return sliding_windows(binary, self.config.search, bases=bases, car_x=self.car_x_px,
                               top_px=top_px)

    def search_bands_px(self, search: LaneSearch) -> tuple[float, float]:
        """Return the width (px) of the band each line was searched in (``checks.search_bands_px``)."""
        return search_bands_px(search, self.size, self.config.search)

    def line_confidence(self, fit: LineFit) -> float:
        """Return the 0-1 confidence of a fitted line (``result.line_confidence``)."""
        return line_confidence(fit, self.size[1], self.config.search)

    def measure(self, left: LineFit, right: LineFit) -> LaneMeasurement:
        """Return curvature, radius, offset and lane width in metres for two fits."""
        p = self.perspective
        return measure(left, right, self.size[1], self.car_x_px, p.xm_per_px, p.ym_per_px)

    # ---- one frame ------------------------------------------------------------------------

    def band_binary(self, raw: np.ndarray, prior: tuple[LineFit, LineFit]) -> np.ndarray:
        """Return the lane-pixel mask of a RAW frame near the ``prior`` fits only (0 elsewhere).

        Inside the bands that ``search.search_around`` reads (``prior_margin_px`` either side of
        each found prior line) the mask equals ``binary(birdseye(raw))``. The view is cut into
        ``BAND_STRIPS`` horizontal strips; in each, the pieces of band, grown by the border
        ``thresholds.context_px`` asks for, are laid side by side (in x order, so a piece cut by
        the image's edge keeps that edge) and remapped and thresholded in one call each. On a
        tracked video frame that is about 40 % of the bird's-eye view. With
        ``thresholds.clahe`` on (CLAHE depends on the whole view) the whole view is thresholded
        and the bands are cut from it.
        """
        self.undistorter.check(raw)
        w, h = self.size
        margin = self.config.search.prior_margin_px
        cx, cy = self._context_px
        m1, m2 = self._birdseye_maps
        whole = self.binary(self.birdseye(raw)) if self._clahe is not None else None
        mask = np.zeros((h, w), np.uint8)
        edges = np.linspace(0, h, BAND_STRIPS + 1).round().astype(int)
        for y0, y1 in zip(edges[:-1], edges[1:]):
            rows = np.arange(y0, y1, dtype=np.float64)
            spans = []
            for fit in prior:
                if fit.found:
                    xs = fit.x_at(rows)
                    lo = max(0, int(np.floor(xs.min() - margin)))
                    hi = min(w, int(np.ceil(xs.max() + margin)) + 1)
                    if lo < hi:
                        spans.append([lo, hi])
            pieces: list[list[int]] = []  # [lo, hi] of band columns; the grown box is lo-cx..hi+cx
            for lo, hi in sorted(spans):
                if pieces and lo - cx <= pieces[-1][1] + cx:
                    pieces[-1][1] = max(pieces[-1][1], hi)
                else:
                    pieces.append([lo, hi])
            if not pieces:
                continue
            if whole is not None:
                for lo, hi in pieces:
                    mask[y0:y1, lo:hi] = whole[y0:y1, lo:hi]
                continue
            b0, b1 = max(0, y0 - cy), min(h, y1 + cy)
            boxes = [(max(0, lo - cx), min(w, hi + cx)) for lo, hi in pieces]
            # each box remapped into its place on the canvas (no stacked copy of the maps)
            grown = np.empty((b1 - b0, sum(a1 - a0 for a0, a1 in boxes), raw.shape[2]), np.uint8)
            x = 0
            for a0, a1 in boxes:
                cv2.remap(raw, m1[b0:b1, a0:a1], m2[b0:b1, a0:a1], cv2.INTER_LINEAR,
                          dst=grown[:, x:x + a1 - a0])
                x += a1 - a0
            cuts, x = [], 0  # where each piece's band lies in the grown canvas
            for (lo, hi), (a0, a1) in zip(pieces, boxes):
                cuts.append((slice(y0 - b0, y1 - b0), slice(x + lo - a0, x + hi - a0)))
                x += a1 - a0
            part = self._band_threshold(grown, cuts)
            x = 0
            for lo, hi in pieces:
                mask[y0:y1, lo:hi] = part[:, x:x + hi - lo]
                x += hi - lo
        return mask

    def _band_threshold(self, grown: np.ndarray, cuts: list[tuple[slice, slice]]) -> np.ndarray:
        """Return the combined mask of the band pieces ``cuts`` of a grown canvas, side by side.

        Masks that look beyond a pixel (Sobel, top-hat) are computed on the grown canvas and cut;
        colour masks only on the pieces themselves. With a closing or opening of the combined
        mask everything is computed on the grown canvas.
        """
        tconf = self.config.thresholds
        join = (lambda parts: parts[0]) if len(cuts) == 1 else np.hstack
        if tconf.open_px > 1 or tconf.close_px > 1:
            full = thresholds.combine(grown, tconf)
            return join([full[c] for c in cuts])
        channels = thresholds.Channels(grown)
        computed = {}
        for name in self._context_masks:
            m = thresholds.mask(channels, getattr(tconf, name))
            computed[name] = join([m[c] for c in cuts])
        pieces = channels.cut(cuts, join)  # the colour spaces those masks converted, cut too
        return thresholds.combine(pieces.rgb, tconf, computed, channels=pieces)

    def search_frame(self, raw: np.ndarray, prior: tuple[LineFit, LineFit] | None = None,
                     keep_images: bool = False, top_px: int = 0) -> tuple[LaneSearch, dict]:
        """Return the lane search of one RAW frame, unchecked, and the stage images kept.

        With a ``prior`` and no ``keep_images``, only the bands around the prior fits are
        remapped and thresholded (``band_binary``); the search sees the same pixels either way.
        ``images`` holds "birdseye" and "binary" when the whole view was thresholded (always
        without a usable prior, or with ``keep_images``). ``top_px``: the look-ahead (``search``).
        """
        if prior is not None and not keep_images and (prior[0].found or prior[1].found):
            return self.search(self.band_binary(raw, prior), prior, top_px=top_px), {}
        bird = self.birdseye(raw)
        mask = self.binary(bird)
        return self.search(mask, prior, top_px=top_px), {"birdseye": bird, "binary": mask}

    def check(self, search: LaneSearch, turn_back: bool = False) -> LaneCheck:
        """Return the plausibility checks (``checks.check_lane``, ``config.checks``) of a search's
        fits; with ``turn_back``, each line's hook beyond its pixels too (``checks.turn_back_problem``)."""
        p = self.perspective
        return check_lane(search.left, search.right, self.search_bands_px(search),
                          self.size[1], p.xm_per_px, p.ym_per_px, self.config.checks,
                          search.top_px, self.size[0] if turn_back else None)

    def detect(self, raw: np.ndarray, prior: tuple[LineFit, LineFit] | None = None,
               keep_images: bool = False) -> FrameResult:
        """Return the lane found in one RAW frame, checked, without drawing (the per-frame hot path).

        The fits of ``search_frame`` go through ``result``: a lane that fails the plausibility
        checks is not found, and is kept apart in ``rejected``. Without a ``prior``, a lane of
        the whole view that fails is looked for again: on the fallback masks
        (``ThresholdConfig.fallback_rule``) in the whole view, then in shorter views
        (``short_view_search``), then from other histogram peaks (``robust_search``, when
        ``candidates`` > 1), then, when one line was found and the other side has no paint
        line, with the asphalt edge on that side (``edge_search``).
        """
        search, images = self.search_frame(raw, prior, keep_images)
        result = self.result(search, images if keep_images else {})
        if result.found or prior is not None:
            return result
        mask = images["binary"]
        retry = None
        if self.has_fallback_masks:
            mask = self.binary(images["birdseye"], fallback=True)
            whole = self.search(mask)
            if whole.left.found and whole.right.found and self.check(whole).ok:
                retry = whole
        if retry is None:
            retry = self.short_view_search(mask)
        if retry is None and self.config.search.candidates > 1:
            retry = self.robust_search(mask, search)
        if retry is None:
            retry = self.edge_search(images["birdseye"], search)
        if retry is None:
            return result
        if keep_images:
            images["binary"] = mask  # the views show the mask the lane came from
        return self.result(retry, images if keep_images else {})

    def lines_view(self) -> tuple[LinesView, tuple[np.ndarray, np.ndarray], thresholds.ThresholdConfig]:
        """Return the lines view (``perspective.LinesView`` of the ego view), its raw-frame remap
        maps and the thresholds rescaled to it (``thresholds.scaled``); made once, when first asked
        (with the view's transform back to the raw frame, ``_lines_to_raw``, and the view's pixels
        that see the frame away from its edge, ``_lines_seen``)."""
        if self._lines_view is None:
            lc = self.config.lines
            view = LinesView(self.perspective, lc.view_half_width_m, lc.view_xm_per_px, lc.view_ahead_m,
                             lc.view_ym_per_px)
            raw_to_view = self.lens.inverse + view
            tconf = thresholds.scaled(self.config.thresholds, view.scale_from_ego)
            maps = raw_to_view.remap_maps(view.size)
            self._lines_view = (view, maps, tconf)
            self._lines_to_raw = raw_to_view.inverse
            # where the view sees the frame, away from its edge: the edge of the frame is no paint
            seen = cv2.remap(np.full(self.size[::-1], 255, np.uint8), maps[0], maps[1], cv2.INTER_NEAREST,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=0)
            edge = 2 * tconf.line_tophat.width_px + 1
            self._lines_seen = cv2.erode(seen, np.ones((3, edge), np.uint8))
        return self._lines_view

    def lines_row_weights(self) -> np.ndarray:
        """Return how much each row of the lines view counts in the vote (``LinesConfig``:
        ``row_weight_full``, ``row_weight_power``): the raw frame's rows it sees, over
        ``row_weight_full`` and at most 1, to the power ``row_weight_power``. A far row of the
        view is stretched from a fraction of one raw row, so a speck there would otherwise vote
        along metres of road. Made once, with the view."""
        if self._lines_weights is None:
            view, _, _ = self.lines_view()
            lc = self.config.lines
            rows = np.arange(view.size[1], dtype=np.float64)
            pts, ok = self._lines_to_raw.checked(np.column_stack([np.full(len(rows), view.car_x_px), rows]))
            seen = np.where(ok, np.abs(np.gradient(pts[:, 1])), 0.0)
            self._lines_weights = np.clip(seen / lc.row_weight_full, 0.0, 1.0) ** lc.row_weight_power
        return self._lines_weights

    def detect_lines(self, raw: np.ndarray, config: LinesConfig | None = None,
                     keep_images: bool = False, ego: bool = True) -> LinesResult:
        """Return every lane line seen in one RAW frame, left to right, and the ego lane.

        The ego lane is ``detect``'s (what the overlay, curvature and offset use). The lines are
        looked for in the lines view (``lines_view``: by default 28 m across and 150 m ahead), masked
        by the rule of the thresholds rescaled to it (not at the edge of the frame), by
        ``lines.trace.find_lines`` or ``lines.vote.vote_lines`` (``LinesConfig.method``), and mapped back to
        the raw frame over the span where each is seen (``result.image_line``). ``keep_images``
        keeps the view ("lines_birdseye") and its mask ("lines_binary"). ``config``: the search's
        parameters (default: ``PipelineConfig.lines``, so ``--config``/``--set lines.KEY=V``
        tune ``predict``). ``ego=False`` skips
        ``detect`` (a third of the time) and leaves ``LinesResult.ego`` None.
        """
        config = self.config.lines if config is None else config
        ego_result = self.detect(raw) if ego else None
        view, maps, tconf = self.lines_view()
        bird = cv2.remap(raw, maps[0], maps[1], cv2.INTER_LINEAR)
        mask = thresholds.combine(bird, tconf)
        if config.tophat_low and tconf.line_tophat.enabled:  # far paint: blurred, dimmer
            far = replace(tconf.line_tophat, low=min(config.tophat_low, tconf.line_tophat.low))
            low = thresholds.mask(bird, far)
            top = max(0, int(view.bottom_px - config.near_m / view.ym_per_px))
            half = int(config.near_half_width_m / view.xm_per_px)
            cx = int(view.car_x_px)
            low[top:, max(0, cx - half):cx + half] = 0
            mask = cv2.bitwise_or(mask, low)
        wide = 2 * tconf.line_tophat.width_px  # paint is narrow: not a verge or a field beside the road
        mask = cv2.subtract(mask, thresholds.morph(mask, "open", wide, 1))
        mask = cv2.bitwise_and(mask, self._lines_seen)
        to_raw = functools.partial(image_line, view_to_raw=self._lines_to_raw, car_x_px=view.car_x_px,
                                   bottom_px=view.bottom_px, xm_per_px=view.xm_per_px)
        refused: tuple = ()
        if config.method == "vote":
            weights = self.lines_row_weights() if config.row_weight_power > 0 else None
            weighed = vote.vote_candidates(mask, config, view.xm_per_px, view.ym_per_px, view.car_x_px, weights)
            found = vote.reported(weighed, config, mask.shape[0], view.ym_per_px)
            refused = tuple((to_raw(c.line), c.refused) for c in weighed if c.refused and c.line is not None)
        else:
            found = find_lines(mask, config, view.xm_per_px, view.ym_per_px)
        images = {"lines_birdseye": bird, "lines_binary": mask} if keep_images else {}
        return LinesResult(tuple(to_raw(line) for line in found), ego_result, images, refused)

    def short_view_search(self, binary: np.ndarray) -> LaneSearch | None:
        """Return the first search in a shorter look-ahead whose lane passes the checks, or None.

        For a frame without a track whose whole view failed its checks: sliding windows over the
        lower ``SearchConfig.short_views`` shares of the view in turn (a tight bend's lane stays
        in a shorter view; ``search.lookahead_top_px``). Its search's ``top_px`` says which.
        """
        h = self.size[1]
        for share in self.config.search.short_views:
            search = self.search(binary, top_px=int(round(h * (1.0 - share))))
            if search.left.found and search.right.found and self.check(search).ok:
                return search
        return None

    def robust_search(self, binary: np.ndarray, first: LaneSearch) -> LaneSearch | None:
        """Return the first search from other histogram peaks whose lane passes the checks, or None.

        The robust path (``SearchConfig.candidates``), for a frame whose search from the
        strongest peaks failed its checks (a seam, a kerb or a shadow edge took a line): sliding
        windows from each pair of the ``candidates`` strongest peaks on each side
        (``search.candidate_bases``), the pairs with the stronger peaks first, skipping the pair
        already tried. Its search's ``method`` is "robust".
        """
        sc = self.config.search
        hist = histogram(binary, sc.histogram_fraction)
        lefts, rights = candidate_bases(hist, self.car_x_px, sc.candidates, sc.margin_px)
        pairs = sorted(((l, r) for l in lefts for r in rights),
                       key=lambda p: -(int(hist[int(p[0])]) + int(hist[int(p[1])])))
        for bases in pairs:
            if first.bases_px == bases:
                continue
            search = sliding_windows(binary, sc, bases=bases, car_x=self.car_x_px)
            if self.check(search).ok and search.left.found and search.right.found:
                return replace(search, method="robust")
        return None

    def edge_search(self, bird: np.ndarray, search: LaneSearch, guide_px=None,
                    range_m: tuple[float, float] | None = None,
                    shoulder_m: float | None = None) -> LaneSearch | None:
        """Return ``search`` with its missing line replaced by the asphalt edge on that side,
        when the lane then passes the checks; else None.

        Only for a search that found one line, which passes its own check, and no paint at all
        on the other side (its fit not found): a painted line that is seen is never replaced.
        The edge (``roads.edge.road_edge``, ``PipelineConfig.edge``, read in the bird's-eye image
        ``bird``, between ``range_m`` from ``guide_px``: by default a lane's width from the found
        line) is then checked with the found line as a lane (``check``: width within the
        road's range, parallel, equally curved) over the rows where the edge is seen (the
        search's look-ahead, ``top_px``, ends at its farthest point: its fit is not extrapolated
        beyond); its search's ``edge`` flags the side. With ``shoulder_m`` (a painted line faded
        out, ``roads.tracked.Shoulder``) the line is placed that far inside the edge, along its
        normal (``fit.offset_line``) where the edge is seen, joined beyond it to ``guide_px``
        (one second-order fit to both), the look-ahead and the other line kept; the search's
        ``shoulder`` flags the side instead, and it is returned unchecked: the tracker checks it
        against its track (the lane's width ahead, which a grade changes in the flat view).
        """
        cfg = self.config.edge
        if not cfg.enabled or search.left.found == search.right.found:
            return None
        side, other = ("right", search.left) if search.left.found else ("left", search.right)
        first = self.check(search)
        if first.left or first.right:
            return None
        p = self.perspective
        fit, _ = road_edge(bird, other, side, p.xm_per_px, p.ym_per_px, self.config.checks,
                           cfg, search.top_px, guide_px, range_m)
        if not fit.found:
            return None
        h = self.size[1]
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
                                self.size[1], self.config.search, "no lane pixels")
            if not refit.found:
                return None
            fits["left" if side == "right" else "right"] = refit
        found = replace(search, **fits, edge=(side == "left", side == "right"), top_px=top)
        return found if self.check(found).ok else None

    def result(self, search: LaneSearch, images: dict | None = None) -> FrameResult:
        """Return the FrameResult of a search: its fits if they pass ``check``, else not found.

        A line that fails its own check, or both lines when the pair fails, become not-found
        fits whose ``reason`` is the failed check; the measurement is then NaN and the search's
        fits with what they measured are kept in ``rejected``. Confidences are those of the
        fits reported (0 for a rejected line).
        """
        check = self.check(search)
        left, right, rejected = search.left, search.right, None
        if not check.ok:
            left = _rejected(left, check.left or check.pair)
            right = _rejected(right, check.right or check.pair)
            rejected = Rejected(search.left, search.right, self.measure(search.left, search.right),
                                check.reason)
        reasons = [f"{side} line not found ({fit.reason})"
                   for side, fit in (("left", search.left), ("right", search.right)) if not fit.found]
        if check.reason:
            reasons.append(check.reason)
        sources = tuple(line_source(search, i) if fit.found else "" for i, fit in enumerate((left, right)))
        return FrameResult(left, right, self.measure(left, right), search.method,
                           self.line_confidence(left), self.line_confidence(right),
                           "; ".join(reasons), search, images if images is not None else {}, rejected,
                           sources)

    def process(self, raw: np.ndarray, keep_images: bool = False) -> FrameResult:
        """Return the lane in one RAW frame with the annotated frame in ``images["result"]``.

        With ``keep_images`` the stage images (undistorted, birdseye, binary, search) are kept too.
        """
        result = self.detect(raw, keep_images=keep_images)
        if keep_images:
            self.draw_views(result, raw)
        else:
            result.images["result"] = self.annotate(self.undistort(raw), result)
        return result

    def annotate(self, frame: np.ndarray, result: FrameResult, raw: bool = False) -> np.ndarray:
        """Return the frame with the lane, the lines and the measurements drawn.

        ``frame`` is the undistorted frame, or with ``raw`` the RAW frame: the lane is then mapped
        through the lens model onto it (no full-frame undistortion needed). The lines are drawn
        only from the row where they hold (``checks.holds_from_px``): not where a fit leaves the
        view, hooks back beyond its paint or meets the other line.
        """
        to_frame = self.birdseye_to_raw if raw else self.perspective.inverse
        held = result.method == "hold"  # held from earlier frames: drawn in the held colour
        top = holds_from_px(result.left, result.right, self.size[1], self.size[0],
                            self.perspective.xm_per_px, self.config.checks)
        out = draw.lane_overlay(frame, result.left.coeffs_px, result.right.coeffs_px, to_frame,
                                self.config.draw, self.size[1], held=held, top_px=top)
        edges = tuple(side for side, src in zip(("left", "right"), result.sources) if src == "edge")
        return draw.put_lines(out, draw.measurement_lines(result.radius_m, result.offset_m,
                                                          result.lane_width_m, result.found,
                                                          result.reason, held, edges), self.config.draw)

    def draw_views(self, result: FrameResult, raw: np.ndarray) -> dict:
        """Return ``result.images`` with the drawn views added: undistorted, result and search.

        ``result`` kept its stage images (``detect``, ``LaneTracker.update`` or ``process`` with
        ``keep_images=True``) and ``raw`` is its RAW frame. Views already there are kept; the
        search view needs the kept "binary". The one place the debug views are drawn, for
        ``process``, ``debug_composite`` and the video's ``--debug``.
        """
        im = result.images
        if "undistorted" not in im:
            im["undistorted"] = self.undistort(raw)
        if "result" not in im:
            im["result"] = self.annotate(im["undistorted"], result)
        if "search" not in im and "binary" in im and result.search is not None:
            im["search"] = draw.search_view(im["binary"], result.search, self.config.draw,
                                            self.config.search.prior_margin_px)
        return im

    def debug_composite(self, result: FrameResult, raw: np.ndarray | None = None) -> np.ndarray:
        """Return the 2x2 debug view (undistorted, binary, search, result) of a kept-images result.

        ``result`` comes from ``process(frame, keep_images=True)``; or from ``detect`` or
        ``LaneTracker.update`` with ``keep_images=True``, passed with its RAW frame ``raw``, from
        which the missing views (undistorted, search, result) are drawn here (``draw_views``).
        """
        im = result.images
        if raw is not None and "binary" in im:
            self.draw_views(result, raw)
        if not all(k in im for k in ("undistorted", "binary", "search", "result")):
            raise InputError("debug_composite needs a result from process(frame, keep_images=True), "
                             "or a kept-images result (detect, LaneTracker.update) and its raw frame")
        return draw.composite([("undistorted", im["undistorted"]), ("binary (bird's-eye)", im["binary"]),
                               ("search and fits", im["search"]), ("result", im["result"])], self.size)


def _rejected(fit: LineFit, why: str) -> LineFit:
    """Return ``fit`` unchanged when ``why`` is empty, else a not-found fit saying ``why``."""
    if not why or not fit.found:
        return fit
    return LineFit(None, fit.n_pixels, fit.span_px, why, fit.scatter_px)


def pipeline_for(image: np.ndarray, config: PipelineConfig = PipelineConfig(),
                 calibration: Calibration | None = None) -> LanePipeline:
    """Return a LanePipeline for frames of ``image``'s size."""
    return LanePipeline(config, calibration, size=(image.shape[1], image.shape[0]))
