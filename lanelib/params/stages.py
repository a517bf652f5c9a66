"""The parameter records of the core stages: perspective, lane search, lane checks, drawing, Hough.

Each record is a frozen dataclass with defaults and units in its field names; its
``__post_init__`` refuses a value out of range with a ``ConfigError`` naming the key. The stage
modules import their records from here (``lanelib.search.SearchConfig`` is this
``SearchConfig``), and ``config.PipelineConfig`` nests them, so a record depends on nothing above it.
A function a record's docstring names without its module is its stage's (``checks.check_lane``,
``perspective.Perspective``, ...).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError

Point = tuple[float, float]

# src: top-left, bottom-left, bottom-right, top-right (undistorted 1280x720 image)
DEFAULT_SRC_1280x720: tuple[Point, ...] = ((564.3, 470.0), (193.0, 720.0), (1087.0, 720.0), (715.7, 470.0))
# dst: the same corners in the bird's-eye view (1280x720)
DEFAULT_DST_1280x720: tuple[Point, ...] = ((320.0, 0.0), (320.0, 720.0), (960.0, 720.0), (960.0, 0.0))
DEFAULT_LANE_WIDTH_M = 3.7
DEFAULT_VISIBLE_LENGTH_M = 23.5
Triple = tuple[int, int, int]
Color = tuple[int, int, int]


@dataclass(frozen=True)
class PerspectiveConfig:
    """Source and destination points of the bird's-eye transform and the metric scale they carry.

    Parameters
    ----------
    src_px : four (x, y) points in the undistorted image: top-left, bottom-left, bottom-right,
        top-right of a stretch of straight lane.
    dst_px : the same four points in the bird's-eye image (a rectangle).
    size_px : (width, height) of the images the points belong to; the bird's-eye view has this size.
    lane_width_m : the real distance between the dst left and right lines (US lane: 3.7 m).
    visible_length_m : the real road length between the dst top and bottom rows.
    car_x_px : x (px) of the car's centre line in the bird's-eye view, from which the offset is
        measured and the search splits left from right; None (the default): where the bottom
        row's centre pixel of the image lands, right for a camera that looks straight ahead.
        ``geometry.RoadGeometry`` sets it (a turned camera's image centre is not the car's).
    """

    src_px: tuple[Point, ...] = DEFAULT_SRC_1280x720
    dst_px: tuple[Point, ...] = DEFAULT_DST_1280x720
    size_px: tuple[int, int] = (1280, 720)
    lane_width_m: float = DEFAULT_LANE_WIDTH_M
    visible_length_m: float = DEFAULT_VISIBLE_LENGTH_M
    car_x_px: float | None = None

    def __post_init__(self):
        for name in ("src_px", "dst_px"):
            pts = getattr(self, name)
            if len(pts) != 4 or any(len(p) != 2 for p in pts):
                raise ConfigError(f"perspective.{name}: needs four (x, y) points, got {pts!r}")
        if self.lane_width_m <= 0 or self.visible_length_m <= 0:
            raise ConfigError("perspective.lane_width_m and visible_length_m must be positive")

    @property
    def xm_per_px(self) -> float:
        """Metres per bird's-eye pixel across the road."""
        d = np.asarray(self.dst_px, dtype=float)
        width_px = abs((d[2, 0] + d[3, 0]) / 2 - (d[0, 0] + d[1, 0]) / 2)
        return self.lane_width_m / width_px

    @property
    def ym_per_px(self) -> float:
        """Metres per bird's-eye pixel along the road."""
        d = np.asarray(self.dst_px, dtype=float)
        length_px = abs((d[1, 1] + d[2, 1]) / 2 - (d[0, 1] + d[3, 1]) / 2)
        return self.visible_length_m / length_px


@dataclass(frozen=True)
class SearchConfig:
    """Parameters of the lane-pixel search and the fits.

    Parameters
    ----------
    n_windows : sliding windows stacked over the image height.
    margin_px : half width of a sliding window.
    minpix : pixels a window must hold to recentre the next one on their mean x.
    histogram_fraction : lower share of the image whose column sums locate the line bases.
    prior_margin_px : half width of the band searched around a previous fit.
    min_line_pixels : fewer pixels than this and the line is "not found".
    min_span_fraction : pixels must span this share of the image height for a 2nd-order fit;
        below it the line is fitted as a straight line (a = 0), unless its bend is resolved in a
        look-ahead (``short_bend_resolution``).
    short_bend_resolution : 0 (off), or how many times its pixels' RMS scatter about it the
        2nd-order fit of a line spanning less than ``min_span_fraction`` must bow over its span
        (``|a| * span**2 / 4``) to be kept, in a search over a look-ahead (``top_px`` > 0: a
        tracked lane's, ``lookahead_top_px``, or a shorter view). A line on a tight bend leaves the
        view sideways (on a 35 m hairpin after about 6 m of its 23.5 m), so it spans less than the
        share on exactly the bends whose curvature matters most: fitted straight, such a line lies
        off the road's line at the car and ahead, and a track of straight lines then refuses the
        lines seen whole. A dash on a straight road bows by a fraction of a pixel and stays
        straight. The whole view (no track) keeps the straight fit: there the pair checks read the
        fit over the view's 23.5 m, three or four times the span of such a line.
    min_found_span_fraction : below this share of the height the line is "not found".
    trim_outliers_pct : 0 (off), or the share (%) of a line's pixels kept for its fit: after a
        first fit, the pixels with the smallest |x residual| (e.g. 95: the nearest 95 %), then a
        refit on them (``fit_line``).
    window_histogram : False: a window recentres the next one on the mean x of its pixels;
        True: on the peak of the column histogram of its pixels (the fullest column).
    centre_first : False: a window takes all its pixels; True: it looks at the lane-centre side
        first: its pixels are cut into clusters of columns (split at empty columns) and it takes
        the cluster nearest the lane centre that holds ``minpix`` pixels (all its pixels when
        none does), so a verge or kerb beyond the line does not pull the window out.
    short_views : shares of the view's height, from its bottom row, tried in order as the
        look-ahead when the lane of the whole view fails its checks and there is no track (off:
        ``()``, the default); see ``lookahead_top_px`` for why a shorter view finds a lane on a
        tight bend. The ``hard-roads`` and ``country`` presets' 0.6 and 0.4 of the 23.5 m view (14 m and 9.4 m of road), keep the lane of a
        60 m and of a 35 m bend in the view (a line 1.9 m from the view's side leaves it after
        sqrt(2 * R * 1.9 m) of road, less the 4.8 m to the bottom row).
    min_view_fraction : the shortest look-ahead, as a share of the view's height, that
        ``lookahead_top_px`` gives a tracked lane; below about 9 m of road a dashed line (3 m
        dashes, 12 m period) may show no dash at all.
    candidates : 1 (off), or the histogram peaks tried on each side when the lane of the
        strongest ones fails its checks (``roads.fallbacks.candidate_bases``): the robust path of
        ``LanePipeline.detect``, which runs sliding windows from each pair of them, strongest
        first, and keeps the first pair that passes the checks.
    grow_margin_px : 0 (off), or px added to a window's half width for each empty window (fewer
        than ``minpix`` pixels) in a row below it; the margin is back to ``margin_px`` after a
        window with pixels. A line lost over a gap (a missing dash, a shadow) is caught again.
        Off by default, 15 px in the ``hard-roads`` and ``country`` presets (notebook 09 compares
        the switches).
    double_line_px : 0 (off), or the distance (px) between the centres of the two stripes of a
        double line (a double yellow centre line): where a line's pixels form two such stripes,
        the line is fitted to the inner one, the stripe nearer the lane (``inner_stripe``), as
        the lane's boundary is marked. Off by default; the ``hard-roads`` and ``country`` presets'
        38 px is 0.22 m in the default 1280x720 view (0.10-0.15 m stripes 0.10 m apart); stripes
        0.6-1.5 times as far apart are taken.
    """

    n_windows: int = 9
    margin_px: int = 80
    minpix: int = 50
    histogram_fraction: float = 0.5
    prior_margin_px: int = 60
    min_line_pixels: int = 150
    min_span_fraction: float = 0.3
    short_bend_resolution: float = 2.0
    min_found_span_fraction: float = 0.08
    trim_outliers_pct: float = 0.0
    window_histogram: bool = False
    centre_first: bool = False
    grow_margin_px: int = 0
    candidates: int = 1
    short_views: tuple[float, ...] = ()
    min_view_fraction: float = 0.4
    double_line_px: float = 0.0

    def __post_init__(self):
        if self.double_line_px < 0:
            raise ConfigError(f"search: double_line_px {self.double_line_px} must be 0 (off) or more")
        if self.candidates < 1:
            raise ConfigError(f"search: candidates {self.candidates} must be 1 (off) or more")
        if not 0 <= self.trim_outliers_pct <= 100:
            raise ConfigError(f"search: trim_outliers_pct {self.trim_outliers_pct} must lie in 0-100 (0: off)")
        if self.grow_margin_px < 0:
            raise ConfigError(f"search: grow_margin_px {self.grow_margin_px} must be 0 (off) or more")
        if not all(0 < v < 1 for v in self.short_views):
            raise ConfigError(f"search: short_views {self.short_views} must be shares of the view "
                              "between 0 and 1 (none: off)")
        if not 0 < self.min_view_fraction <= 1:
            raise ConfigError(f"search: min_view_fraction {self.min_view_fraction} must lie in (0, 1]")
        if self.short_bend_resolution < 0:
            raise ConfigError(f"search: short_bend_resolution {self.short_bend_resolution} must be 0 (off) "
                              "or more")


@dataclass(frozen=True)
class LaneChecks:
    """The plausibility checks every found lane passes, in a single image or in a video.

    ``check_lane`` applies them to the fits of one search; ``LanePipeline.detect`` (images) and
    ``LaneTracker`` (video) both call ``line_problem`` and ``pair_problem``, so a lane is found
    by the same rules everywhere. A line's support (its pixel count and the rows it spans) is
    checked where it is fitted (``fit_line``: ``SearchConfig.min_line_pixels`` and
    ``min_found_span_fraction``); with less it is not found at all. The checks read only the
    fits, the line pixels' counts and a few rows (``check_rows``), never the whole view, so the
    tracker's band-only search can run them too.

    Each line alone: it may not fill its search band (``max_band_fill``: a bright verge) nor
    spread across it (``max_band_scatter``: texture, not a line nor the two stripes of a double
    line). The pair: width on the bottom row, parallel
    lines, consistent curvatures. Images without a lane (noise, blurred noise, stripes in any
    direction, a chessboard, flat or black frames) fail these rules for what they are: texture
    spreads over its band, and the lines of a stripe or blob pattern are rarely a lane's width
    apart, parallel and equally curved. The rules do not look for an "ambiguous" view (several
    equally strong candidate lines): real roads have that too (a shadow edge, a car, a seam),
    and a band-only search could not see it. What remains possible is chance: a few blobs that
    line up like two dashed lines at a lane's width (about 3 in 1,000 random blob fields pass).

    Parameters
    ----------
    min_width_m, max_width_m : the lane width on the view's bottom row must lie in this range.
    max_width_spread_m : largest difference of the lane width between the check rows, top to
        bottom (the two lines roughly parallel), over the whole view; a shorter look-ahead
        (``LaneSearch.top_px``) allows its share of it, the same divergence per metre of road.
    max_curvature_diff_per_m : largest difference of the two lines' curvatures on the bottom
        row (1/m), over the whole view; a shorter look-ahead allows it divided by its share of
        the view (a shorter fit's curvature is measured less well; ``pair_problem``).
    max_band_fill : largest share of its search band (sliding window or prior band, over the
        rows it spans) a line's pixels may fill; a wider patch is a bright area (grass, sky,
        concrete) whose edge would pass for a line. Real lines fill at most about 0.35.
    max_band_scatter : largest RMS distance of a line's pixels from its fit, as a share of the
        RMS distance of pixels spread evenly across the band (band width / sqrt(12)): 1 for
        texture (noise, gravel, stripes crossing the band), whatever line it happens to fit; a
        painted line is a thin stroke close to its fit, well below the limit in sliding windows
        and in the narrower prior band alike (the band cuts the clutter with it). A double line
        (two stripes side by side) scatters more from one fit through both, past 1 where the
        view's edge cuts its band on a tight bend; it is texture only if its pixels also spread
        as two stripes (``LineFit.stripe_scatter_px``): their RMS distance from the nearer
        stripe, as a share of an even spread over half the band, is over the same limit.
        Texture split in two keeps its even spread over each half (1); two narrow stripes keep
        about their width / sqrt(12), well below it.
    check_rows : rows (evenly spaced, top to bottom) on which widths and shapes are compared.
    max_turn_back_m : largest distance (m, across) a line's fit may come back, beyond its pixels,
        from a row where its x turns around within the look-ahead (``turn_back_m``): a second-order
        fit extrapolated from pixels on part of the view (a stub of paint, a blob beside it) may
        hook sideways above them, and a lane drawn so leaves the road. Where the pixels
        themselves turn (a car heading across a bend) the fit rests on them.
    """

    min_width_m: float = 3.0
    max_width_m: float = 4.5
    max_width_spread_m: float = 0.7
    max_curvature_diff_per_m: float = 0.004
    max_band_fill: float = 0.6
    max_band_scatter: float = 0.7
    check_rows: int = 8
    max_turn_back_m: float = 0.3

    def __post_init__(self):
        if not 0 < self.min_width_m < self.max_width_m:
            raise ConfigError("checks: need 0 < min_width_m < max_width_m")
        if self.check_rows < 2:
            raise ConfigError("checks: check_rows must be at least 2")
        if min(self.max_width_spread_m, self.max_curvature_diff_per_m, self.max_band_fill,
               self.max_band_scatter, self.max_turn_back_m) <= 0:
            raise ConfigError("checks: max_width_spread_m, max_curvature_diff_per_m, max_band_fill, "
                              "max_band_scatter and max_turn_back_m must be positive")


@dataclass(frozen=True)
class DrawConfig:
    """Colours (RGB), opacity and text size of the overlays.

    ``video_undistorted``: the ``video`` command draws on the RAW frame by default, the lane
    mapped through the lens model (what the camera saw, and one full-frame remap per frame
    cheaper); true draws on the undistorted frame, as the ``images`` command does.
    ``held_color``: the lane area and both lines of a lane held from earlier frames (not seen in
    this one), so it never looks like a lane seen now.
    """

    lane_color: Color = (0, 200, 90)
    held_color: Color = (255, 170, 0)
    left_color: Color = (255, 60, 40)
    right_color: Color = (40, 110, 255)
    lane_alpha: float = 0.3
    line_thickness_px: int = 12
    font_scale: float = 1.0
    samples: int = 48
    video_undistorted: bool = False


@dataclass(frozen=True)
class HoughConfig:
    """Parameters of the basic Canny + region of interest + Hough pipeline.

    Parameters
    ----------
    white_hls_lo, white_hls_hi : inclusive (H, L, S) bounds of white paint, OpenCV 8-bit units
        (H in 0..179 = degrees / 2, L and S in 0..255).
    yellow_hls_lo, yellow_hls_hi : the same for yellow paint.
    blur_kernel_px : side of the Gaussian blur kernel (odd, >= 1; 1 means no blur).
    canny_low, canny_high : Canny hysteresis thresholds on the gradient (grey levels per pixel).
    roi_frac : the region of interest, a polygon of (x / width, y / height) vertices in 0..1;
        (0, 0) is the top-left pixel and (1, 1) the bottom-right one.
    rho_px : distance resolution of the Hough accumulator (px, >= 0.5).
    theta_deg : angle resolution of the Hough accumulator (degrees, 0.1..90).
    threshold_votes : accumulator votes a line needs.
    min_line_length_px : shortest segment kept (px).
    max_line_gap_px : largest gap between collinear points joined into one segment (px).
    min_abs_slope : smallest |dy/dx| of a segment counted as a lane line (flatter ones are dropped).
    smoothing_alpha : weight of the new frame in the exponential smoothing of line endpoints
        across video frames, in (0, 1]; 1 means no smoothing.
    hold_frames : frames a lost line is held at its last position in video before it is dropped.
    """

    white_hls_lo: Triple = (0, 200, 0)
    white_hls_hi: Triple = (179, 255, 255)
    yellow_hls_lo: Triple = (10, 0, 100)
    yellow_hls_hi: Triple = (40, 255, 255)
    blur_kernel_px: int = 5
    canny_low: int = 50
    canny_high: int = 150
    roi_frac: tuple[tuple[float, float], ...] = ((0.06, 1.0), (0.44, 0.60), (0.56, 0.60), (0.97, 1.0))
    rho_px: float = 1.0
    theta_deg: float = 1.0
    threshold_votes: int = 25
    min_line_length_px: int = 20
    max_line_gap_px: int = 150
    min_abs_slope: float = 0.5
    smoothing_alpha: float = 0.3
    hold_frames: int = 10

    def __post_init__(self):
        # JSON gives lists; store tuples so the config stays hashable and comparable
        for name in ("white_hls_lo", "white_hls_hi", "yellow_hls_lo", "yellow_hls_hi"):
            value = tuple(getattr(self, name))
            if len(value) != 3:
                raise ConfigError(f"hough.{name}: needs three values (H, L, S), got {value!r}")
            object.__setattr__(self, name, value)
        roi = tuple(tuple(p) for p in self.roi_frac)
        if len(roi) < 3 or any(len(p) != 2 or not all(0.0 <= v <= 1.0 for v in p) for p in roi):
            raise ConfigError(f"hough.roi_frac: needs three or more (x, y) fractions in 0..1, got {roi!r}")
        object.__setattr__(self, "roi_frac", roi)
        if self.blur_kernel_px < 1 or self.blur_kernel_px % 2 == 0:
            raise ConfigError(f"hough.blur_kernel_px: must be odd and >= 1, got {self.blur_kernel_px}")
        if not 0 <= self.canny_low <= self.canny_high:
            raise ConfigError(f"hough.canny_low, canny_high: need 0 <= low <= high, "
                              f"got {self.canny_low}, {self.canny_high}")
        # finer steps make the Hough accumulator huge (over 40 MB at 960x540) for no gain
        if not (self.rho_px >= 0.5 and 0.1 <= self.theta_deg <= 90 and self.threshold_votes >= 1):
            raise ConfigError(f"hough.rho_px >= 0.5, theta_deg in 0.1..90 and threshold_votes >= 1 "
                              f"are needed, got {self.rho_px}, {self.theta_deg}, {self.threshold_votes}")
        if self.min_line_length_px < 0 or self.max_line_gap_px < 0 or self.min_abs_slope < 0:
            raise ConfigError("hough.min_line_length_px, max_line_gap_px and min_abs_slope "
                              "must not be negative")
        if not 0.0 < self.smoothing_alpha <= 1.0 or self.hold_frames < 0:
            raise ConfigError(f"hough.smoothing_alpha must be in (0, 1] and hold_frames >= 0, "
                              f"got {self.smoothing_alpha}, {self.hold_frames}")
