"""`video` and `hough` on part of a clip: ``--start``/``--end`` (seconds), on the bundled
``videos/project.mp4`` (25 fps, 250 frames, 10 s).

The part is the frames from the first at or after START to the last before END; decoding seeks
to the first (``io.VideoReader(start=...)``) and the frames are the very ones a reader from the
clip's start yields. The per-frame log keeps the source clip's frame index and time.
"""
from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pytest

from lanelib import batch, io
from lanelib.batch import VIDEO_LOG_COLUMNS, clip_frames, video_log_row
from lanelib.batch.pipelines import pipeline_for
from lanelib.cli import main
from lanelib.errors import InputError
from lanelib.tracking import LaneTracker

REPO = Path(__file__).resolve().parents[1]
PROJECT = REPO / "videos" / "project.mp4"


def read_log(path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def project_frames() -> list[np.ndarray]:
    """Frames 0..74 of the clip, decoded one after another from its start."""
    frames = []
    with io.VideoReader(PROJECT) as reader:
        for frame in reader:
            frames.append(frame.copy())
            if len(frames) == 75:
                break
    return frames


def test_the_frames_of_a_part_are_those_of_decoding_from_the_start(project_frames, tmp_path):
    seen = []

    def process(frame, index, time_s):
        seen.append((frame.copy(), index, time_s))
        return frame, {"frame": index, "time_s": time_s}, True

    run = batch.run_video(PROJECT, tmp_path / "part.mp4", process, progress=False, start_s=2.0, end_s=3.0)
    assert (run.frames, run.first_frame, run.found_frames) == (25, 50, 25)
    assert [i for _, i, _ in seen] == list(range(50, 75))
    assert [t for _, _, t in seen] == pytest.approx([i / 25 for i in range(50, 75)])
    for frame, i, _ in seen:
        assert np.array_equal(frame, project_frames[i]), i
    assert np.array_equal(seen[0][0], io.read_frame(PROJECT, 50))
    # the reader alone: frames start .. stop - 1, the same pixels
    with io.VideoReader(PROJECT, start=17, stop=20) as reader:
        part = [f.copy() for f in reader]
    assert len(part) == 3 and all(np.array_equal(f, project_frames[17 + k]) for k, f in enumerate(part))


def test_video_start_2_end_3_tracks_frames_50_to_74(project_frames, tmp_path, capsys):
    out, log = tmp_path / "part.mp4", tmp_path / "part.csv"
    assert main(["video", str(PROJECT), "-o", str(out), "--log", str(log), "--start", "2",
                 "--end", "3", "--no-progress"]) == 0
    printed = capsys.readouterr().out
    assert re.match(rf"{re.escape(str(out))}: 25 frames \(frames 50\.\.74 of {re.escape(str(PROJECT))}\) "
                    r"in [\d.]+ s \([\d.]+ fps\); lane found in 25 of 25 frames; per-frame log in ", printed)
    with io.VideoReader(out) as reader:
        assert reader.info.fps == 25.0 and reader.info.n_frames == 25
        assert sum(1 for _ in reader) == 25
    rows = read_log(log)
    assert list(rows[0]) == list(VIDEO_LOG_COLUMNS)
    assert [int(r["frame"]) for r in rows] == list(range(50, 75))  # the source clip's frames ...
    assert [float(r["time_s"]) for r in rows] == pytest.approx([i / 25 for i in range(50, 75)])  # ... times
    # a fresh tracker on frames 50..74 of the clip gives the rows the log holds
    tracker = LaneTracker(pipeline_for(project_frames[50]))
    for i, row in zip(range(50, 75), rows):
        expected = video_log_row(i, i / 25, tracker.update(project_frames[i]))
        for k, v in expected.items():
            if isinstance(v, str):  # the method
                assert row[k] == v, (i, k)
            else:
                assert float(row[k]) == pytest.approx(v, rel=1e-5, abs=1e-9), (i, k)


def test_a_start_alone_runs_to_the_end_and_an_end_alone_from_the_start(tmp_path, capsys):
    log = tmp_path / "a.csv"
    assert main(["video", str(PROJECT), "-o", str(tmp_path / "a.mp4"), "--log", str(log),
                 "--start", "9.5", "--no-progress"]) == 0
    assert "12 frames (frames 238..249 of" in capsys.readouterr().out  # 9.5 s is between 237 and 238
    assert [int(r["frame"]) for r in read_log(log)] == list(range(238, 250))
    # a start between frames takes the next one; an end between frames, the one before
    assert main(["hough", str(PROJECT), "-o", str(tmp_path / "b.mp4"), "--log", str(log),
                 "--start", "0.01", "--end", "0.5", "--no-progress"]) == 0
    assert "12 frames (frames 1..12 of" in capsys.readouterr().out  # 0.5 s: between 12 and 13
    rows = read_log(log)
    assert [int(r["frame"]) for r in rows] == list(range(1, 13))
    assert [float(r["time_s"]) for r in rows] == pytest.approx([i / 25 for i in range(1, 13)])
    # an end beyond the clip runs to its last frame
    assert clip_frames(io.video_info(PROJECT), None, 99.0) == range(0, 250)
    assert clip_frames(io.video_info(PROJECT), 9.96, None) == range(249, 250)  # the last frame


DURATION = re.escape(f"{PROJECT}: the clip is 10.000 s long (250 frames at 25 fps); ")


@pytest.mark.parametrize("bounds, message", [
    (["--start", "-1"], r"--start -1 s is not a time in it; pass a time in seconds from 0 to 10\.000"),
    (["--end", "nan"], r"--end nan s is not a time in it; pass a time in seconds from 0 to 10\.000"),
    (["--start", "3", "--end", "2"], "--start 3 s is not before --end 2 s; pass a start time before "
                                     "the end time"),
    (["--start", "2", "--end", "2"], "--start 2 s is not before --end 2 s"),
    (["--start", "12"], r"--start 12 s is at or beyond its end; pass a start time from 0 to 9\.960 s"),
    (["--start", "10"], r"--start 10 s is at or beyond its end"),
    (["--start", "9.97"], r"--start 9\.97 s is after its last frame, which starts at 9\.960 s; pass a "
                          r"start time from 0 to 9\.960 s"),
    (["--start", "2.01", "--end", "2.03"], r"no frame starts from 2\.01 s to before --end 2\.03 s "
                                           r"\(frames are 0\.040 s apart\); pass a longer span"),
])
def test_bad_bounds_are_one_line_naming_the_clip_and_exit_2(bounds, message, tmp_path, capsys):
    for command in ("video", "hough"):
        out = tmp_path / command
        code = main([command, str(PROJECT), "-o", str(out / "o.mp4"), "--log", str(out / "o.csv"),
                     *bounds, "--no-progress"])
        err = capsys.readouterr().err.strip().splitlines()
        assert code == 2 and len(err) == 1, err
        assert re.match(f"error: {DURATION}{message}", err[0]), err[0]
        assert not out.exists()  # nothing written
    given = dict(zip(bounds[::2], map(float, bounds[1::2])))  # the library says the same
    with pytest.raises(InputError, match=f"^{DURATION}{message}"):
        clip_frames(io.video_info(PROJECT), given.get("--start"), given.get("--end"))


def test_start_and_end_are_for_videos_and_documented(tmp_path, capsys):
    io.write_image(tmp_path / "in" / "a.png", np.zeros((540, 960, 3), np.uint8))
    assert main(["hough", str(tmp_path / "in"), "-o", str(tmp_path / "out"), "--start", "1"]) == 2
    assert "--start and --end are for videos; drop them for a folder of images" in capsys.readouterr().err
    for command in ("video", "hough"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "--start S" in text and "--end E" in text
        assert "the --log rows keep the source clip's frame index and time_s" in text
        assert "frames 50..74" in text


def test_a_reader_refuses_a_part_outside_the_clip():
    with pytest.raises(InputError, match=r"project.mp4: frame 250 is outside the video \(frames "
                                         r"0\.\.249, 250 frames at 25 fps\); pass a start frame"):
        io.VideoReader(PROJECT, start=250)
    with pytest.raises(InputError, match=r"frames 5 to 5 hold no frame; pass a stop frame after"):
        io.VideoReader(PROJECT, start=5, stop=5)
    with pytest.raises(InputError, match=r"start frame -1 is not a frame index"):
        io.VideoReader(PROJECT, start=-1)
