"""``LanePipeline``: the advanced lane-finding pipeline wired from one ``PipelineConfig``.

One frame: raw RGB -> bird's-eye view (one remap: undistort + warp) -> thresholds -> lane-pixel
search -> fits -> plausibility checks (``params.LaneChecks``, as the tracker's) -> measurements
-> overlay on the undistorted frame; ``detect_lines`` finds every lane line in a wider, longer
view, for the benchmarks. A lane that fails the checks is not found; what it measured is kept in
``FrameResult.rejected``. The notebooks, tuners and CLI all use this object, so a slider tunes
exactly what a video run uses. Runs over folders and videos are ``batch.process_images`` and
``batch.process_video``.
"""
from __future__ import annotations

import cv2
import numpy as np

from . import draw, thresholds
from .bands import Bands
from .camera import Calibration, Undistorter
from .checks import LaneCheck, check_lane, holds_from_px, search_bands_px
from .config import PipelineConfig
from .errors import InputError
from .thresholds import Made
from .fit import measure
from .lines.detect import LinesSetup, find_every_line, make_setup, row_weights
from .lines.result import LinesResult
from .lines.view import LinesView
from .params import LinesConfig
from .perspective import Perspective, scaled
from .records import LaneMeasurement, LaneSearch, LineFit, line_source
from .result import FrameResult, Rejected, line_confidence
from .roads.proposers import DETECT, detect_again
from .search import search_around, sliding_windows


# the hard-road proposers a single image's second look asks (``roads.proposers.detect_again``)
DETECT_PROPOSERS = DETECT


class LanePipeline:
    """Find the lane in frames of one size with one configuration and (optional) calibration.

    Everything that depends only on the configuration (remap maps, matrices, the car's position in
    the view) is computed once, here. A pipeline pickles as (config, calibration, size) and is
    rebuilt on unpickling, so it can be sent to Dask workers.

    Parameters
    ----------
    config : all parameters; its perspective points are scaled if ``size`` differs from theirs.
    calibration : the camera's calibration, or None for an undistorted (or uncalibrated) camera.
    size : (width, height) of the frames; defaults to the perspective's ``size_px``.

    Examples
    --------
    >>> from lanelib import data, evaluate, io
    >>> camera = evaluate.calibration_from_truth(data.bundled("test_images"))  # the true camera
    >>> pipe = LanePipeline(calibration=camera, size=camera.image_size)
    >>> result = pipe.detect(io.read_image(data.bundled("test_images") / "straight_1.jpg"))
    >>> result.found, round(float(result.lane_width_m), 1), result.method
    (True, 3.7, 'windows')
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
        self._clahe = thresholds.make_clahe(config.thresholds, self.size)  # None when off
        self._bands = Bands(config.thresholds, config.search.prior_margin_px, self._birdseye_maps, self.size)
        self.car_x_px = self.perspective.car_x_px
        self._lines: LinesSetup | None = None  # the lines view, made by the first detect_lines
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
        """Return the bird's-eye rows ``rows_px`` (int) of a RAW frame, (n, W, 3), or only their columns
        ``cols_px`` = (first, last + 1): ``birdseye(raw)[rows_px, first:last + 1]`` at a fraction of
        its cost.
        """
        self.undistorter.check(raw)
        m1, m2 = self._birdseye_maps
        rows = np.asarray(rows_px, int)
        c0, c1 = (0, self.size[0]) if cols_px is None else cols_px
        return cv2.remap(raw, m1[rows, c0:c1], m2[rows, c0:c1], cv2.INTER_LINEAR)

    def undistort(self, raw: np.ndarray) -> np.ndarray:
        """Return the undistorted frame."""
        return self.undistorter.undistort(raw)

    def binary(self, birdseye: np.ndarray, fallback: bool = False, made: Made | None = None) -> np.ndarray:
        """Return the combined 0/255 lane-pixel mask of a bird's-eye image; with ``fallback``, under
        ``ThresholdConfig.fallback_rule`` if any. ``made``: this image's masks (``thresholds.combine``).
        """
        tc = self.config.thresholds
        rule = tc.fallback_rule if fallback and tc.fallback_rule else None
        return thresholds.combine(birdseye, tc, clahe=self._clahe, rule=rule, made=made)

    @property
    def has_fallback_masks(self) -> bool:
        """Return True when the fallback searches threshold with another rule than the cheap one."""
        tc = self.config.thresholds
        return bool(tc.fallback_rule) and tc.fallback_rule.replace(" ", "") != tc.rule.replace(" ", "")

    def search(self, binary: np.ndarray, prior: tuple[LineFit, LineFit] | None = None,
               bases: tuple[float, float] | None = None, top_px: int = 0, pixels=None, made=None) -> LaneSearch:
        """Return the lane search of a mask: around ``prior`` fits when given, else sliding windows
        starting from ``bases`` (the lines' x, px, on the bottom row, e.g. the track's) or the
        histogram peaks nearest the car. ``top_px``: the look-ahead's first row (0: the whole view).
        ``pixels``: the mask's ``lane_pixels``; ``made``: the image's ``Made``, whose line fits it reuses.
        """
        if prior is not None:
            return search_around(binary, prior[0], prior[1], self.config.search, top_px)
        return sliding_windows(binary, self.config.search, bases=bases, car_x=self.car_x_px,
                               top_px=top_px, pixels=pixels, fits=None if made is None else made.fits)

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
        """Return the lane-pixel mask of a RAW frame near the ``prior`` fits only (0 elsewhere), equal to
        ``binary(birdseye(raw))`` inside the bands ``search.search_around`` reads (``bands.Bands.mask``).
        With CLAHE on (it depends on the whole view) the whole view is thresholded and cut.
        """
        self.undistorter.check(raw)
        whole = self.binary(self.birdseye(raw)) if self._clahe is not None else None
        return self._bands.mask(raw, prior, whole)

    def search_frame(self, raw: np.ndarray, prior: tuple[LineFit, LineFit] | None = None,
                     keep_images: bool = False, top_px: int = 0, made: Made | None = None
                     ) -> tuple[LaneSearch, dict]:
        """Return the lane search of one RAW frame, unchecked, and the stage images kept.

        With a ``prior`` and no ``keep_images`` only the bands around the prior fits are remapped and
        thresholded (``band_binary``): the same pixels for the search. ``images`` holds "birdseye" and
        "binary" when the whole view was thresholded. ``top_px``: the look-ahead (``search``).
        ``made``: gets the whole view's masks, colour spaces (for a second rule, ``binary``) and fits.
        """
        if prior is not None and not keep_images and (prior[0].found or prior[1].found):
            return self.search(self.band_binary(raw, prior), prior, top_px=top_px), {}
        bird = self.birdseye(raw)
        mask = self.binary(bird, made=made)
        return self.search(mask, prior, top_px=top_px, made=made), {"birdseye": bird, "binary": mask}

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

        The fits of ``search_frame`` go through ``result``: a lane that fails the checks is not found
        and kept in ``rejected``. Without a ``prior``, a failed lane is looked for again by the
        proposers that need no track (``DETECT_PROPOSERS``, ``roads.proposers.detect_again``): fallback
        masks, shorter views, other histogram peaks, the asphalt edge. The first pair to pass is taken.
        """
        made = Made()  # the masks and fits made, which the fallback rule's mask and searches reuse
        search, images = self.search_frame(raw, prior, keep_images, made=made)
        result = self.result(search, images if keep_images else {})
        if result.found or prior is not None:
            return result
        best = detect_again(self, raw, images, search, made, keep_images)
        return result if best is search else self.result(best, images if keep_images else {})

    def lines_view(self) -> tuple[LinesView, tuple[np.ndarray, np.ndarray], thresholds.ThresholdConfig]:
        """Return the lines view (``lines.view.LinesView`` of the ego view), its raw-frame remap maps and
        the thresholds rescaled to it, made once when first asked (``lines.detect.make_setup``, a
        ``lines.detect.LinesSetup``, with its transform back and its pixels away from the frame's edge).
        """
        if self._lines is None:
            self._lines = make_setup(self.perspective, self.lens, self.size, self.config.lines,
                                     self.config.thresholds)
        return self._lines.view, self._lines.maps, self._lines.tconf

    def lines_row_weights(self) -> np.ndarray:
        """Return how much each row of the lines view counts in the vote
        (``lines.detect.row_weights``); made once, with the view."""
        if self._lines_weights is None:
            self.lines_view()
            self._lines_weights = row_weights(self._lines, self.config.lines)
        return self._lines_weights

    def detect_lines(self, raw: np.ndarray, config: LinesConfig | None = None,
                     keep_images: bool = False, ego: bool = True) -> LinesResult:
        """Return every lane line seen in one RAW frame, left to right, and the ego lane.

        The ego lane is ``detect``'s (the overlay, curvature and offset); the lines are found in the
        lines view (``lines_view``, by default 28 m across and 150 m ahead) by
        ``lines.detect.find_every_line``. ``keep_images`` keeps "lines_birdseye" and "lines_binary".
        ``config``: the search's parameters (default ``PipelineConfig.lines``, so ``--set
        lines.KEY=V`` tunes ``predict``). ``ego=False`` skips ``detect`` (a third of the time) and
        leaves ``LinesResult.ego`` None.
        """
        config = self.config.lines if config is None else config
        ego_result = self.detect(raw) if ego else None
        self.lines_view()
        weights = self.lines_row_weights() if config.method == "vote" and config.row_weight_power > 0 else None
        lines, images, refused = find_every_line(raw, self._lines, config, weights)
        return LinesResult(lines, ego_result, images if keep_images else {}, refused)

    def result(self, search: LaneSearch, images: dict | None = None) -> FrameResult:
        """Return the FrameResult of a search: its fits if they pass ``check``, else not found.

        A line failing its own check, or both when the pair fails, becomes a not-found fit whose
        ``reason`` is the check; the measurements are then NaN and the search's fits and measurements
        are kept in ``rejected``. Confidences are those of the fits reported (0 when rejected).
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
        """Return the lane in one RAW frame with the annotated frame in ``images["result"]``; with
        ``keep_images``, the stage images (undistorted, birdseye, binary, search) too.
        """
        result = self.detect(raw, keep_images=keep_images)
        if keep_images:
            self.draw_views(result, raw)
        else:
            result.images["result"] = self.annotate(self.undistort(raw), result)
        return result

    def annotate(self, frame: np.ndarray, result: FrameResult, raw: bool = False) -> np.ndarray:
        """Return the frame with the lane, the lines and the measurements drawn.

        ``frame`` is the undistorted frame, or with ``raw`` the RAW one: the lane is then mapped onto
        it through the lens model. Lines are drawn only from where they hold (``checks.holds_from_px``).
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
        """Return ``result.images`` with the undistorted, result and search views added (those there are
        kept), drawn from ``raw``, the RAW frame of a result that kept its stage images; the search
        view needs "binary". The one place the debug views are drawn (``process``,
        ``debug_composite``, the video's ``--debug``).
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
        """Return the 2x2 debug view (undistorted, binary, search, result) of a kept-images result, the
        missing views drawn from its RAW frame ``raw`` (``draw_views``).
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
