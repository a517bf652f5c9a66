"""Image and video I/O: clear errors on bad files, atomic outputs."""
from __future__ import annotations

import numpy as np
import pytest

from lanelib import io
from lanelib.errors import InputError


def test_read_image_errors_name_the_file(tmp_path):
    with pytest.raises(InputError, match=f"{tmp_path / 'missing.jpg'}: no such file"):
        io.read_image(tmp_path / "missing.jpg")
    bad = tmp_path / "corrupt.jpg"
    bad.write_bytes(b"\xff\xd8\xff\xe0" + b"garbage" * 10)
    with pytest.raises(InputError, match="corrupt.jpg: not a readable image"):
        io.read_image(bad)
    with pytest.raises(InputError, match="not a file"):
        io.read_image(tmp_path)


def test_image_round_trip_is_rgb(tmp_path):
    img = np.zeros((10, 20, 3), np.uint8)
    img[..., 0] = 200  # red
    path = io.write_image(tmp_path / "x.png", img)
    back = io.read_image(path)
    assert back.shape == (10, 20, 3) and back[0, 0, 0] == 200 and back[0, 0, 2] == 0


def test_atomic_write_leaves_nothing_on_failure(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with io.atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


def test_output_never_over_an_input(tmp_path):
    src = tmp_path / "in.png"
    io.write_image(src, np.zeros((4, 4, 3), np.uint8))
    with pytest.raises(InputError, match="overwrite an input"):
        io.write_image(src, np.ones((4, 4, 3), np.uint8), inputs=[src])


def test_list_images(tmp_path):
    with pytest.raises(InputError, match="holds no images"):
        io.list_images(tmp_path)
    io.write_image(tmp_path / "b.png", np.zeros((4, 4, 3), np.uint8))
    io.write_image(tmp_path / "a.jpg", np.zeros((4, 4, 3), np.uint8))
    (tmp_path / "notes.txt").write_text("x")
    assert [p.name for p in io.list_images(tmp_path)] == ["a.jpg", "b.png"]


def test_video_round_trip(tmp_path):
    path = tmp_path / "v.mp4"
    with io.VideoWriter(path, fps=25) as w:
        for i in range(10):
            w.write(np.full((72, 128, 3), i * 20, np.uint8))
    reader = io.VideoReader(path)
    assert (reader.info.width, reader.info.height, reader.info.fps) == (128, 72, 25.0)
    frames = list(reader)
    assert len(frames) == 10 and abs(int(frames[5].mean()) - 100) <= 3


def test_video_writer_abort_leaves_no_file(tmp_path):
    path = tmp_path / "v.mp4"
    with pytest.raises(KeyboardInterrupt):
        with io.VideoWriter(path, fps=25) as w:
            w.write(np.zeros((72, 128, 3), np.uint8))
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("content,message", [(b"", "empty"), (b"\x00" * 5000, "not a readable video")])
def test_bad_videos(tmp_path, content, message):
    path = tmp_path / "bad.mp4"
    path.write_bytes(content)
    with pytest.raises(InputError, match=f"bad.mp4: .*{message}"):
        io.VideoReader(path)
    with pytest.raises(InputError, match="no such video"):
        io.VideoReader(tmp_path / "none.mp4")
