"""Grids of labelled views: ``draw.sheet`` (the tuners' previews), ``draw.shrink``, and
``draw.composite`` (the pipeline's 2x2 debug view) as one case of the sheet."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from lanelib import draw
from lanelib.camera import Calibration, distort_points
from lanelib.checks import holds_from_px
from lanelib.errors import InputError
from lanelib.pipeline import FrameResult, LanePipeline
from lanelib.records import LineFit

YELLOW = (255, 255, 0)


def textured(w: int, h: int, seed: int) -> np.ndarray:
    """Return a smooth random RGB image (every pixel differs from its neighbours a little)."""
    rng = np.random.default_rng(seed)
    return cv2.GaussianBlur(rng.integers(0, 256, (h, w, 3), dtype=np.uint8), (0, 0), 3)


def panels(w: int, h: int) -> list[tuple[str, np.ndarray]]:
    img = textured(w, h, 1)
    mask = np.where(np.random.default_rng(2).random((h, w)) < 0.1, 255, 0).astype(np.uint8)
    return [("undistorted", img), ("binary (bird's-eye)", mask), ("search and fits", img[:, ::-1].copy()),
            ("result", textured(w, h, 3))]


def label_box(label: str, ph: int) -> tuple[slice, slice]:
    """Return the rows and columns of a tile that a bottom label (font scale 0.8) may touch."""
    (tw, th), base = cv2.getTextSize(label, cv2.FONT_HERSHEY_SIMPLEX, 0.8, 2)
    return slice(ph - 15 - th - 4, ph - 15 + base + 4), slice(0, 10 + tw + 4)


# --------------------------------------------------------------------------- sheet and shrink

def test_sheet_and_shrink():
    a = np.full((720, 1280, 3), 200, np.uint8)
    m = np.zeros((720, 1280), np.uint8)
    out = draw.sheet({"a": a, "m": m, "off": None}, tile_width_px=320, columns=2)
    assert out.shape == (2 * 180, 2 * 320, 3)
    assert out[100, 100].tolist() == [200, 200, 200]       # view a, below its label
    assert out[100, 420].tolist() == [0, 0, 0]             # mask m
    assert out[270, 100].tolist() == [48, 48, 48]          # the "off" tile
    assert out[270, 420].tolist() == [0, 0, 0]             # the empty slot
    assert a[10, 10].tolist() == [200, 200, 200]           # the caller's view is not drawn on
    assert draw.shrink(a, (400, 225)).shape == (225, 400, 3)
    assert draw.shrink(m, (320, 180)).shape == (180, 320)


def test_shrink_halves_by_area_then_goes_linear():
    img = textured(1280, 720, 4)
    half = cv2.resize(img, (640, 360), interpolation=cv2.INTER_AREA)
    assert np.array_equal(draw.shrink(img, (640, 360)), half)
    assert np.array_equal(draw.shrink(img, (400, 225)),
                          cv2.resize(half, (400, 225), interpolation=cv2.INTER_LINEAR))
    assert draw.shrink(img, (1280, 720)) is img  # nothing to do


def test_sheet_takes_pairs_with_repeated_labels_and_an_explicit_tile_size():
    img = textured(200, 100, 5)
    out = draw.sheet([("same", img), ("same", img)], tile_width_px=100, columns=2, tile_height_px=40,
                     interpolation=cv2.INTER_AREA)
    assert out.shape == (40, 200, 3)
    tile = cv2.resize(img, (100, 40), interpolation=cv2.INTER_AREA)
    assert np.array_equal(out[:, 100:][30:, 60:], tile[30:, 60:])  # right of and below the label


def test_sheet_labels_at_the_top_or_the_bottom():
    grey = np.full((360, 640, 3), 90, np.uint8)
    top = draw.sheet({"a label": grey}, tile_width_px=640, columns=1)
    bottom = draw.sheet({"a label": grey}, tile_width_px=640, columns=1, label_at="bottom")
    is_yellow = lambda im: np.all(im == YELLOW, axis=2)  # noqa: E731
    assert is_yellow(top[:40]).any() and not is_yellow(top[40:]).any()
    assert is_yellow(bottom[-40:]).any() and not is_yellow(bottom[:-40]).any()
    assert np.all(top[0, :20] == 0)  # the black box behind a top label


def test_sheet_refuses_what_it_cannot_lay_out():
    with pytest.raises(InputError, match="no views"):
        draw.sheet({})
    with pytest.raises(InputError, match="every view is off"):
        draw.sheet({"a": None})
    assert draw.sheet({"a": None}, tile_width_px=64, tile_height_px=36).shape == (36, 64, 3)
    with pytest.raises(InputError, match="label_at"):
        draw.sheet({"a": np.zeros((8, 8), np.uint8)}, label_at="left")


# --------------------------------------------------------------------------- the debug composite

@pytest.mark.parametrize("size", [(1280, 720), (960, 540), (1281, 721), (333, 201)])
def test_composite_tiles_are_the_area_resized_panels_with_a_label_at_the_bottom(size):
    w, h = size
    pw, ph = w // 2, h // 2
    views = panels(w, h)
    copies = [v.copy() for _, v in views]
    out = draw.composite(views, size)
    assert out.shape == (h, w, 3) and out.dtype == np.uint8
    for i, (label, view) in enumerate(views):
        r, c = divmod(i, 2)
        tile = out[r * ph:(r + 1) * ph, c * pw:(c + 1) * pw]
        rgb = cv2.cvtColor(view, cv2.COLOR_GRAY2RGB) if view.ndim == 2 else view
        expected = cv2.resize(rgb, (pw, ph), interpolation=cv2.INTER_AREA)
        rows, cols = label_box(label, ph)
        outside = np.ones((ph, pw), bool)
        outside[rows, cols] = False
        assert np.array_equal(tile[outside], expected[outside]), (size, label)
        inside = tile[rows, cols]
        assert np.all(inside == YELLOW, axis=-1).sum() > 20, (size, label)  # the label's text
        assert (inside[..., 2] < 30).sum() > 1.2 * np.all(inside == YELLOW, axis=-1).sum()  # + outline
    # an odd width or height leaves one black column or row
    assert not out[2 * ph:].any() and not out[:, 2 * pw:].any()
    assert all(np.array_equal(v, copy) for (_, v), copy in zip(views, copies))  # views untouched


def test_composite_is_the_sheet_of_four_panels():
    views = panels(1280, 720)
    sheet = draw.sheet(views, 640, 2, tile_height_px=360, interpolation=cv2.INTER_AREA,
                       label_at="bottom", font_scale=0.8)
    assert np.array_equal(draw.composite(views, (1280, 720)), sheet)
    # a fifth panel is left out; fewer than four leave the rest black
    assert np.array_equal(draw.composite(views + [("more", views[0][1])], (1280, 720)), sheet)
    two = draw.composite(views[:2], (1280, 720))
    assert np.array_equal(two[:360], sheet[:360]) and not two[360:].any()
    assert not draw.composite([], (64, 36)).any()


def test_the_pipelines_debug_composite_shows_its_stage_images():
    pipe = LanePipeline()
    frame = textured(1280, 720, 6)
    result = pipe.process(frame, keep_images=True)
    out = pipe.debug_composite(result)
    im = result.images
    expected = draw.composite([("undistorted", im["undistorted"]), ("binary (bird's-eye)", im["binary"]),
                               ("search and fits", im["search"]), ("result", im["result"])], (1280, 720))
    assert np.array_equal(out, expected)
    top_left = cv2.resize(im["undistorted"], (640, 360), interpolation=cv2.INTER_AREA)
    assert np.array_equal(out[:300, :640], top_left[:300])


# --------------------------------------------------------------------------- the lane overlay

K = np.array([[1156.46, 0, 671.32], [0, 1151.27, 389.22], [0, 0, 1]])
DIST = np.array([-0.24667, -0.02544, -0.00067, 0.00013, 0.01067])
FITS = [((0, 0, 320.0), (0, 0, 960.0)), ((4e-4, -0.5, 420.0), (4e-4, -0.5, 1060.0)),
        ((-3e-4, 0.1, 250.0), (-3e-4, 0.1, 900.0)), ((0, 0, -3000.0), (0, 0, 5000.0))]


def old_lane_overlay(image, left_coeffs, right_coeffs, Minv, config, lens=None):
    """The overlay as it was drawn before the transforms: fits through ``Minv``, then ``lens``."""
    out = image.copy()
    mapped = {}
    for side, coeffs in (("left", left_coeffs), ("right", right_coeffs)):
        pts = draw.line_points(coeffs, image.shape[0], config.samples)
        pts = cv2.perspectiveTransform(pts.reshape(-1, 1, 2), Minv).reshape(-1, 2)
        mapped[side] = lens(pts) if lens is not None else pts
    fill = out.copy()
    cv2.fillPoly(fill, [draw.pixel_points(np.vstack([mapped["left"], mapped["right"][::-1]]))],
                 config.lane_color, lineType=cv2.LINE_AA)
    out = cv2.addWeighted(fill, config.lane_alpha, out, 1 - config.lane_alpha, 0)
    for side, color in (("left", config.left_color), ("right", config.right_color)):
        cv2.polylines(out, [draw.pixel_points(mapped[side])], False, color, config.line_thickness_px, cv2.LINE_AA)
    return out


def iou(a: np.ndarray, b: np.ndarray) -> float:
    """Return the intersection over union of two boolean masks (1 when both are empty)."""
    union = (a | b).sum()
    return float((a & b).sum() / union) if union else 1.0


@pytest.mark.parametrize("fits", FITS)
def test_the_overlay_through_transform_objects_is_the_old_drawing(fits):
    pipe = LanePipeline(calibration=Calibration(K, DIST, (1280, 720)))
    cal, cfg = pipe.undistorter.calibration, pipe.config.draw
    image = textured(1280, 720, 7)
    cases = [(pipe.perspective.inverse, old_lane_overlay(image, *fits, pipe.perspective.Minv, cfg)),
             (pipe.birdseye_to_raw, old_lane_overlay(image, *fits, pipe.perspective.Minv, cfg,
                                                     lambda p: distort_points(cal, p)))]
    for to_image, old in cases:
        new = draw.lane_overlay(image, *fits, to_image, cfg)
        assert iou(np.any(new != image, axis=2), np.any(old != image, axis=2)) > 0.99
        assert np.array_equal(new, old)
    # the pipeline passes the perspective's inverse on the undistorted frame, the chain on the raw one
    result = FrameResult(*(LineFit(np.array(c, float), 1000, 700.0) for c in fits),
                         pipe.measure(*(LineFit(np.array(c, float), 1000, 700.0) for c in fits)),
                         "windows", 1.0, 1.0)
    top = holds_from_px(result.left, result.right, 720, 1280, pipe.perspective.xm_per_px)
    assert top == (0 if fits is not FITS[3] else 719)  # lines 3000 px beside the view hold nowhere
    for raw, (to_image, _) in zip((False, True), cases):
        expected = draw.lane_overlay(image, *fits, to_image, cfg, 720, top_px=top)
        drawn = pipe.annotate(image, result, raw=raw)
        below_text = slice(200, None)  # the measurements are written at the top
        assert np.array_equal(drawn[below_text], expected[below_text])


def test_a_lane_is_drawn_only_below_the_row_where_it_holds():
    pipe = LanePipeline(calibration=Calibration(K, DIST, (1280, 720)))
    black = np.zeros((720, 1280, 3), np.uint8)
    xm, cfg = pipe.perspective.xm_per_px, pipe.config.draw
    a = 1.0 / xm / 300**2  # x turns on row 300 and comes back 1 m above it
    cases = {"straight": ((0, 0, 320.0), 719.0, (0, 0, 960.0), 0),
             "right leaves the view": ((0, 0, 320.0), 719.0, (0, -1.0, 1480.0), 201),
             "left hooks back above its pixels": ((a, -600 * a, 320.0), 319.0, (0, 0, 960.0), 300),
             "left turns where its pixels are": ((a, -600 * a, 320.0), 719.0, (0, 0, 960.0), 0),
             "lines cross": ((0, -1.0, 1040.0), 719.0, (0, 0, 960.0), 81)}
    for name, (lc, span, rc, top) in cases.items():
        left, right = LineFit(np.array(lc, float), 1000, span), LineFit(np.array(rc, float), 1000, 719.0)
        assert holds_from_px(left, right, 720, 1280, xm) == top, name
        bird = draw.lane_overlay(black, left.coeffs_px, right.coeffs_px, None, cfg, 720, top_px=top)
        drawn = np.flatnonzero(bird.any(axis=(1, 2)))
        assert top - cfg.line_thickness_px <= drawn.min() <= top + 1, name
        # annotate draws the same rows on the frame
        result = FrameResult(left, right, pipe.measure(left, right), "windows", 1.0, 1.0)
        expected = draw.lane_overlay(black, left.coeffs_px, right.coeffs_px, pipe.perspective.inverse,
                                     cfg, 720, top_px=top)
        assert np.array_equal(pipe.annotate(black, result)[200:], expected[200:]), name


def test_the_overlay_wants_a_transform_not_a_matrix():
    with pytest.raises(InputError, match="perspective.inverse"):
        draw.lane_overlay(textured(64, 36, 1), (0, 0, 10.0), (0, 0, 50.0), np.eye(3))
    plain = draw.lane_overlay(textured(64, 36, 1), (0, 0, 10.0), (0, 0, 50.0), None)  # the bird's-eye view
    assert plain[20, 30].tolist() != textured(64, 36, 1)[20, 30].tolist()


def test_stacked_masks_put_each_mask_in_its_own_colour_channel():
    a = np.zeros((20, 30), np.uint8)
    a[:, 5:10] = 255
    b = np.zeros((20, 30), np.uint8)
    b[:, 8:15] = 255
    view = draw.stacked_masks({"a": a, "b": b, "c": None}, ("a", "b"))
    assert view.shape == (20, 30, 3) and view.dtype == np.uint8
    assert np.array_equal(view[..., 0], a) and np.array_equal(view[..., 1], b) and not view[..., 2].any()
    assert tuple(view[0, 6]) == (255, 0, 0) and tuple(view[0, 12]) == (0, 255, 0)
    assert tuple(view[0, 9]) == (255, 255, 0)  # both: yellow
    three = draw.stacked_masks({"a": a, "b": b, "c": None}, ("b", "c", "a"))
    assert np.array_equal(three[..., 0], b) and not three[..., 1].any() and np.array_equal(three[..., 2], a)


def test_stacked_masks_say_what_is_wrong():
    a = np.zeros((20, 30), np.uint8)
    with pytest.raises(InputError, match="one to three"):
        draw.stacked_masks({"a": a}, ("a", "a", "a", "a"))
    with pytest.raises(InputError, match="no mask 'z'"):
        draw.stacked_masks({"a": a}, ("a", "z"))
    with pytest.raises(InputError, match="common size"):
        draw.stacked_masks({"a": a, "b": np.zeros((5, 5), np.uint8)}, ("a", "b"))
