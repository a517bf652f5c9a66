"""Tests of the batch runs on Dask (``images``, ``hough``, ``video`` with ``--workers`` or
``--scheduler``; ``cluster.segments``, ``batch.segments.join_videos``): the outputs are those of one process,
a bad item is recorded and the run goes on, a bad scheduler writes nothing.

Kept small for CI: one ``LocalCluster`` of 2 one-thread workers for the module (the commands get
its address as ``--scheduler``, as a separate cluster would be used), a 130-frame 640x360 clip cut
from ``videos/harder.mp4`` (its joint settles in the warm-up), a 110-frame 640x360 one from
``videos/country.mp4`` (its joint does not: the segment is run again from the previous one's
tracker, ``cluster.settle_joints``), four test images. The two synthetic hard clips are tracked
with the ``hard-roads`` preset (the hard-road parts are off by default): without it the harder
clip's lane is not found on any of frames 10..69 (the two trackers at the joint differ only in
their count of lost frames, so it never settles), and at country's joint the state of the
default parts no longer depends on the frames before the warm-up (it settles).
"""
from __future__ import annotations

import json
import pickle
from dataclasses import replace
import shutil
import socket
import subprocess
from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest

from lanelib import batch, cluster, evaluate, hough, io
from lanelib.batch.pipelines import pipeline_for
from lanelib.batch.segments import join_videos
from lanelib.batch.video import VideoWriter
from lanelib.cli import main
from lanelib.config import preset
from lanelib.errors import InputError
from lanelib.pipeline import LanePipeline
from lanelib.tracking import LaneTracker

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def scheduler() -> str:
    """The address of a LocalCluster of 2 one-thread worker processes, shared by the module."""
    with cluster.dask_client(2) as client:
        yield client.scheduler.address


@pytest.fixture(scope="module")
def clip(tmp_path_factory) -> Path:
    """130 frames (5.2 s at 25 fps) of videos/harder.mp4 at 640x360."""
    out = tmp_path_factory.mktemp("clip") / "small.mp4"
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-y", "-i", str(REPO / "videos/harder.mp4"),
                    "-frames:v", "130", "-vf", "scale=640:360", "-c:v", "libx264", "-preset", "ultrafast",
                    "-pix_fmt", "yuv420p", str(out)], check=True)
    return out


@pytest.fixture(scope="module")
def country(tmp_path_factory) -> Path:
    """110 frames of videos/country.mp4 at 640x360: two segments 0..54 and 55..109, the second
    warmed up from frame 5; on the hairpin the tracker's state at frame 54 depends on frames
    before 5 (the rows of frames 55..109 differ unless the joint is run again)."""
    out = tmp_path_factory.mktemp("country") / "country.mp4"
    subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-v", "error", "-y", "-i",
                    str(REPO / "videos/country.mp4"), "-frames:v", "110", "-vf", "scale=640:360", "-c:v", "libx264", "-preset", "ultrafast",
                    "-pix_fmt", "yuv420p", str(out)], check=True)
    return out


def frames(path: Path) -> list[np.ndarray]:
    with io.VideoReader(path) as reader:
        return [f.copy() for f in reader]


# --------------------------------------------------------------------------- pieces

def test_segments_cover_the_frames_in_order_with_their_warm_up():
    assert cluster.segments(range(10, 130), 2, 50) == [(10, 10, 70), (20, 70, 130)]
    assert cluster.segments(range(0, 7), 3) == [(0, 0, 2), (2, 2, 4), (4, 4, 7)]
    assert cluster.segments(range(0, 2), 5) == [(0, 0, 1), (1, 1, 2)]  # no empty segment
    assert cluster.segment_count(120, 2) == 2  # short: one per worker
    assert cluster.segment_count(1260, 2) == 3  # each at least 8 warm-ups long
    assert cluster.segment_count(100_000, 2) == 2 * cluster.CHUNKS_PER_THREAD


def test_a_hough_segment_warms_up_until_its_smoothing_forgot_the_start():
    """0.7 ** n below a double's precision (2**-53): 103 frames, and a fifth more."""
    assert hough.settle_frames(hough.HoughConfig()) == 124
    assert hough.settle_frames(hough.HoughConfig(smoothing_alpha=1.0)) == 1  # no smoothing


def test_join_videos_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    shown = []
    for name, n in (("a.mp4", 5), ("b.mp4", 7)):
        with VideoWriter(tmp_path / name, 25) as w:
            for _ in range(n):
                shown.append(np.repeat(rng.integers(0, 256, (6, 8, 3), np.uint8), 8, 0).repeat(8, 1))
                w.write(shown[-1])
    out = join_videos([tmp_path / "a.mp4", tmp_path / "b.mp4"], tmp_path / "ab.mp4")
    got = frames(out)
    assert len(got) == 12
    assert io.video_info(out).fps == 25
    # the parts' own frames, not re-encoded: each as close to what was shown as in its part
    parts = frames(tmp_path / "a.mp4") + frames(tmp_path / "b.mp4")
    assert all(np.array_equal(g, p) for g, p in zip(got, parts))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.mp4", "ab.mp4", "b.mp4"]  # no temporaries
    with pytest.raises(InputError, match="no video parts"):
        join_videos([], tmp_path / "none.mp4")


def test_a_pipeline_pickles_as_its_config_calibration_and_size():
    pipe = LanePipeline()
    wire = pickle.dumps(pipe)
    assert len(wire) < 20_000  # no remap maps on the wire: they are built again
    again = pickle.loads(wire)
    assert again.size == pipe.size and again.config == pipe.config
    raw = io.read_image(REPO / "test_images/straight_1.jpg")
    assert again.detect(raw).summary() == pipe.detect(raw).summary()


def test_a_trackers_state_key_says_whether_two_runs_go_on_alike(country):
    """Equal keys: equal results on the next frames, whichever frame each tracker started from.
    With the ``hard-roads`` preset: its parts' memory (the trend, the shoulders, ...) at frame 54
    of country's hairpin still bears the mark of the frames before 5."""
    shown = frames(country)[:64]
    pipe = pipeline_for(shown[0], preset("hard-roads"), None)

    def run(tracker, first, stop):
        return [repr(tracker.update(f)) for f in shown[first:stop]]  # repr: NaN equals NaN

    whole, late = LaneTracker(pipe), LaneTracker(pipe)
    assert whole.state_key() == late.state_key()  # two fresh trackers
    run(whole, 0, 55)
    run(late, 5, 55)  # a Dask segment's warm-up of 50 frames: not enough on the hairpin
    assert whole.state_key() != late.state_key()
    copied = pickle.loads(pickle.dumps(whole))  # what a re-run starts from
    assert copied.state_key() == whole.state_key() != LaneTracker(pipe).state_key()
    assert run(copied, 55, 64) == run(whole, 55, 64) != run(late, 55, 64)
    assert copied.state_key() == whole.state_key()
    # frame numbers count back from the last frame tracked: a start 100 frames later, the same key
    state = copied.state
    state.frame += 100
    state.history = type(state.history)([replace(a, frame=a.frame + 100) for a in state.history],
                                        state.history.maxlen)
    state.trend = type(state.trend)([replace(a, frame=a.frame + 100) for a in state.trend],
                                    state.trend.maxlen)
    assert copied.state_key() == whole.state_key()
    assert pickle.loads(pickle.dumps(state)) == whole.state != LaneTracker(pipe).state


def test_settle_joints_reruns_in_a_chain_from_the_state_before():
    """Joint 1 settled, joint 2 not: segment 2 runs again from segment 1's state, and joint 3 is
    checked against the state the re-run ended in."""
    seg = [cluster.Carry(None, b"a", "A"), cluster.Carry(b"a", b"b", "B"),
           cluster.Carry(b"x", b"c", "C"), cluster.Carry(b"c2", b"d", "D")]
    calls = []

    def rerun(k, state):
        calls.append((k, state))
        return cluster.Carry(None, {2: b"c2", 3: b"d"}[k], state + "'")

    out, joints = cluster.settle_joints(seg, lambda c: c, rerun)
    assert calls == [(2, "B")] and out[2].end_state == "B'" and out[3] is seg[3]
    assert joints == cluster.Joints(3, 1) and str(joints) == (
        "4 segments; 2 of 3 joints settled in the warm-up, 1 re-run")
    seg[3] = cluster.Carry(b"c", b"d", "D")  # settled against the first run's end, not the re-run's
    out, joints = cluster.settle_joints(seg, lambda c: c, rerun)
    assert [k for k, _ in calls[1:]] == [2, 3] and joints.rerun == 2
    # a segment the clip broke off in ends the checks
    out, joints = cluster.settle_joints(seg, lambda c: c, rerun, ended=lambda c: c.end_state == "B")
    assert joints == cluster.Joints(1, 0)


def test_settle_joints_carries_evidence_on_where_the_cores_agree():
    """Keys differ, cores agree: ``rebase`` carries the state on (no re-run) unless it says None."""
    seg = [cluster.Carry(None, b"a", "A", None, b"core"), cluster.Carry(b"a2", b"b", "B", b"core", b"core"),
           cluster.Carry(b"x", b"c", "C", b"other", b"core")]
    reruns = []

    def rerun(k, state):
        reruns.append(k)
        return cluster.Carry(None, b"c", state + "'", None, b"core")

    def rebase(k, state, outcome):
        return replace(outcome, end_state=state + "+" + outcome.end_state, end_key=b"b")

    out, joints = cluster.settle_joints(seg, lambda c: c, rerun, rebase=rebase)
    assert out[1].end_state == "A+B" and reruns == [2] and out[2].end_state == "A+B'"
    assert joints == cluster.Joints(2, 1, 1) and str(joints) == (
        "3 segments; 0 of 2 joints settled in the warm-up, 1 carried on by the evidence alone, 1 re-run")
    out, joints = cluster.settle_joints(seg, lambda c: c, rerun, rebase=lambda k, s, o: None)
    assert joints == cluster.Joints(2, 2, 0)


def test_settle_joints_restarts_the_planned_segments_in_one_round_then_checks_them():
    """``plan`` names the segments that started from a wrong state (from the records alone):
    they run again at once, then every joint is checked as usual (one still off: re-run)."""
    seg = [cluster.Carry(None, b"a", "A"), cluster.Carry(b"x", b"b", "B"), cluster.Carry(b"y", b"c", "C"),
           cluster.Carry(b"z", b"d", "D")]
    restarts, reruns = [], []

    def restart(states):
        restarts.append(dict(states))
        return {k: cluster.Carry({1: b"a", 2: b"b", 3: b"q"}[k], seg[k].end_key, s) for k, s in states.items()}

    def rerun(k, state):
        reruns.append(k)
        return cluster.Carry(None, seg[k].end_key, state + "'")

    out, joints = cluster.settle_joints(seg, lambda c: c, rerun, plan=lambda o: {1: "P1", 2: "P2", 3: "P3"},
                                        restart=restart)
    assert restarts == [{1: "P1", 2: "P2", 3: "P3"}] and reruns == [3]
    assert [c.end_state for c in out] == ["A", "P1", "P2", "P2'"]  # from the restarted state before it
    assert joints == cluster.Joints(3, 1, 0, 3) and joints.rounds == 2
    assert str(joints) == ("4 segments; 2 of 3 joints settled in the warm-up, 1 re-run "
                           "(3 segments first run again at once from the state the records gave)")
    out, joints = cluster.settle_joints(seg, lambda c: c, rerun, plan=lambda o: {}, restart=restart)
    assert len(restarts) == 1 and joints == cluster.Joints(3, 3) and joints.rounds == 3


# --------------------------------------------------------------------------- runs

def test_video_on_dask_gives_the_log_of_one_process(tmp_path, clip, scheduler, capsys):
    """Two segments (frames 10..69, 70..129), the second warmed up from frame 20: the same rows
    (the ``hard-roads`` preset: the lane of the harder clip is found and tracked)."""
    args = ["video", str(clip), "--start", "0.4", "--config", "hard-roads", "--no-progress"]
    assert main([*args, "-o", str(tmp_path / "one.mp4"), "--log", str(tmp_path / "one.csv")]) == 0
    assert main([*args, "-o", str(tmp_path / "two.mp4"), "--log", str(tmp_path / "two.csv"),
                 "--scheduler", scheduler]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].split(" in ")[0] == out[1].split(" in ")[0].replace("two.mp4", "one.mp4")
    assert "120 frames (frames 10..129" in out[1]
    assert out[2] == "dask: 2 segments; 1 of 1 joint settled in the warm-up, 0 re-run"
    assert (tmp_path / "two.csv").read_text() == (tmp_path / "one.csv").read_text()
    assert len(frames(tmp_path / "two.mp4")) == 120
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.csv", "one.mp4", "two.csv", "two.mp4"]


def test_a_joint_that_does_not_settle_in_the_warm_up_is_run_again(tmp_path, country, scheduler, capsys):
    """country's hairpin: the second segment runs again from the first one's tracker; the log
    and the frames are those of one process (the ``hard-roads`` preset)."""
    args = ["video", str(country), "--config", "hard-roads", "--no-progress"]
    assert main([*args, "-o", str(tmp_path / "one.mp4"), "--log", str(tmp_path / "one.csv")]) == 0
    assert main([*args, "-o", str(tmp_path / "two.mp4"), "--log", str(tmp_path / "two.csv"),
                 "--scheduler", scheduler]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[2] == "dask: 2 segments; 0 of 1 joint settled in the warm-up, 1 re-run"
    assert (tmp_path / "two.csv").read_text() == (tmp_path / "one.csv").read_text()
    assert len(frames(tmp_path / "two.mp4")) == 110
    assert sorted(p.name for p in tmp_path.iterdir()) == ["one.csv", "one.mp4", "two.csv", "two.mp4"]


def test_video_with_auto_geometry_on_dask_gives_the_log_of_one_process(tmp_path, scheduler, capsys):
    """videos/project.mp4 with --auto-geometry: the second segment's fresh geometry watch holds
    other straight checks than the first one's at the joint; the first one's are carried
    through the second segment's record (no refinement in it), not run again."""
    clip = REPO / "videos" / "project.mp4"
    args = ["video", str(clip), "--auto-geometry", "--no-progress"]
    assert main([*args, "-o", str(tmp_path / "one.mp4"), "--log", str(tmp_path / "one.csv")]) == 0
    assert main([*args, "-o", str(tmp_path / "two.mp4"), "--log", str(tmp_path / "two.csv"),
                 "--scheduler", scheduler]) == 0
    out = capsys.readouterr().out
    assert "dask: 2 segments; 0 of 1 joint settled in the warm-up, 1 carried on by the evidence alone, 0 re-run" in out
    assert (tmp_path / "two.csv").read_text() == (tmp_path / "one.csv").read_text()


@pytest.mark.slow
def test_a_refinement_early_in_a_run_restarts_the_later_segments_in_one_round(
        bend_then_straight, refine_options, tmp_path, scheduler, monkeypatch):
    """The synthetic clip whose vanishing point is refined at frame 192 (tests/test_geometry_runs.py),
    in 4 segments of 100 frames: every segment from the one the refinement fires in on started
    from the first estimate; the records of the checks tell so, and they run again at once from
    the one process's watch (one round, not one joint after another): the log of one process."""
    monkeypatch.setattr(cluster, "MIN_SEGMENT_WARMUPS", 2)  # 400 frames on 2 workers: 4 segments
    logs, done = {}, {}
    for name, extra in (("one", {}), ("two", {"scheduler": scheduler})):
        logs[name] = tmp_path / f"{name}.csv"
        done[name] = batch.process_video(bend_then_straight, tmp_path / f"{name}.mp4", log_path=logs[name],
                                         progress=False, auto_geometry=refine_options, **extra)
    one, two = done["one"], done["two"]
    refined = [int(n.split()[1]) for n in one.notes if "refined:" in n]
    assert refined and refined[0] < 200, one.notes  # in the second segment (100..199)
    assert two.notes == one.notes
    assert logs["two"].read_text() == logs["one"].read_text()
    assert two.joints.joints == 3 and two.joints.restarted == 3, two.joints
    assert two.joints.rounds == 1, two.joints


def test_hough_video_on_dask_gives_the_log_of_one_process(tmp_path, clip, scheduler):
    args = ["hough", str(clip), "--no-progress"]
    assert main([*args, "-o", str(tmp_path / "one.mp4"), "--log", str(tmp_path / "one.csv")]) == 0
    assert main([*args, "-o", str(tmp_path / "two.mp4"), "--log", str(tmp_path / "two.csv"),
                 "--scheduler", scheduler]) == 0
    assert (tmp_path / "two.csv").read_text() == (tmp_path / "one.csv").read_text()


@pytest.fixture
def image_folder(tmp_path) -> Path:
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("straight_1.jpg", "curve_right_400m_shadows.jpg", "curve_left_250m.jpg"):
        shutil.copy(REPO / "test_images" / name, folder / name)
    (folder / "broken.jpg").write_bytes(b"not a jpeg")
    return folder


@pytest.mark.parametrize("command", ["images", "hough"])
def test_images_on_dask_give_the_results_of_one_process(tmp_path, image_folder, scheduler, capsys, command):
    """A bad file gets its error row and one `error:` line, the others run (exit 1), as in one process."""
    results = []
    for name, extra in (("one", []), ("two", ["--scheduler", scheduler])):
        assert main([command, str(image_folder), "-o", str(tmp_path / name), "--no-progress", *extra]) == 1
        err = capsys.readouterr().err
        assert err.count("error:") == 1 and "broken.jpg" in err
        results.append(json.loads((tmp_path / name / "results.json").read_text()))
        assert sorted(p.name for p in (tmp_path / name).iterdir()) == sorted(
            ["results.json", "curve_left_250m.jpg", "straight_1.jpg", "curve_right_400m_shadows.jpg"])
    assert results[1] == results[0]
    assert [r["file"] for r in results[1]] == ["broken.jpg", "curve_left_250m.jpg",
                                               "curve_right_400m_shadows.jpg", "straight_1.jpg"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("command", ["video", "images"])
def test_a_bad_scheduler_writes_nothing(tmp_path, clip, image_folder, capsys, monkeypatch, command):
    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT_S", 1)
    source = clip if command == "video" else image_folder
    out = tmp_path / ("out.mp4" if command == "video" else "out")
    assert main([command, str(source), "-o", str(out), "--no-progress",
                 "--scheduler", f"tcp://127.0.0.1:{free_port()}"]) == 2
    assert "no Dask scheduler answered" in capsys.readouterr().err
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["in"]


# --------------------------------------------------------------------------- evaluate

def same_reports(a, b) -> bool:
    return (a.names == b.names and a.failed == b.failed and all(
        np.array_equal(getattr(a, k), getattr(b, k), equal_nan=True)
        for k in ("found", "offset_pred_m", "curvature_pred_per_m", "lane_width_pred_m", "line_accuracy",
                  "pred_lines", "fp_lines", "fn_lines")))


def test_evaluate_video_on_dask_scores_the_frames_of_one_process(scheduler):
    """110 frames of country.mp4 with the tracker and the hard-roads parts: segments 0..54 and
    55..109 (warmed up from 5, not enough on the hairpin, where the parts' memory differs unless
    the second segment is scored again from the first one's tracker)."""
    path = REPO / "videos/country.mp4"
    pipe = LanePipeline(preset("hard-roads"), calibration=evaluate.calibration_from_truth(path))
    one = evaluate.evaluate_video(path, pipe, max_frames=110)
    two = evaluate.evaluate_video(path, pipe, max_frames=110, scheduler=scheduler, progress=False)
    assert two.frames == 110 and same_reports(one, two)
    assert one.joints is None and two.joints == cluster.Joints(1, 1)


def test_evaluate_images_on_dask_scores_as_one_process(tmp_path, scheduler):
    folder = tmp_path / "in"
    folder.mkdir()
    for name in ("straight_1", "curve_left_250m", "concrete_light"):
        for suffix in (".jpg", ".json"):
            shutil.copy(REPO / "test_images" / (name + suffix), folder / (name + suffix))
    (folder / "broken.jpg").write_bytes(b"not a jpeg")
    pipe = LanePipeline(calibration=evaluate.calibration_from_truth(folder))
    one = evaluate.evaluate_images(folder, pipe)
    two = evaluate.evaluate_images(folder, pipe, scheduler=scheduler, progress=False)
    assert two.frames == 3 and [name for name, _ in two.failed] == ["broken.jpg"]
    assert same_reports(one, two)


def test_a_video_broken_half_way_on_dask_keeps_the_frames_before_the_break(tmp_path, faststart, scheduler,
                                                                          capsys):
    """As in one process (tests/test_video.py): exit 1, the outputs hold the frames before the break."""
    data = faststart.read_bytes()
    src = tmp_path / "cut.mp4"
    src.write_bytes(data[:len(data) // 12])
    errors = []
    for name, extra in (("one", []), ("two", ["--scheduler", scheduler])):
        out, log = tmp_path / f"{name}.mp4", tmp_path / f"{name}.csv"
        assert main(["video", str(src), "-o", str(out), "--log", str(log), "--no-progress", *extra]) == 1
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and "decoding stopped at frame" in err[0] and f"rows to {log}" in err[0]
        errors.append(err[0])
    assert errors[1] == errors[0].replace("one.", "two.")
    assert (tmp_path / "two.csv").read_text() == (tmp_path / "one.csv").read_text()
    assert len(frames(tmp_path / "two.mp4")) == len(frames(tmp_path / "one.mp4")) > 0
    assert not list(tmp_path.glob(".*part*"))
    # evaluate cannot score the frames that are not there: the message of one process, exit 2
    for suffix in (".csv", ".json"):
        shutil.copy(REPO / "videos" / ("project" + suffix), src.with_suffix(suffix))
    messages = []
    for extra in ([], ["--scheduler", scheduler]):
        assert main(["evaluate", "video", str(src), *extra]) == 2
        messages.append(capsys.readouterr().err.strip().splitlines()[-1])
    assert messages[1] == messages[0] and "frames to score could be read" in messages[0]
