"""Image and video I/O: clear errors on bad files, atomic outputs."""
from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import cv2
import imageio_ffmpeg
import numpy as np
import pytest

from lanelib import io
from lanelib.batch.video import VideoWriter
from lanelib.errors import DecodeStoppedError, InputError


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
    with VideoWriter(path, fps=25) as w:
        for i in range(10):
            w.write(np.full((72, 128, 3), i * 20, np.uint8))
    reader = io.VideoReader(path)
    assert (reader.info.width, reader.info.height, reader.info.fps) == (128, 72, 25.0)
    frames = list(reader)
    assert len(frames) == 10 and abs(int(frames[5].mean()) - 100) <= 3


def test_video_writer_abort_leaves_no_file(tmp_path):
    path = tmp_path / "v.mp4"
    with pytest.raises(KeyboardInterrupt):
        with VideoWriter(path, fps=25) as w:
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


# --------------------------------------------------------------------------- odd images

def _write_raw(path, array) -> None:
    """Write ``array`` as OpenCV stores it (BGR order, any depth), bypassing lanelib."""
    ok, buf = cv2.imencode(path.suffix, array)
    assert ok
    path.write_bytes(buf.tobytes())


def test_grey_rgba_and_16_bit_images_read_as_rgb_uint8(tmp_path):
    grey = np.arange(12, dtype=np.uint8).reshape(3, 4) * 20
    _write_raw(tmp_path / "grey.png", grey)
    rgb, info = io.read_image_info(tmp_path / "grey.png")
    assert rgb.shape == (3, 4, 3) and rgb.dtype == np.uint8
    assert all(np.array_equal(rgb[..., c], grey) for c in range(3))
    assert (info.channels, info.bit_depth, info.colour) == (1, 8, False)

    bgra = np.zeros((2, 3, 4), np.uint8)
    bgra[..., 0], bgra[..., 1], bgra[..., 2], bgra[..., 3] = 10, 20, 30, 0  # fully transparent
    _write_raw(tmp_path / "rgba.png", bgra)
    rgb, info = io.read_image_info(tmp_path / "rgba.png")
    assert rgb.shape == (2, 3, 3) and rgb[0, 0].tolist() == [30, 20, 10]  # alpha dropped, RGB order
    assert (info.channels, info.bit_depth, info.colour) == (3, 8, True)

    # 16 bits -> 8 by the high byte: 65535 -> 255, 0x1234 -> 0x12, 257 -> 1, 255 -> 0
    values = np.array([[65535, 0x1234, 257, 255]], np.uint16)
    bgr16 = np.stack([values, values // 2, np.zeros_like(values)], axis=-1)
    _write_raw(tmp_path / "c16.png", bgr16)
    rgb, info = io.read_image_info(tmp_path / "c16.png")
    assert rgb[0, :, 2].tolist() == [255, 0x12, 1, 0]        # B
    assert rgb[0, :, 1].tolist() == [127, 0x09, 0, 0]        # G = values // 2
    assert (info.channels, info.bit_depth, info.colour) == (3, 16, True)
    _write_raw(tmp_path / "g16.png", values)
    rgb, info = io.read_image_info(tmp_path / "g16.png")
    assert rgb[0, :, 0].tolist() == [255, 0x12, 1, 0] and (info.bit_depth, info.colour) == (16, False)
    assert np.array_equal(io.read_image(tmp_path / "g16.png"), rgb)


def test_a_colour_file_of_a_grey_scene_has_no_colour(tmp_path):
    io.write_image(tmp_path / "flat.png", np.full((4, 4, 3), 90, np.uint8))
    assert io.read_image_info(tmp_path / "flat.png")[1].colour is False
    io.write_image(tmp_path / "red.png", np.full((4, 4, 3), (90, 90, 91), np.uint8))
    assert io.read_image_info(tmp_path / "red.png")[1].colour is True


def test_unreadable_images_are_one_line_naming_the_file_and_the_fix(tmp_path, capfd):
    good = io.encode_image(np.random.default_rng(0).integers(0, 255, (60, 80, 3), dtype=np.uint8))
    cases = {
        "empty.jpg": (b"", re.escape("the file is empty (0 bytes)")),
        "text.png": (b"hello, not an image\n", "not a readable image"),
        "cut.png": (good[:len(good) // 2], r"not a readable image \((libpng error: )?PNG input buffer is incomplete\)"),
    }
    for name, (data, message) in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(InputError, match=re.escape(f"{tmp_path / name}: ") + message) as e:
            io.read_image(tmp_path / name)
        assert "\n" not in str(e.value) and str(e.value).endswith("replace it with a valid jpg or png")
    (tmp_path / "link.jpg").symlink_to(tmp_path / "gone.jpg")
    with pytest.raises(InputError, match="link.jpg: a broken symbolic link"):
        io.read_image(tmp_path / "link.jpg")
    cv2.imwrite(str(tmp_path / "float.tif"), np.zeros((4, 4, 3), np.float32))
    with pytest.raises(InputError, match="float.tif: float32 samples are not supported"):
        io.read_image(tmp_path / "float.tif")
    assert capfd.readouterr().err == ""  # libpng's own message went into the error, not to stderr


def test_an_unreadable_file_is_an_input_error(tmp_path):
    if os.geteuid() == 0:
        pytest.skip("running as root: chmod 000 does not stop root from reading")
    f = tmp_path / "locked.jpg"
    io.write_image(f, np.zeros((4, 4, 3), np.uint8))
    f.chmod(0)
    try:
        with pytest.raises(InputError, match="locked.jpg: cannot be read .*; check its permissions"):
            io.read_image(f)
    finally:
        f.chmod(0o644)


def test_a_corrupt_jpeg_that_still_decodes_keeps_the_decoders_warning(tmp_path, capfd):
    data = bytearray(io.encode_image(np.random.default_rng(1).integers(0, 255, (64, 64, 3), np.uint8),
                                     ".jpg"))
    for i in range(len(data) // 2, len(data) // 2 + 40, 7):  # damage the entropy-coded data
        data[i] ^= 0xFF
    (tmp_path / "damaged.jpg").write_bytes(bytes(data))
    rgb, info = io.read_image_info(tmp_path / "damaged.jpg")
    assert rgb.shape == (64, 64, 3)
    assert any("Corrupt JPEG data" in m for m in info.decoder_messages), info.decoder_messages
    assert capfd.readouterr().err == ""


def test_list_images_lists_entries_that_are_not_files(tmp_path):
    (tmp_path / "x.jpg").mkdir()
    (tmp_path / "link.png").symlink_to(tmp_path / "gone.png")
    (tmp_path / "sub").mkdir()
    assert [p.name for p in io.list_images(tmp_path)] == ["link.png", "x.jpg"]
    with pytest.raises(InputError, match="x.jpg: not a file"):
        io.read_image(tmp_path / "x.jpg")


# --------------------------------------------------------------------------- odd videos

PROJECT = Path(__file__).resolve().parents[1] / "videos" / "project.mp4"


def test_a_truncated_mp4_without_its_index_is_unreadable(tmp_path):
    data = PROJECT.read_bytes()
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(data[:int(0.3 * len(data))])  # ffmpeg writes the index (moov) last
    with pytest.raises(InputError, match="cut.mp4: not a readable video \\(moov atom not found: the "
                                         "mp4 has no index"):
        io.VideoReader(cut)


def test_an_unknown_codec_and_a_file_without_frames_are_unreadable(tmp_path, faststart):
    data = bytearray(PROJECT.read_bytes())
    i = data.index(b"avc1", data.index(b"stsd"))  # the sample entry's codec tag
    data[i:i + 4] = b"zzzz"
    (tmp_path / "codec.mp4").write_bytes(bytes(data))
    with pytest.raises(InputError, match="codec.mp4: not a readable video .*unknown codec"):
        io.VideoReader(tmp_path / "codec.mp4")
    zero = tmp_path / "zero.mp4"  # a valid mp4 of no frames
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-i", str(PROJECT), "-c", "copy",
                    "-frames:v", "0", str(zero)], check=True)
    with pytest.raises(InputError, match=re.escape(f"{zero}: not a readable video (the file holds no "
                                                   "video stream); pass a valid video (mp4, H.264)")):
        io.VideoReader(zero)
    # the index and the first few kB of the first frame: nothing can be decoded
    head = faststart.read_bytes()
    (tmp_path / "head.mp4").write_bytes(head[:head.index(b"mdat") + 5000])
    with pytest.raises(InputError, match="head.mp4: not a readable video") as e:
        list(io.VideoReader(tmp_path / "head.mp4"))
    assert not isinstance(e.value, DecodeStoppedError)


def test_a_video_cut_half_way_stops_with_the_frames_before(tmp_path, faststart):
    data = faststart.read_bytes()
    cut = tmp_path / "cut.mp4"
    cut.write_bytes(data[:len(data) // 10])
    reader = io.VideoReader(cut)
    assert reader.info.n_frames == 250  # what the (complete) index announces
    frames = []
    with pytest.raises(DecodeStoppedError) as e:
        for frame in reader:
            frames.append(frame)
    n = len(frames)
    assert 10 < n < 40 and e.value.frames == n  # about a tenth of the 250 frames
    assert str(e.value) == (f"{cut}: decoding stopped at frame {n}: the file ends after {n} of the "
                            "250 frames its container announces (truncated?)")
    # the frames before the break are the complete file's first frames
    with io.VideoReader(faststart) as whole:
        first = [f for _, f in zip(range(n), whole)]
    assert all(np.abs(a.astype(int) - b).max() == 0 for a, b in zip(frames[:-1], first[:-1]))


def test_a_jpegs_exif_orientation_is_applied_as_before(tmp_path):
    Image = pytest.importorskip("PIL.Image")  # matplotlib's dependency; writes the EXIF tag
    a = np.zeros((20, 40, 3), np.uint8)
    a[:, :10] = 255  # a white band on the left
    im = Image.fromarray(a)
    exif = im.getexif()
    exif[0x0112] = 6  # "rotate 90 degrees clockwise to display"
    im.save(tmp_path / "rot.jpg", exif=exif)
    rgb = io.read_image(tmp_path / "rot.jpg")
    assert rgb.shape == (40, 20, 3)
    assert rgb[:10].mean() > 200 and rgb[-10:].mean() < 50  # the band is now on top


# --------------------------------------------------------------------------- one frame by seeking

PROJECT = Path(__file__).resolve().parents[1] / "videos" / "project.mp4"
SEEK_INDICES = (0, 1, 17, 120, 249)  # 249: the last frame of the 250


@pytest.fixture(scope="module")
def project_frames() -> dict[int, np.ndarray]:
    """The frames SEEK_INDICES of videos/project.mp4, decoded one after another from the start."""
    with io.VideoReader(PROJECT) as reader:
        return {i: f.copy() for i, f in enumerate(reader) if i in SEEK_INDICES}


def test_a_seeked_frame_is_the_frame_sequential_decoding_gives(project_frames):
    info = io.video_info(PROJECT)
    assert (info.n_frames, info.fps) == (250, 25.0)
    assert sorted(project_frames) == list(SEEK_INDICES)
    for i, expected in project_frames.items():
        frame = io.read_frame(PROJECT, i, info=info)
        assert frame.dtype == np.uint8 and frame.shape == (720, 1280, 3), i
        assert np.array_equal(frame, expected), i
    frame = io.read_frame(PROJECT, 17)  # without info: the file's info is read first
    assert np.array_equal(frame, project_frames[17]) and frame.flags.writeable


def test_time_s_picks_the_frame_that_shows_at_that_time(project_frames):
    info = io.video_info(PROJECT)
    for t, i in [(0.0, 0), (0.039, 0), (0.04, 1), (17 / 25, 17), (17 / 25 - 1e-9, 17),
                 (17.9 / 25, 17), (4.8, 120), (9.999, 249)]:
        assert np.array_equal(io.read_frame(PROJECT, time_s=t, info=info), project_frames[i]), t


def test_seeking_is_frame_accurate_at_an_ntsc_frame_rate(tmp_path):
    # 29.97 fps: frame times are not round numbers, so a seek to the exact time could land a
    # hair after a frame's timestamp; each frame is a different grey level, to tell them apart
    path = tmp_path / "ntsc.mp4"
    with VideoWriter(path, fps=30000 / 1001) as w:
        for i in range(40):
            w.write(np.full((48, 64, 3), 6 * i, np.uint8))
    with io.VideoReader(path) as reader:
        frames = [f.copy() for f in reader]
    info = io.video_info(path)
    assert info.n_frames == len(frames) == 40
    for i in (0, 1, 2, 13, 29, 30, 38, 39):
        assert np.array_equal(io.read_frame(path, i, info=info), frames[i]), i
    assert np.array_equal(io.read_frame(path, time_s=30 * 1001 / 30000, info=info), frames[30])


@pytest.mark.parametrize("kwargs,message", [
    (dict(index=250), r"frame 250 is outside the video \(frames 0\.\.249, 250 frames at 25 fps\); "
                      "pass an index in that range"),
    (dict(index=-1), r"frame -1 is outside the video \(frames 0\.\.249"),
    (dict(index=1.5), r"frame index 1\.5 is not an integer; pass an index 0\.\.249"),
    (dict(time_s=10.0), r"time 10\.0 s is outside the video \(0 to 10\.000 s, 250 frames at 25 fps\); "
                        "pass a time in that range"),
    (dict(time_s=-0.1), "time -0.1 s is outside the video"),
    (dict(), r"read_frame needs a frame index or a time in seconds \(got neither\); "
             "pass index=N or time_s=T"),
    (dict(index=3, time_s=0.1), r"read_frame needs .* \(got both\)"),
])
def test_a_frame_outside_the_video_is_an_input_error_with_the_range(kwargs, message):
    with pytest.raises(InputError, match=f"^{re.escape(str(PROJECT))}: {message}"):
        io.read_frame(PROJECT, **kwargs)


def test_read_frame_on_a_missing_corrupt_or_cut_video_names_the_file(tmp_path, faststart):
    with pytest.raises(InputError, match="none.mp4: no such video file; check the path"):
        io.read_frame(tmp_path / "none.mp4", 0)
    bad = tmp_path / "bad.mp4"
    bad.write_bytes(b"\x00" * 5000)
    with pytest.raises(InputError, match=r"bad.mp4: not a readable video \(.*\); pass a valid video"):
        io.read_frame(bad, 0)
    # a file cut after a tenth of its bytes still announces 250 frames: the late ones are gone
    cut = tmp_path / "cut.mp4"
    data = faststart.read_bytes()
    cut.write_bytes(data[:len(data) // 10])
    assert io.video_info(cut).n_frames == 250
    assert io.read_frame(cut, 0).shape == (720, 1280, 3)
    with pytest.raises(InputError, match=r"cut.mp4: frame 240 could not be decoded \(no frame: the "
                                         "file ends before the 250 frames its container announces"):
        io.read_frame(cut, 240)


def test_exact_fps_reads_a_rounded_ntsc_rate_as_n_times_1000_over_1001():
    assert io.exact_fps(29.97) == 30000 / 1001 and io.exact_fps(23.98) == 24000 / 1001
    assert io.exact_fps(59.94) == 60000 / 1001
    assert io.exact_fps(25.0) == 25.0 and io.exact_fps(30.0) == 30.0 and io.exact_fps(29.5) == 29.5
