"""Tuner export: the preview sheet and the annotated frame written as PNG, pixel for pixel what the
tuner shows and what the command line draws with the tuner's config.

PNG is lossless, so a written file read back is the very array: the annotated frame is compared
with the image ``python -m lanelib images`` (or ``hough``) writes for the same input, config and
calibration, and the video tuner's with the frame ``batch.process_video`` hands to the encoder.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from lanelib import batch, io, widgets
from lanelib.batch.video import VideoWriter
from lanelib.cli import main
from lanelib.errors import InputError
from lanelib.pipeline import LanePipeline
from lanelib.widgets import export

REPO = Path(__file__).resolve().parents[1]
CLIP = REPO / "videos" / "project.mp4"
STRAIGHT = "straight_1"
CURVED = "curve_left_600m"



@pytest.fixture(scope="module")
def png_road(tmp_path_factory) -> dict[str, Path]:
    """Two bundled road images copied as PNG (the CLI writes an output in its input's format)."""
    folder = tmp_path_factory.mktemp("road")
    for stem in (STRAIGHT, CURVED):
        io.write_image(folder / f"{stem}.png", io.read_image(REPO / "test_images" / f"{stem}.jpg"))
    return {f"{stem}.png": folder / f"{stem}.png" for stem in (CURVED, STRAIGHT)}


# a move of one control of each tuner that changes the lane it finds or draws
MOVES = {
    widgets.ThresholdTuner: ("white.range1", (150, 255)),
    widgets.PerspectiveTuner: ("top_y", 480.0),
    widgets.FitTuner: ("margin_px", 40),
}


def _cli_images(config_file: Path, in_dir: Path, out_dir: Path, *extra: str) -> None:
    code = main(["images", str(in_dir), "-o", str(out_dir), "--config", str(config_file), *extra])
    assert code == 0


@pytest.mark.parametrize("cls", list(MOVES), ids=lambda c: c.__name__)
def test_the_exported_frame_is_what_the_images_command_writes(cls, camera, png_road, tmp_path, capsys):
    t = cls(png_road, calibration=camera)
    key, value = MOVES[cls]
    t.controls[key].value = value
    assert t.error == "" and t.config != type(t.config)()

    written = t.export(tmp_path / "export")

    kind = cls.__name__.removesuffix("Tuner").lower()
    assert written == {"preview": tmp_path / "export" / f"{CURVED}_{kind}_preview.png",
                       "annotated": tmp_path / "export" / f"{CURVED}_{kind}_annotated.png"}
    assert np.array_equal(io.read_image(written["preview"]), t.preview_sheet())
    # the command line with the tuner's config and calibration draws the very same pixels
    config_file, cal_file = t.save(tmp_path / "tuned.json"), camera.save(tmp_path / "cal.json")
    _cli_images(config_file, png_road[f"{CURVED}.png"].parent, tmp_path / "cli", "--calibration",
                str(cal_file))
    capsys.readouterr()
    cli = io.read_image(tmp_path / "cli" / f"{CURVED}.png")
    annotated = io.read_image(written["annotated"])
    assert annotated.shape == (720, 1280, 3)
    assert np.array_equal(annotated, cli)
    # and it follows the control: the default config draws another frame
    default = LanePipeline(replace(t.config, **{p: getattr(type(t.config)(), p) for p in t.parts}),
                           camera, size=(1280, 720)).process(t.raw).images["result"]
    assert not np.array_equal(annotated, default)


def test_the_hough_export_is_what_the_hough_command_writes(png_road, tmp_path, capsys):
    t = widgets.HoughTuner(png_road, image=f"{STRAIGHT}.png")
    t.controls["threshold_votes"].value = 20
    t.controls["yellow.range2"].value = (120, 255)
    written = t.export(tmp_path / "export", name="tuned")
    assert written == {"preview": tmp_path / "export" / "tuned_preview.png",
                       "annotated": tmp_path / "export" / "tuned_annotated.png"}
    assert np.array_equal(io.read_image(written["preview"]), t.preview_sheet())
    config_file = t.save(tmp_path / "tuned.json")
    assert main(["hough", str(png_road[f"{STRAIGHT}.png"].parent), "-o", str(tmp_path / "cli"),
                 "--config", str(config_file)]) == 0
    capsys.readouterr()
    cli = io.read_image(tmp_path / "cli" / f"{STRAIGHT}.png")
    assert np.array_equal(io.read_image(written["annotated"]), cli)
    assert t.result.left_found and t.result.right_found  # lines were drawn: not the bare frame
    assert not np.array_equal(cli, t.raw)


def test_a_video_frame_exports_the_frame_detected_on_its_own(camera, tmp_path):
    t = widgets.ThresholdTuner({"clip": CLIP, f"{STRAIGHT}.jpg": REPO / "test_images" / f"{STRAIGHT}.jpg"},
                               calibration=camera)
    t.frame = 50
    written = t.export(tmp_path)
    assert written["annotated"].name == "project_frame50_threshold_annotated.png"
    expected = LanePipeline(t.config, camera, size=(1280, 720)).process(
        io.read_frame(CLIP, 50)).images["result"]
    assert np.array_equal(io.read_image(written["annotated"]), expected)
    assert np.array_equal(io.read_image(written["preview"]), t.preview_sheet())


def test_the_video_tuner_exports_the_frame_the_video_command_encodes(camera, tmp_path, monkeypatch):
    n = 12
    t = widgets.VideoTuner({"project": CLIP}, calibration=camera, max_frames=n)
    t.controls["tracking.smooth_frames"].value = 2
    t.frame = 9
    written = t.export(tmp_path / "export")
    assert written["annotated"].name == "project_frame9_video_annotated.png"
    assert np.array_equal(io.read_image(written["preview"]), t.preview_sheet())
    # the frames batch.process_video hands to the encoder, over the same n frames (--end n / fps)
    encoded = []
    real_write = VideoWriter.write
    monkeypatch.setattr(VideoWriter, "write",
                        lambda self, rgb: (encoded.append(rgb.copy()), real_write(self, rgb))[1])
    run = batch.process_video(CLIP, tmp_path / "run.mp4", t.config, camera, progress=False,
                              end_s=n / 25)
    assert run.frames == len(encoded) == n
    assert np.array_equal(io.read_image(written["annotated"]), encoded[9])
    assert not np.array_equal(encoded[9], t.raw)  # the lane was drawn


def test_an_export_never_writes_over_the_picked_input(tmp_path):
    shot = tmp_path / "shot_annotated.png"
    io.write_image(shot, io.read_image(REPO / "test_images" / f"{STRAIGHT}.jpg"))
    before = shot.read_bytes()
    t = widgets.ThresholdTuner({"shot": shot})
    with pytest.raises(InputError, match=rf"^{shot}: output would overwrite an input; choose another"):
        t.write_annotated(shot)
    with pytest.raises(InputError, match=rf"^{shot}: output would overwrite an input"):
        t.write_preview(shot)
    # both names are checked first: the preview is not written when the frame cannot be
    with pytest.raises(InputError, match="overwrite an input"):
        t.export(tmp_path, name="shot")
    assert shot.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["shot_annotated.png"]


def test_an_export_needs_an_image_suffix(tmp_path):
    t = widgets.ThresholdTuner({"straight": REPO / "test_images" / f"{STRAIGHT}.jpg"})
    with pytest.raises(InputError, match=r"notes\.txt: an exported image needs an image suffix "
                                         r"\(\.jpg, .*\); e\.g\. notes\.txt\.png"):
        t.write_preview(tmp_path / "notes.txt")
    assert list(tmp_path.iterdir()) == []
    assert t.write_preview(tmp_path / "view.jpg") == tmp_path / "view.jpg"  # JPEG if asked
    assert io.read_image(tmp_path / "view.jpg").shape == t.preview_sheet().shape


def test_the_export_button_writes_to_out_and_lists_the_files(tmp_path, monkeypatch):
    monkeypatch.setattr(export, "repo_root", lambda: tmp_path)
    t = widgets.HoughTuner({"straight": REPO / "test_images" / f"{STRAIGHT}.jpg"})
    button = t.export_button
    assert "lanelib-control-export" in button._dom_classes
    assert button in t.widget.children[0].children  # beside the picker
    button.click()
    out = tmp_path / "out"
    assert sorted(p.name for p in out.iterdir()) == [f"{STRAIGHT}_hough_annotated.png",
                                                     f"{STRAIGHT}_hough_preview.png"]
    assert f"exported: {out / STRAIGHT}_hough_preview.png, {out / STRAIGHT}_hough_annotated.png" \
        in t.message.value
    assert "Hough segments" in t.message.value  # the readout stays
    # a failed export says why in the readout and raises nothing
    blocked = tmp_path / "blocked"
    blocked.write_text("a file where the repository's folder should be")
    monkeypatch.setattr(export, "repo_root", lambda: blocked)
    button.click()
    assert t.error.startswith(f"{blocked / 'out' / STRAIGHT}_hough_preview.png: cannot be written")
    assert "color:#c00" in t.message.value and "exported" not in t.message.value
