"""Colour and gradient masks and the rule that combines them, against images of known content."""
from __future__ import annotations

import numpy as np
import pytest

from lanelib import thresholds as th
from lanelib.errors import ConfigError

YELLOW = (230, 190, 40)
WHITE = (235, 235, 235)
ASPHALT = (90, 90, 95)


@pytest.fixture()
def road():
    """A grey road with a yellow line at x 100-119 and a white line at x 300-319."""
    img = np.zeros((120, 400, 3), np.uint8)
    img[:] = ASPHALT
    img[:, 100:120] = YELLOW
    img[:, 300:320] = WHITE
    return img


def cols(mask):
    return set(np.nonzero(mask.any(axis=0))[0])


def test_color_ranges_separate_yellow_from_white(road):
    cfg = th.ThresholdConfig()
    assert cols(th.color_range_mask(road, cfg.yellow)) == set(range(100, 120))
    assert cols(th.color_range_mask(road, cfg.white)) == set(range(300, 320))


def test_masks_are_uint8_zero_or_255(road):
    for name, m in th.masks(road).items():
        assert m.dtype == np.uint8 and set(np.unique(m)) <= {0, 255}, name


def test_channels_cut_from_a_larger_image_equal_those_of_the_pieces(road):
    """``Channels.cut``: the pieces of an image side by side, with the colour spaces converted so
    far cut alike, give the same spaces and masks as the pieces converted on their own."""
    rng = np.random.default_rng(3)
    img = np.clip(road.astype(int) + rng.integers(-40, 40, road.shape), 0, 255).astype(np.uint8)
    cuts = [(slice(10, 90), slice(80, 140)), (slice(10, 90), slice(290, 330))]
    whole = th.Channels(img)
    whole.space("hls")  # converted before the cut: cut, not converted again
    pieces = whole.cut(cuts, np.hstack)
    alone = th.Channels(np.hstack([img[c] for c in cuts]))
    assert np.array_equal(pieces.rgb, alone.rgb)
    for space in ("hls", "hsv"):
        assert np.array_equal(pieces.space(space), alone.space(space)), space
    cfg = th.ThresholdConfig()
    assert np.array_equal(th.combine(pieces.rgb, cfg, channels=pieces), th.combine(alone.rgb, cfg))

@pytest.mark.parametrize("space,channel,expected", [
    ("hls", "s", 255), ("hsv", "v", 255), ("rgb", "r", 255), ("gray", "y", 76), ("lab", "l", 136)])  # L* 53.2 of sRGB red, x 255/100
def test_channel_values_of_pure_red(space, channel, expected):
    red = np.zeros((4, 4, 3), np.uint8)
    red[..., 0] = 255
    assert abs(int(th.channel(red, space, channel)[0, 0]) - expected) <= 1


@pytest.mark.parametrize("kernel", [1, 3, 5, 7])
def test_sobel_reports_the_step_height(kernel):
    img = np.zeros((40, 40), np.uint8)
    img[:, 20:] = 100  # a vertical step of 100 grey levels
    gx = th.sobel(img, "x", kernel)
    assert gx.max() == pytest.approx(100, rel=0.02)
    assert th.sobel(img, "y", kernel).max() == pytest.approx(0, abs=1e-3)


def test_sobel_direction_of_vertical_and_horizontal_edges():
    img = np.zeros((40, 40), np.uint8)
    img[:, 20:] = 100
    d = th.sobel(img, "dir", 3)
    m = th.sobel(img, "mag", 3) > 50
    assert np.allclose(d[m], 0, atol=1e-3)
    d2 = th.sobel(img.T.copy(), "dir", 3)
    assert np.allclose(d2[m.T], np.pi / 2, atol=1e-3)


def test_tophat_keeps_narrow_lines_and_drops_wide_bright_areas():
    img = np.full((50, 400, 3), 80, np.uint8)
    img[:, 50:70] = 200     # a 20 px line
    img[:, 200:350] = 170   # a 150 px patch of light concrete
    m = th.tophat_mask(img, th.TopHatMask(width_px=61, low=30))
    assert cols(m) == set(range(50, 70))


def test_rule_combines_and_disabled_masks_drop_out(road):
    cfg = th.ThresholdConfig(rule="yellow | white")
    assert cols(th.combine(road, cfg)) == set(range(100, 120)) | set(range(300, 320))
    off = th.ThresholdConfig(rule="yellow | white", white=th.ColorRange("hls", (0, 200, 0), (179, 255, 255), False))
    assert cols(th.combine(road, off)) == set(range(100, 120))
    # a disabled mask inside an & neither adds nor removes pixels
    both = th.ThresholdConfig(rule="yellow & white", white=off.white)
    assert cols(th.combine(road, both)) == set(range(100, 120))
    inv = th.ThresholdConfig(rule="~yellow & ~white")
    assert cols(th.combine(road, inv)).isdisjoint(range(100, 120))


def test_morphology_closes_gaps():
    img = np.full((60, 100, 3), 80, np.uint8)
    img[:, 40:50] = WHITE
    img[28:31, :] = 80  # a 3 px gap across the line
    cfg = th.ThresholdConfig(rule="white", close_px=7)
    assert th.combine(img, cfg)[29, 45] == 255
    assert th.combine(img, th.ThresholdConfig(rule="white"))[29, 45] == 0


@pytest.mark.parametrize("rule,message", [
    ("yellow | purple", "unknown mask 'purple'"),
    ("yellow |", "not a valid expression"),
    ("__import__('os')", "only mask names"),
    ("yellow + white", "only mask names"),
])
def test_bad_rules_are_rejected_with_the_reason(rule, message):
    with pytest.raises(ConfigError, match=message):
        th.ThresholdConfig(rule=rule)


def test_bad_mask_parameters():
    with pytest.raises(ConfigError, match="no channel 'q'"):
        th.ChannelMask("hls", "q")
    with pytest.raises(ConfigError, match="unknown colour space"):
        th.ChannelMask("xyz", "x")
    with pytest.raises(ConfigError, match="kernel_px"):
        th.SobelMask(kernel_px=4)


# --------------------------------------------------------------------------- the seeds' switches

def test_per_mask_opening_removes_a_speck_and_keeps_the_line(road):
    img = road.copy()
    img[60, 50] = YELLOW  # a one-pixel yellow speck beside the yellow line
    plain = th.ColorRange("hsv", (15, 80, 120), (35, 255, 255))
    assert cols(th.color_range_mask(img, plain)) == {50} | set(range(100, 120))
    opened = th.ColorRange("hsv", (15, 80, 120), (35, 255, 255), open_px=3)
    m = th.color_range_mask(img, opened)
    assert cols(m) == set(range(100, 120)) and np.all(m[:, 100:120] == 255)
    # through the rule: only the yellow mask is opened
    cfg = th.ThresholdConfig(yellow=opened, rule="yellow | white")
    assert cols(th.combine(img, cfg)) == set(range(100, 120)) | set(range(300, 320))
    # a channel mask opens the same way
    s_plain, s_open = th.ChannelMask("hls", "s", 170, 255), th.ChannelMask("hls", "s", 170, 255, open_px=3)
    assert 50 in cols(th.channel_mask(img, s_plain)) and 50 not in cols(th.channel_mask(img, s_open))


def test_a_per_mask_opening_widens_the_context():
    assert th.mask_context_px(th.ColorRange(open_px=0)) == (0, 0)
    assert th.mask_context_px(th.ColorRange(open_px=1)) == (0, 0)
    assert th.mask_context_px(th.ColorRange(open_px=5)) == (4, 4)
    assert th.mask_context_px(th.ChannelMask(open_px=3)) == (2, 2)
    cfg = th.ThresholdConfig(yellow=th.ColorRange("hsv", (15, 80, 120), (35, 255, 255), open_px=7),
                             rule="yellow | white")
    assert th.context_px(cfg) == (6, 6)
    assert th.context_px(th.ThresholdConfig(rule="yellow | white")) == (0, 0)


def test_clahe_raises_contrast_on_a_low_contrast_frame():
    rng = np.random.default_rng(0)
    grey = rng.integers(100, 116, (240, 320)).astype(np.uint8)      # road: grey 100-115
    grey[:, 150:170] = rng.integers(120, 131, (240, 20))              # a faint line: 120-130
    img = np.dstack([grey] * 3)
    cfg = th.ThresholdConfig(clahe=True, clahe_clip_limit=4.0, clahe_tile_px=80)
    clahe = th.make_clahe(cfg, (320, 240))
    assert clahe.getTilesGridSize() == (4, 3) and clahe.getClipLimit() == 4.0
    out = th.equalize_lightness(img, clahe)

    def contrast(a):
        a = a[..., 0].astype(float)
        return a[:, 150:170].mean() - np.delete(a, range(150, 170), axis=1).mean()

    assert contrast(img) == pytest.approx(17.5, abs=0.5)
    assert contrast(out) > 2.5 * contrast(img)
    assert np.allclose(out[..., 0], out[..., 1], atol=2)  # still grey: only the lightness changed
    # the masks see the equalised image (the CLAHE passed, or one made for the image)
    white = th.ColorRange("rgb", (140, 140, 140), (255, 255, 255))
    cfg = th.ThresholdConfig(clahe=True, clahe_clip_limit=4.0, clahe_tile_px=80, white=white, rule="white")
    expected = th.color_range_mask(out, white)
    assert expected.any() and not th.color_range_mask(img, white).any()
    assert np.array_equal(th.masks(img, cfg, ("white",), clahe)["white"], expected)
    assert np.array_equal(th.combine(img, cfg), expected)
    assert not th.combine(img, th.ThresholdConfig(white=white, rule="white")).any()


def test_clahe_is_off_by_default_and_makes_no_object():
    assert th.make_clahe(th.ThresholdConfig(), (1280, 720)) is None
    assert th.make_clahe(th.ThresholdConfig(clahe=True), (1280, 720)).getTilesGridSize() == (8, 4)


def test_bad_switch_parameters():
    with pytest.raises(ConfigError, match="open_px"):
        th.ColorRange(open_px=-1)
    with pytest.raises(ConfigError, match="open_px"):
        th.ChannelMask(open_px=-2)
    with pytest.raises(ConfigError, match="clahe_clip_limit"):
        th.ThresholdConfig(clahe_clip_limit=0.0)
    with pytest.raises(ConfigError, match="clahe_tile_px"):
        th.ThresholdConfig(clahe_tile_px=4)


def test_the_switches_are_not_mask_names():
    assert th.mask_names(th.ThresholdConfig()) == ("yellow", "white", "lab_b", "s_channel", "line_tophat",
                                                   "shade_tophat",
                                                   "sobel_x", "sobel_y", "sobel_mag", "sobel_dir")


def test_the_top_hat_drops_a_light_seam_narrower_than_paint_and_keeps_the_paint():
    """A light seam 8 px wide (5 cm at the default view's 5.8 mm/px) beside paint 26 px wide
    (15 cm): both are brighter than the road on both sides; the default least width (12 px)
    keeps the paint whole and drops the seam, and with the least width off both pass."""
    img = np.zeros((60, 400, 3), np.uint8)
    img[:] = ASPHALT
    img[:, 150:158] = (200, 200, 200)  # the seam
    img[:, 200:226] = WHITE  # the paint
    spec = th.ThresholdConfig().line_tophat
    assert spec.min_width_px == 12
    assert cols(th.tophat_mask(img, spec)) == set(range(200, 226))
    off = th.TopHatMask(spec.space, spec.channel, spec.width_px, spec.low, spec.high, min_width_px=1)
    assert cols(th.tophat_mask(img, off)) == set(range(150, 158)) | set(range(200, 226))


def test_the_top_hat_least_width_is_checked_and_widens_the_context():
    with pytest.raises(ConfigError, match="min_width_px 61 must be 1"):
        th.TopHatMask(width_px=61, min_width_px=61)
    with pytest.raises(ConfigError, match="min_width_px 0"):
        th.TopHatMask(min_width_px=0)
    assert th.mask_context_px(th.TopHatMask(width_px=61, min_width_px=12)) == (60 + 11, 0)
    assert th.mask_context_px(th.TopHatMask(width_px=61, min_width_px=1)) == (60, 0)


# --------------------------------------------------------------------------- paint in shade

SHADE = 20  # the road's level under an overpass (V of HSV), as in the bundled shadows clip


def shaded_road(seed=0):
    """A road 120 x 600 px: x < 300 in deep shade (level ~20, noise sd 1.5), x >= 300 sunlit
    asphalt with texture (level ~110, blurred noise sd ~8), the edge between them soft (9 px);
    paint only where a test puts it."""
    rng = np.random.default_rng(seed)
    level = np.where(np.arange(600) < 300, SHADE, 110).astype(np.float32)
    level = np.convolve(np.pad(level, 4, mode="edge"), np.ones(9) / 9, mode="valid")
    texture = rng.normal(0, 1.0, (120, 600)).astype(np.float32)
    texture = (texture + np.roll(texture, 1, 1) + np.roll(texture, 1, 0)) / np.sqrt(3)
    grey = level[None, :] * (1 + np.where(level[None, :] > 60, 0.07, 0.075) * texture)
    img = np.clip(np.round(grey), 0, 255).astype(np.uint8)
    return np.dstack([img, img, img])


def test_the_shade_top_hat_finds_white_and_yellow_paint_under_a_deep_shadow():
    """Paint 26 px wide in shade, at 1.7x the road's level (white: 34 on 20; yellow: R=G 34,
    B 20 as in the shadows clip's frames 127-135): the shade top-hat finds both at their place,
    the absolute top-hat (30 levels) and the colour masks find neither."""
    img = shaded_road()
    img[:, 80:106] = 34  # white paint in shade
    img[:, 180:206] = (34, 34, SHADE)  # yellow paint in shade
    cfg = th.ThresholdConfig()
    shade = th.tophat_mask(img, cfg.shade_tophat)
    assert cols(shade) == set(range(80, 106)) | set(range(180, 206))
    assert not th.tophat_mask(img, cfg.line_tophat).any()
    assert not th.color_range_mask(img, cfg.yellow).any() and not th.color_range_mask(img, cfg.white).any()


def test_the_shade_top_hat_marks_neither_sunlit_texture_nor_a_shadow_edge():
    """The same road without paint: the noise in the shade, the sunlit asphalt's texture and the
    soft edge between shade and sun are not paint, and the shade top-hat marks none of them."""
    assert not th.tophat_mask(shaded_road(), th.ThresholdConfig().shade_tophat).any()
    for seed in (1, 2, 3):
        assert not th.combine(shaded_road(seed), th.ThresholdConfig()).any()


def test_the_shade_top_hat_is_relative_with_a_floor_in_levels():
    """A 30 px stripe on a flat road of level b passes when stripe >= (1 + ratio) * b and its
    top-hat >= low; ``max_background`` keeps only roads at most that bright; ratio 0 is the
    absolute top-hat."""
    def stripe(background, value, spec):
        img = np.full((10, 200, 3), background, np.uint8)
        img[:, 90:120] = value
        return bool(th.tophat_mask(img, spec).any())

    spec = th.TopHatMask("hsv", "v", 61, 8, 255, min_width_px=12, ratio=0.5)
    assert stripe(40, 60, spec) and not stripe(40, 59, spec)  # 60 = 1.5 x 40
    assert stripe(100, 150, spec) and not stripe(100, 149, spec)
    assert stripe(10, 18, spec) and not stripe(10, 17, spec)  # the floor: 8 levels, not 1.5 x 10
    dark_only = th.TopHatMask("hsv", "v", 61, 8, 255, min_width_px=12, ratio=0.5, max_background=60)
    assert stripe(60, 90, dark_only) and not stripe(61, 92, dark_only)
    assert stripe(100, 140, th.TopHatMask("hsv", "v", 61, 8, 255)) == stripe(100, 140, th.TopHatMask(
        "hsv", "v", 61, 8, 255, ratio=0.0))
    with pytest.raises(ConfigError, match="ratio -1"):
        th.TopHatMask(ratio=-1)
    with pytest.raises(ConfigError, match="max_background 300"):
        th.TopHatMask(max_background=300)
    assert th.mask_context_px(spec) == (60 + 11, 0)  # the ratio and the background level are per pixel


@pytest.mark.parametrize("size", [2, 3, 4, 5, 6, 8])
def test_openings_and_closings_of_any_size_leave_a_wide_shape_in_place(size, road):
    # OpenCV's morphologyEx put an even kernel's anchor half a pixel off centre for both passes,
    # which moved a 20 px square one pixel down and right; th.morph mirrors the second anchor
    square = np.zeros((40, 40), np.uint8)
    square[10:30, 10:30] = 255
    for op in ("open", "close"):
        assert np.array_equal(th.morph(square, op, size, size), square), op
    # every place that opens or closes a mask: per mask, the combined mask, the top-hat's least width
    yellow = th.ColorRange("hsv", (15, 80, 120), (35, 255, 255), open_px=size)
    assert cols(th.color_range_mask(road, yellow)) == set(range(100, 120))
    for cfg in (th.ThresholdConfig(rule="yellow | white", open_px=size),
                th.ThresholdConfig(rule="yellow | white", close_px=size)):
        assert cols(th.combine(road, cfg)) == set(range(100, 120)) | set(range(300, 320))
    stripe = np.full((10, 100), 60, np.uint8)
    stripe[:, 40:60] = 200
    tophat = th.TopHatMask("hls", "l", 41, 50, 255, min_width_px=size)
    assert cols(th.tophat_mask(np.dstack([stripe] * 3), tophat)) == set(range(40, 60))


def test_an_even_opening_still_drops_what_is_narrower_than_it():
    m = np.zeros((20, 40), np.uint8)
    m[:, 10:13] = 255  # 3 px wide: dropped by 4, kept by 3
    m[:, 25:29] = 255  # 4 px wide: kept by 4
    assert cols(th.morph(m, "open", 4, 1)) == set(range(25, 29))
    assert cols(th.morph(m, "open", 3, 1)) == set(range(10, 13)) | set(range(25, 29))
    with pytest.raises(ValueError, match="'open' or 'close'"):
        th.morph(m, "erode", 3, 3)


def test_row_morphology_and_colour_boxes_equal_opencv_on_random_images():
    # th.row_extreme (a row kernel's erosion or dilation by doubling runs) and th.color_range_mask (one
    # channel at a time) give exactly cv2.erode / cv2.dilate and the 3-channel cv2.inRange
    import cv2
    rng = np.random.default_rng(0)
    for trial in range(60):
        h, w = int(rng.integers(1, 12)), int(rng.integers(1, 150))
        img = rng.integers(0, 256, (h, w), dtype=np.uint8)
        for width in (1, 2, 3, 12, 61):
            kernel = np.ones((1, width), np.uint8)
            for anchor in {0, width // 2, width - 1}:
                assert np.array_equal(th.row_extreme(img, width, anchor, True),
                                      cv2.erode(img, kernel, anchor=(anchor, 0)))
                assert np.array_equal(th.row_extreme(img, width, anchor, False),
                                      cv2.dilate(img, kernel, anchor=(anchor, 0)))
        rgb = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        low = tuple(int(v) for v in rng.integers(0, 128, 3) * (rng.random(3) < 0.7))
        high = tuple(int(v) for v in 255 - rng.integers(0, 128, 3) * (rng.random(3) < 0.7))
        spec = th.ColorRange("hls", low, high)
        expected = cv2.inRange(cv2.cvtColor(rgb, cv2.COLOR_RGB2HLS), np.array(low, np.uint8),
                               np.array(high, np.uint8))
        assert np.array_equal(th.color_range_mask(rgb, spec), expected)


def test_rows_opened_equals_the_whole_opening_on_sparse_and_full_masks():
    # th.rows_opened opens only the rows holding a pixel: the same mask as th.morph on the whole
    rng = np.random.default_rng(1)
    for trial in range(40):
        h, w = int(rng.integers(1, 30)), int(rng.integers(1, 150))
        mask = np.where(rng.random((h, w)) < 0.5, 255, 0).astype(np.uint8)
        mask[rng.random(h) < [0.0, 0.5, 1.0][trial % 3]] = 0  # no, some or all rows emptied
        for width in (2, 3, 12):
            assert np.array_equal(th.rows_opened(mask, width), th.morph(mask, "open", width, 1))


def _relative_reference(tophat, background, spec):
    """The relative top-hat's mask by its definition (``TopHatMask``): top-hat at least ``low`` and
    ``ratio`` times the background (to 1e-9), at most ``high``, background at most ``max_background``."""
    t, b = tophat.astype(np.float64), background.astype(np.float64)
    keep = (t >= spec.low) & (t >= spec.ratio * b - 1e-9) & (t <= spec.high) & (b <= spec.max_background)
    return np.where(keep, 255, 0).astype(np.uint8)


RELATIVE_SPECS = [th.TopHatMask("gray", "y", 5, low, high, ratio=ratio, max_background=dark)
                  for ratio in (0.0, 0.0001, 1 / 3, 0.5, 0.65, 1.0, 1.000001, 1.7, 2.5, 255.0)
                  for low in (0, 8, 30) for dark in (255, 120, 0) for high in (255, 200)]


def test_the_relative_top_hat_keeps_what_its_definition_says_at_every_level():
    # row b: a road of level b with every other pixel b + t, t = 0..255 (saturated): each background
    # level under each top-hat, for ratios and floors the scaled levels match exactly or not
    b = np.arange(256)[:, None]
    img = np.repeat(b, 512, axis=1)
    img[:, 1::2] = np.minimum(255, b + np.arange(256)[None, :])
    rgb = np.repeat(img.astype(np.uint8)[:, :, None], 3, axis=2)
    tophat, background = th.Channels(rgb).tophat(RELATIVE_SPECS[0])
    assert np.array_equal(background, img * 0 + b) and np.array_equal(tophat[:, 1::2], img[:, 1::2] - b)
    for spec in RELATIVE_SPECS:
        assert np.array_equal(th.tophat_mask(rgb, spec), _relative_reference(tophat, background, spec)), spec


def test_the_relative_top_hat_keeps_what_its_definition_says_on_random_images():
    # widths that leave OpenCV's vector loops a tail of every length, and the shade top-hat's least width
    rng = np.random.default_rng(2)
    shade = th.ThresholdConfig().shade_tophat
    for trial in range(40):
        rgb = rng.integers(0, 256, (int(rng.integers(1, 9)), int(rng.integers(1, 140)), 3), dtype=np.uint8)
        for spec in (shade, RELATIVE_SPECS[trial * 3 % len(RELATIVE_SPECS)]):
            tophat, background = th.Channels(rgb).tophat(spec)
            expected = _relative_reference(tophat, background, spec)
            if spec.min_width_px > 1:
                expected = th.morph(expected, "open", spec.min_width_px, 1)
            assert np.array_equal(th.tophat_mask(rgb, spec), expected), spec


def test_a_fallback_rule_that_extends_the_rule_reuses_its_mask(road):
    road[:, 130:290] = 30  # deep shade, and in it a stripe twice as bright: the shade top-hat's alone
    road[40:60, 200:215] = 60
    cfg = th.ThresholdConfig(fallback_rule="yellow | (white & line_tophat) | shade_tophat")
    made = th.Made()
    cheap = th.combine(road, cfg, made=made)
    fallback = th.combine(road, cfg, rule=cfg.fallback_rule, made=made)
    assert np.array_equal(fallback, th.combine(road, cfg, rule=cfg.fallback_rule))
    assert np.array_equal(fallback, cheap | th.tophat_mask(road, cfg.shade_tophat))
    assert cols(fallback) - cols(cheap) == set(range(200, 215))
    assert any(m is cheap for m in made.expressions.values())  # the rule's mask, made once


@pytest.mark.parametrize("dtype", [np.uint8, np.float32])
def test_channels_convert_in_bands_as_opencv_converts_the_whole_image(dtype):
    # th.Channels.space converts a three-channel space th.BAND_ROWS rows at a time and splits each
    # band: the same conversion and planes as cv2.cvtColor and cv2.split of the whole image, for
    # images of fewer rows than a band and of several, contiguous or a view
    import cv2
    rng = np.random.default_rng(3)
    for h in (1, th.BAND_ROWS - 1, th.BAND_ROWS, 2 * th.BAND_ROWS + 7):
        big = rng.integers(0, 256, (h + 2, 37, 3)).astype(np.uint8)
        big = big if dtype == np.uint8 else big.astype(np.float32) / 255
        for img in (np.ascontiguousarray(big[:h, :31]), big[1:h + 1, 3:34]):
            ch = th.Channels(img)
            for space, (code, letters) in th.SPACES.items():
                whole = img if code is None else cv2.cvtColor(img, code)
                assert np.array_equal(ch.space(space), whole)
                for i, letter in enumerate(letters):
                    assert np.array_equal(ch.channel(space, letter), whole if whole.ndim == 2 else whole[..., i])
