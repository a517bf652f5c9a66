"""The parameter records beyond one clean frame: the asphalt edge, every line in view, the tracker.

``EdgeConfig`` (``roads.edge.road_edge``), ``LinesConfig`` (``lines.trace.find_lines``,
``lines.vote.vote_lines``, ``pipeline.LanePipeline.detect_lines``) and ``TrackerConfig``
(``tracking.LaneTracker``, whose loop ``tracking``'s module docstring describes). Frozen
dataclasses with units in their field names; ``__post_init__`` refuses a value out of range with a
``ConfigError`` naming the key. A function a docstring names without its module is its stage's
(``roads.edge.road_edge``, ``fit.fit_line``, ...).
"""
from __future__ import annotations

from dataclasses import dataclass

from ..errors import ConfigError


@dataclass(frozen=True)
class EdgeConfig:
    """Parameters of the road-edge candidate (``road_edge``): the unpainted asphalt edge of a
    side with no paint line, where the grey road surface meets a verge of another kind.

    Parameters
    ----------
    enabled : look for the asphalt edge where a side has no paint line (the lane's other line
        found); off (the default; the ``hard-roads`` and ``country`` presets switch it on): a
        side without paint gives no line.
    scale : the bird's-eye view is shrunk by this factor each way before the edge is looked for
        (the edge is a wide step, not a thin stroke; 4: a 320 x 180 grid in the default view).
    step_m : width (m) of the window inside a candidate edge whose verge score is compared with
        that of the window beyond it, twice as wide (the verge must go on beyond the edge: a
        seam, a shadow line or a yellow line is narrow).
    min_saturation_step : the verge's saturation (HSV S, 0-1) above the road surface's (its
        median between the lines) at which a pixel counts fully as verge (grass, dirt: colour).
    min_texture_ratio : 0 (off), or the rise of the verge's grain (local std / mean of V) over
        the road surface's, as a ratio less 1, at which a pixel counts fully as verge (gravel).
        Off by default: the bird's-eye view's grain changes with its blur ahead and under
        dappled shade as much as at a verge, so a grain step alone puts edge points inside the
        lane.
    max_road_saturation : a row whose road surface (the median between the lines) is more
        saturated than this is not grey asphalt there (the view has left the road: grass in a
        hairpin's inside); it gives no edge point.
    min_step : least rise of the mean verge score (0-1) from the inner window to the outer one.
    max_inner : largest mean verge score of the inner (road) window; min_outer : least of the outer.
    min_points : least rows (of the shrunk grid) with an edge for a line; min_span_fraction :
        least share of the look-ahead's rows they span.
    trim_outliers_pct : share (%) of the edge points kept for the fit (``fit_line``'s trim).
    trace_margin_m : 0 (off), or how far (m along the row) from the straight line through the
        last edge points the next row's edge is looked for (``road_edge``'s trace): the edge is
        followed from the car over the view where it is seen, not searched at a lane's width
        from the other line, which the flat view changes with distance on a pitched road.
    trace_gap_m : the trace ends after this much road (m) without an edge point.
    max_shoulder_m : how far (m) beyond a painted line its asphalt edge is looked for, to
        measure the shoulder between them (``roads.proposers.Shoulder``).
    """

    enabled: bool = False
    scale: int = 4
    step_m: float = 0.4
    min_saturation_step: float = 0.15
    min_texture_ratio: float = 0.0
    min_step: float = 0.5
    max_inner: float = 0.3
    min_outer: float = 0.7
    max_road_saturation: float = 0.2
    min_points: int = 30
    min_span_fraction: float = 0.3
    trim_outliers_pct: float = 80.0
    trace_margin_m: float = 0.0
    trace_gap_m: float = 2.0
    max_shoulder_m: float = 1.5

    def __post_init__(self):
        if self.trace_margin_m < 0 or self.trace_gap_m <= 0 or self.max_shoulder_m <= 0:
            raise ConfigError("edge: need trace_margin_m >= 0 (0: off), trace_gap_m > 0 and max_shoulder_m > 0")
        if self.scale < 1 or self.step_m <= 0 or self.min_points < 3 or self.min_texture_ratio < 0:
            raise ConfigError("edge: need scale >= 1, step_m > 0, min_points >= 3 and min_texture_ratio >= 0")
        if not 0 < self.trim_outliers_pct <= 100:
            raise ConfigError(f"edge: trim_outliers_pct {self.trim_outliers_pct} must lie in (0, 100]")


@dataclass(frozen=True)
class LinesConfig:
    """Parameters of the multi-line search (``find_lines``), in metres of road.

    Parameters
    ----------
    lane_width_m : the usual distance of two neighbour lines.
    min_gap_fraction : two lines nearer than this share of ``lane_width_m`` are one line (their
        peaks are not traced twice, and two traces that close are merged).
    band_m : the height of each horizontal band whose column histogram gives the start of lines;
        ``bands`` of them from the view's bottom up (a neighbour line enters the image only some
        way ahead, and a line far out is curved: one histogram of the whole view smears it).
    window_m : the height of a sliding window along the road.
    margin_m : half the width of a window across the road; ``grow_margin_m`` is added after each
        empty window (back to ``margin_m`` after one with pixels).
    max_empty_windows : a trace stops after this many empty windows in a row (the line ended or
        left the image); dash gaps are shorter.
    min_window_pixels : pixels a window needs to recentre the trace.
    max_slope : the steepest a trace follows a line across the road (m across per m along; a
        line 150 m ahead on a 500 m bend runs at 0.3).
    min_peak_m : a histogram peak needs this much paint (m of line along the road, per column).
    min_line_pixels, min_span_m : a traced line needs this many pixels spanning this far.
    curved_span_m : a line spanning less is fitted straight (a = 0).
    max_scatter_m : a line whose pixels lie further from its fit (a robust RMS: 1.4826 times
        the median distance, m across) is not paint (the ragged edge of a verge or a field).
    tophat_low : the lines view adds to its mask the pixels of ``ThresholdConfig.line_tophat``
        at this lower level (0: off): far paint is blurred and dimmer than the colour masks'
        floors, but still brighter than the road beside it. Not within ``near_m`` of the ego
        view's bottom row and ``near_half_width_m`` of the car's centre line: there the colour
        masks see the paint and the road's texture would pass the lower level (further out the
        lines are seen at a grazing angle, thin and dim, and the texture is blurred).
    extend_m : how far (m along the road) a line is taken to go on beyond its last pixels at
        either end, within the view: a dashed line is seen through a gap (9 m on a highway).
    view_half_width_m, view_ahead_m, view_xm_per_px, view_ym_per_px : the lines view
        (``lines.view.LinesView``): the road seen either side of the car's centre line and
        ahead of the ego view's bottom row, and its metres per pixel across and along the road.
        A camera that sees the road only some tens of metres ahead (a low camera in traffic)
        needs a shorter, finer view than a highway camera.
    method : how lines are found in the view: "trace" (``find_lines``: histogram peaks, then
        windows that follow each line) or "vote" (``lines.vote.vote_lines``: narrow runs of
        paint vote for straight lines, so a line seen in pieces between vehicles or as sparse
        dashes is one line).
    max_paint_width_m, vote_tolerance_m, max_lines : the vote's widest run of paint, how far
        (across) a run may lie from a line to vote for it, and how many lines it reports.
    heading_spread : the most (m across per m along) a line's slope in the view may differ from
        the common heading of the lines in it (lane lines are parallel).
    min_offset_m, near_paint_m : a line nearer than ``min_offset_m`` to the car's centre line on
        the view's bottom row (0: off) is reported only when its paint reaches within
        ``near_paint_m`` of that row (``lines.vote``): a lane line runs under the car only during a
        lane change, and then its paint is seen beside the car, while the edge of a vehicle ahead
        looks like a line there in the view but starts where the vehicle is.
    follow_bends : a voted line is also traced by windows (``window_m``, ``max_empty_windows``)
        from its paint near the car, and the traced paint is kept where it fits tighter
        (``lines.vote``): a bend of the road or the lens bends a line away from a straight one.
    seen_window_m : a voted line is seen in the windows of this height along the road where at
        least half of the runs near it hug its fit (within a quarter of ``vote_tolerance_m``,
        twice the share of runs spread evenly: texture, a vehicle ahead); its span, which the
        checks read (``min_span_m``, ``near_paint_m``) and from which it is extended, runs over
        those windows (``lines.vote.seen_span``; 0: over every run near it). Shorter than a dash,
        so a window on a dash is all paint.
    follow_ahead_m : the lines view goes on this far beyond ``view_ahead_m`` (0: off); the lines
        found within ``view_ahead_m`` are followed by windows (``window_m``, ``max_empty_windows``)
        along their paint into it, and each is reported as far as its paint goes
        (``lines.vote.follow_ahead``). A line is labelled as far as it is seen, beyond the road
        where vehicles and their shadows crowd the search.
    row_weight_power, row_weight_full : how much a row of the lines view counts in the vote
        (``LanePipeline.lines_row_weights``; power 0: every row alike): the raw frame's rows it
        sees over ``row_weight_full``, at most 1, to this power. Far rows are stretched from a
        fraction of a raw row, where vehicles and their shadows crowd the road.
    headings : how many common headings the vote tries (the slopes with the most strong votes,
        ``heading_spread`` apart); it keeps the one whose reported lines hold the most paint
        (junk beside the road can outvote the paint for a heading, but not pass as lines).
    contrast_full : a run votes by how clearly it is brighter than the road beside it
        (``lines.detect.paint_strength``; 0: every run alike): its top-hat over this multiple
        of the lowest top-hat floor of the lines view's mask, between one half and 1. Paint
        stands out from the road; a concrete seam, a barrier's foot or a vehicle's edge beside a
        line passes the floor but barely, and outvotes the paint less.
    refused_clear_crossings : a weighed line clears the vote cells of the lines that cross it
        in the view (they would be the same paint counted twice); False: a refused line (too
        scattered, a vehicle's edge) clears only its own cells, so a lane line it crosses is
        still weighed. The ``culane`` preset turns it off: in stop-and-go traffic a vehicle's
        edge refused under the car crosses the ego lines ahead.
    refine_points_px : ``predict`` moves the bird's-eye points of each sequence (one camera)
        to where the lines it finds meet, when that is further than this many px (vertically;
        twice as far sideways) from where the points' sides meet (``batch.refine``; 0: off): a
        camera pitched or turned a little otherwise than the one the points were set for.
    min_lane_fraction : a reported line nearer than this share of ``lane_width_m`` (on the view's
        bottom row) to the next reported line towards the car on its side is refused (``lines.vote``;
        0: off): no lane is that narrow, and the line further out is the one beside the paint (a
        vehicle's edge, a barrier's foot, a slab joint), the lines nearest the car being seen best.
    tight_scatter_m : a line found at another of the ``headings`` than the one kept is reported
        too when its runs scatter less than this about its fit and it stays ``min_gap_fraction``
        of a lane from every reported line without crossing one (``lines.vote``; 0: off). Lane
        lines are parallel, but on a bend or where a lane merges a dashed line's chord and a solid
        line's do not share one heading; a line that tight is paint, not texture.
    """

    lane_width_m: float = 3.7
    min_gap_fraction: float = 0.5
    band_m: float = 15.0
    bands: int = 4
    window_m: float = 5.0
    margin_m: float = 0.6
    grow_margin_m: float = 0.1
    max_empty_windows: int = 5
    min_window_pixels: int = 15
    max_slope: float = 0.35
    min_peak_m: float = 1.5
    min_line_pixels: int = 80
    min_span_m: float = 6.0
    curved_span_m: float = 30.0
    max_scatter_m: float = 0.1
    tophat_low: int = 12
    near_m: float = 25.0
    near_half_width_m: float = 5.0
    extend_m: float = 9.0
    view_half_width_m: float = 14.0
    view_ahead_m: float = 150.0
    view_xm_per_px: float = 0.016
    view_ym_per_px: float = 0.2
    method: str = "trace"
    max_paint_width_m: float = 0.45
    vote_tolerance_m: float = 0.15
    max_lines: int = 6
    heading_spread: float = 0.02
    headings: int = 1
    row_weight_power: float = 0.0
    row_weight_full: float = 0.5
    follow_bends: bool = False
    min_offset_m: float = 0.0
    near_paint_m: float = 3.0
    refused_clear_crossings: bool = True
    follow_ahead_m: float = 0.0
    seen_window_m: float = 2.0
    contrast_full: float = 0.0
    refine_points_px: float = 0.0
    min_lane_fraction: float = 0.0
    tight_scatter_m: float = 0.0

    def __post_init__(self):
        if self.row_weight_power < 0 or self.row_weight_full <= 0:
            raise ConfigError("lines: row_weight_power must be 0 or more and row_weight_full positive")
        if self.method not in ("trace", "vote"):
            raise ConfigError(f"lines.method: {self.method!r} is not a method; use \"trace\" or \"vote\"")
        if min(self.max_paint_width_m, self.vote_tolerance_m) <= 0 or min(self.max_lines, self.headings) < 1:
            raise ConfigError("lines: max_paint_width_m and vote_tolerance_m must be positive, max_lines and "
                              "headings 1 or more")
        if min(self.view_half_width_m, self.view_ahead_m, self.view_xm_per_px, self.view_ym_per_px) <= 0:
            raise ConfigError("lines: the view's width, length and metres per pixel must be positive")
        if min(self.follow_ahead_m, self.seen_window_m, self.contrast_full, self.refine_points_px,
               self.min_lane_fraction, self.tight_scatter_m) < 0:
            raise ConfigError(f"follow_ahead_m {self.follow_ahead_m}, seen_window_m {self.seen_window_m}, "
                              f"contrast_full {self.contrast_full}, refine_points_px {self.refine_points_px}, "
                              f"min_lane_fraction {self.min_lane_fraction} and tight_scatter_m "
                              f"{self.tight_scatter_m} must be 0 (off) or more")
        if min(self.lane_width_m, self.min_gap_fraction, self.band_m, self.window_m, self.margin_m,
               self.min_span_m) <= 0 or self.bands < 1 or self.max_empty_windows < 0:
            raise ConfigError("lines: widths, heights and spans must be positive, bands 1 or more")


@dataclass(frozen=True)
class TrackerConfig:
    """Parameters of ``LaneTracker`` (the checks every lane passes are ``params.LaneChecks``); the parts
    named are in ``lanelib.tracking`` and ``lanelib.roads``.

    Parameters
    ----------
    max_jump_m : largest change of a line's position at the car from one frame to the next.
    max_bend_m : largest change of a line's shape against its track: the spread, over the check
        rows, of its distance from the tracked line.
    smooth_frames : good frames averaged (weighted towards the newest) for the reported fit.
    recency_decay : weight of a frame relative to the next newer one in the average (0-1].
    hold_frames : frames the last good lane is kept after detection fails, before a reset.
    base_history_frames : 0 (off), or accepted frames whose line bases are remembered
        (``roads.proposers.RememberedBases``).
    min_base_peak : a histogram base whose (peak - mean) / mean is below this is weak, and the
        remembered base is tried instead (with ``base_history_frames``).
    lookahead_growth_m : how far (m of road) the look-ahead may reach beyond the rows the tracked
        lane was measured on, per frame (``LaneTracker.lookahead_top_px``). Beyond those rows the track is an
        extrapolation: coming out of a tight bend it still curves as it did, and a search
        around it, or a check against it, over the whole view would refuse the straightening
        lane. A second-order fit extrapolated 3 m errs by about 3**2 * dk / 2, a few cm for the
        curvature changes of a clothoid between frames; the view opens fully in 5 frames.
    trend_frames : accepted frames whose lane centre line gives the trend that the predicted lane
        follows (``roads.trend.predicted_lane``), from the third accepted frame on; below 3 (0, the
        default) turns the prediction off, the presets ``hard-roads`` and ``country`` use 5.
    blind_hold_frames : frames in which nothing at all is seen (no line found by any search) that
        the lane is held for, beside ``hold_frames`` (``tracking.update.hold_or_lose``); they do not
        count toward it. 0 by default; 12 in the ``hard-roads`` and ``country`` presets.
    max_gap_m : largest distance (m of road) between the view's bottom row and a line's pixels
        nearest it (``records.LineFit.gap_px``) for the line to be taken as seen at the car
        (``TrackChecks.judge``). A line seen only farther ahead (its paint near the car in an overpass's shade or worn
        away, a stray edge far ahead) is an extrapolation at the car: a heading error of a degree
        over 15 m puts it 0.26 m off there, where the lane's position, width and offset are
        read. 12 m is the period of a dashed line (3 m dashes, 9 m gaps): a dashed line always
        has paint within it.
    grade_pair_check : (off by default; on in the ``hard-roads`` and ``country`` presets) with a
        track, a pair whose width changes along the view otherwise than the tracked width's does
        (``checks.pair_problem``: "lines not parallel") is checked again against the width the road
        ahead's grade gives it in the flat view: its width at the car times the view's scale across
        the road read from a double line's stripes in this frame (``stripe_spread``'s measure, along
        either line), and kept when it passes. The tracked width ahead is only as new as the last
        frame that saw both lines; where a crest or a dip comes into view it lags, and the pair is
        refused though it is the lane. Not without a track: a pair that only this check keeps, with
        nothing to compare it with, is more often false than the lane.
    stripe_spread : (off by default; on in the ``hard-roads`` and ``country`` presets) while one
        line is inferred, take the change of the lane's width ahead from the seen line's double
        stripes (``roads.stripes.stripe_spacing_px``) when they show on enough rows: where the road
        pitches, the flat view spreads (or narrows) the lane ahead, and the stripes' spacing with
        it, so the lane's width on a row is its tracked width at the car times the stripes' spacing
        there over their spacing at the car (a straight line fitted in the distance from the bottom
        row). Without such stripes the tracked width is kept. The tracked width ahead is only as new
        as the last frame that saw both lines, while over a crest the flat view's lane ahead widens
        far beyond its width at the car.
    reacquire_after_frames : 0 (off, the default), or the accepted frames in a row a line must have
        been inferred (or seen only short of the car, ``max_gap_m``) before it is looked for in a
        wider band around its inference (``roads.proposers.Reacquire``; 3 in the ``hard-roads``
        and ``country`` presets): twice ``prior_margin_px`` either side, one ``prior_margin_px``
        more for each further frame, up to ``reacquire_band_m``; the jump limit against it
        (``max_jump_m``) is as wide. Three frames: a line missing for one or two frames (a gap in a
        dashed line, a shadow) is still near its track.
    reacquire_band_m : the widest half band (m) a long-inferred line is looked for in.
        1.2 m, about a third of a lane: paint returning after a line was inferred for many frames
        (over a crest) may lie a metre outside the inference; a line farther out makes a lane
        outside the width checks' range with the seen line anyway.
    restart_frames : 0 (off, the default; 25 in the ``hard-roads`` and ``country`` presets), or the
        frames after a reset in which one line alone may restart the lane where the lost track's
        line on its side was (``roads.checks.restart``). 25 frames (a second at 25 fps): within it
        the car has moved across the lane by little (at 0.5 m/s of lateral speed, half a metre);
        later the lost track tells nothing about where the lines are.
    restart_distance_m : how far (m, at the car) a line may lie from the lost track's line on
        its side to restart the lane. 0.5 m, ``max_jump_m``'s default: a line of the
        neighbouring lane lies a lane's width (2.5-4.5 m) away.
    road_view_run_m : 0 (off, the default; 1 in the ``hard-roads`` and ``country`` presets), or the
        least run (m of road) of rows whose lane interior does not look like the road near the car
        that ends the look-ahead of a frame whose lines were refused (``roads.proposers.RoadView``).
        1 m: a patch of dirt or a shadow's tinted edge across one or two rows does not; a crest's
        grass spans many.
    road_view_step_px : rows of the bird's-eye view between the rows sampled for it (8: 90 rows
        of the 720, 0.26 m apart; only the columns the interior covers are remapped).
    shoulder_frames : 0 (off, the default; 10 in the ``hard-roads`` and ``country`` presets), or the
        newest measurements of a painted line's shoulder (the distance from the paint out to the
        asphalt edge beyond it, ``roads.proposers.Shoulder``) that are remembered; the shoulder is
        their median once half of them are in and they agree within ``shoulder_spread_m``, and a
        line whose paint then fades out is placed that far inside the asphalt edge.
    shoulder_near_m : the road (m from the view's bottom row) the shoulder is measured on: at
        the car, where the paint and the edge are sharpest and the flat view least pitched.
    shoulder_spread_m : the largest robust spread (1.4826 x the median distance from the median,
        m) of the edge points' distances from the paint within one frame, and of the remembered
        measurements, for the shoulder to count as measured: the edge clearly found, and
        running at a constant distance from the paint.
    shoulder_every : the shoulder is measured on one frame of each ``shoulder_every``: those whose
        number in the video (``update``'s ``index``) it divides, so a Dask segment measures on the
        same frames as one process. A shoulder changes over tens of metres, not from one frame to
        the next, and measuring it costs about a fifth of a clean road's update.
    return_gap_m : on a side whose paint has been missing at the car, the largest distance
        (m of road) between the view's bottom row and the returning paint's nearest pixels for it
        to count as seen at the car again (``max_gap_m`` for any other line); farther, the paint
        is joined nearer the car to the line placed the shoulder inside the asphalt edge. Paint
        returning beyond a crest, into a sag, is seen metres ahead, and its fit extrapolated to
        the car lies inside the lane there (the flat view widens the lane ahead in a sag).
    near_gap_m : 0 (off, the default; 1 in the ``hard-roads`` and ``country`` presets), or
        ``max_gap_m`` on a bend (``roads.checks.gap_limits_m``) for a line whose paint reached the
        car in the newest accepted frames, when the other line of the frame reaches the car within
        it and the tracked line bends by more than ``near_gap_bend_m`` over the gap: seen now only
        from farther ahead (its paint near the car in a tree's shade) it is kept where seen and
        joined nearer the car to the line inferred from the other line, not extrapolated. On a bend
        a line seen only a few metres ahead, extrapolated, lies tens of centimetres off at the car,
        and a double line's far rows sweeping sideways across the view can turn its fit back there.
        Not on straight roads (``near_gap_bend_m``): there a dashed line's gaps are extrapolated
        well, and a join to a track whose other line is missing too is worse. The same rule keeps a
        frame whose line is so extrapolated out of the width seen at the car (``seen_width_m``).
    pitched_start_frames : 0 (off), or the frames in a row, without a track, whose pair is refused
        only as not parallel but is a lane in a pitched flat view (``checks.pitched_pair_problem``:
        its width changes linearly along the view by at most ``max_pitch_change``, and is
        parallel about that trend) and agrees with the previous frame's such pair (each line
        within ``max_jump_m`` at the car and ``max_bend_m`` in shape) that start the track with
        that pair (``tracking.start.pitched_start``). Where the camera looks at the road at another pitch than the
        bird's-eye points were chosen for, every pair of the flat view converges or diverges,
        and no lane would start; once started, the pair's checks compare the width with the
        tracked width, which carries the pitch. One frame alone starts nothing: a
        wrong pair (a seam, a barrier's foot) rarely keeps one trend while the car moves.
    max_pitch_change : the largest change of the lane's width over the whole view, as a share of
        its width at the car, that a pitched start takes for the view's pitch (0.5: with the
        default view, 23.5 m of road beyond 4.8 m ahead, a camera 1.4 m above a road pitched
        about 1.5 degrees from the points' plane narrows the lane at the view's top by half).
    near_gap_bend_m : the least bend (m) of the tracked line over a line's gap (|a| * gap**2 in
        the view, a the tracked line's second-order coefficient) for ``near_gap_m`` to apply:
        below it the curvature moves the extrapolation by less than that, and the line is
        extrapolated (a dashed line on a straight road). 5 cm, a quarter of the 20 cm that make a
        line false near the car; read from the track, not the line's own fit: a dash too short
        for a second-order fit is fitted straight and bends 0, and one such dash extrapolated
        while its neighbours are joined can set off a lost lane.
    """

    max_jump_m: float = 0.5
    max_bend_m: float = 0.7
    smooth_frames: int = 5
    recency_decay: float = 0.6
    hold_frames: int = 12
    base_history_frames: int = 0
    min_base_peak: float = 3.0
    lookahead_growth_m: float = 3.0
    trend_frames: int = 0
    blind_hold_frames: int = 0
    max_gap_m: float = 12.0
    stripe_spread: bool = False
    grade_pair_check: bool = False
    reacquire_after_frames: int = 0
    reacquire_band_m: float = 1.2
    restart_frames: int = 0
    restart_distance_m: float = 0.5
    road_view_run_m: float = 0.0
    road_view_step_px: int = 8
    shoulder_frames: int = 0
    shoulder_near_m: float = 6.0
    shoulder_spread_m: float = 0.05
    shoulder_every: int = 4
    return_gap_m: float = 2.0
    near_gap_m: float = 0.0
    near_gap_bend_m: float = 0.05
    pitched_start_frames: int = 3
    max_pitch_change: float = 0.5

    def __post_init__(self):
        if self.smooth_frames < 1 or self.hold_frames < 0:
            raise ConfigError("tracking: smooth_frames >= 1 and hold_frames >= 0")
        if self.base_history_frames < 0:
            raise ConfigError("tracking: base_history_frames must be 0 (off) or more")
        if not 0 < self.recency_decay <= 1:
            raise ConfigError("tracking: recency_decay must lie in (0, 1]")
        if min(self.max_jump_m, self.max_bend_m) <= 0:
            raise ConfigError("tracking: max_jump_m and max_bend_m must be positive")
        if self.lookahead_growth_m <= 0:
            raise ConfigError("tracking: lookahead_growth_m must be positive")
        if self.trend_frames < 0 or self.blind_hold_frames < 0:
            raise ConfigError("tracking: trend_frames >= 0 and blind_hold_frames >= 0")
        if self.max_gap_m <= 0:
            raise ConfigError("tracking: max_gap_m must be positive")
        if self.reacquire_after_frames < 0 or self.reacquire_band_m <= 0:
            raise ConfigError("tracking: reacquire_after_frames >= 0 (0: off) and reacquire_band_m > 0")
        if self.restart_frames < 0 or self.restart_distance_m <= 0:
            raise ConfigError("tracking: restart_frames >= 0 (0: off) and restart_distance_m > 0")
        if self.road_view_run_m < 0 or self.road_view_step_px < 1:
            raise ConfigError("tracking: road_view_run_m >= 0 (0: off) and road_view_step_px >= 1")
        if (self.shoulder_frames < 0 or self.shoulder_near_m <= 0 or self.shoulder_spread_m <= 0
                or self.shoulder_every < 1):
            raise ConfigError("tracking: shoulder_frames >= 0 (0: off), shoulder_near_m > 0, "
                              "shoulder_spread_m > 0 and shoulder_every >= 1")
        if self.return_gap_m < 0 or self.near_gap_m < 0 or self.near_gap_bend_m < 0:
            raise ConfigError("tracking: return_gap_m >= 0, near_gap_m >= 0 (0: off) and "
                              "near_gap_bend_m >= 0")
        if self.pitched_start_frames < 0 or not 0 < self.max_pitch_change < 1:
            raise ConfigError("tracking: pitched_start_frames >= 0 (0: off) and max_pitch_change "
                              "in (0, 1)")
