"""The command line fed random bytes, truncated files and odd images: one line per problem, no traceback.

Hypothesis writes folders of random bytes named .jpg/.png, truncated JPEG/PNG files and valid
images of odd sizes and formats (1x1, 3x5000, grey, RGBA, 16-bit; a flat colour, so no lane), and
videos of random bytes or cut from videos/project.mp4, and runs ``images``, ``hough``, ``evaluate
images`` and ``video`` on them in-process (``cli.main``). Every run must exit with 0 (every file
ran), 1 (some files failed, or the video broke off half-way) or 2 (nothing could be run), print
exactly one ``error:`` line per failed file on stderr and nothing else there, and write one row per
file. A few subprocess runs prove that the real entry point prints no traceback either.
"""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

from lanelib import io
from lanelib.cli import main
from lanelib.batch import GRAYSCALE_NOTE

REPO = Path(__file__).resolve().parents[1]
ROAD = REPO / "test_images" / "straight_1.jpg"
PROJECT = REPO / "videos" / "project.mp4"

FUZZ = settings(deadline=None, derandomize=True, database=None, print_blob=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow,
                                       HealthCheck.data_too_large])


# --------------------------------------------------------------------------- what goes in

def decodes(data: bytes) -> bool:
    """Return whether OpenCV decodes ``data`` as an image at all (its messages are swallowed)."""
    with io.captured_native_stderr():
        try:
            return bool(data) and cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_UNCHANGED) is not None
        except cv2.error:
            return False


@st.composite
def image_files(draw) -> tuple[str, bytes, str]:
    """Return (suffix, bytes, expectation): expectation "error", "no lane" or "any"."""
    kind = draw(st.sampled_from(["random", "truncated", "valid", "valid"]))
    event(f"image file: {kind}")
    if kind == "random":
        data = draw(st.binary(max_size=3000))
        assume(not decodes(data))
        return draw(st.sampled_from([".jpg", ".png"])), data, "error"
    if kind == "truncated":
        suffix = draw(st.sampled_from([".jpg", ".png"]))
        h, w = draw(st.integers(1, 60)), draw(st.integers(1, 60))
        noise = np.random.default_rng(draw(st.integers(0, 99))).integers(0, 256, (h, w, 3), np.uint8)
        data = io.encode_image(noise, suffix)
        return suffix, data[:draw(st.integers(0, len(data) - 1))], "any"  # JPEG may still decode
    w, h = draw(st.one_of(st.sampled_from([(1, 1), (3, 5000), (5000, 3), (1, 400), (400, 1)]),
                          st.tuples(st.integers(1, 400), st.integers(1, 400))))
    event(f"valid image: {'a side under 8 px' if min(w, h) < 8 else 'both sides 8 px or more'}")
    mode = draw(st.sampled_from(["grey", "bgr", "bgra"]))
    depth = draw(st.sampled_from([8, 16]))
    top = 255 if depth == 8 else 65535
    channels = {"grey": 1, "bgr": 3, "bgra": 4}[mode]
    colour = [draw(st.integers(0, top)) for _ in range(channels)]
    array = np.empty((h, w, channels), np.uint8 if depth == 8 else np.uint16)
    array[...] = colour
    suffix = ".jpg" if depth == 8 and mode != "bgra" and draw(st.booleans()) else ".png"
    ok, buf = cv2.imencode(suffix, array[..., 0] if mode == "grey" else array)
    assert ok
    return suffix, buf.tobytes(), f"no lane:{mode}:{depth}:{suffix}:{w}x{h}"


def write_folder(root: Path, specs) -> tuple[Path, dict[str, str]]:
    """Write the files of ``specs`` into a new folder under ``root``; return it and {name: expectation}."""
    folder = Path(tempfile.mkdtemp(dir=root))
    expected = {}
    for i, (suffix, data, expectation) in enumerate(specs):
        name = f"f{i}{suffix}"
        (folder / name).write_bytes(data)
        expected[name] = expectation
    return folder, expected


# --------------------------------------------------------------------------- what must come out

TOO_SMALL = "too small for the bird's-eye view (the perspective points collapse when scaled to it)"


def check_rows(folder: Path, rows: list[dict], expected: dict[str, str], code: int, err: str,
               min_side_px: int = 1) -> list[dict]:
    """Assert the contract on a folder run; return the rows without an error.

    A valid image fails only when a side is under ``min_side_px`` and the error says it is too small.
    """
    assert "Traceback" not in err
    assert [r["file"] for r in rows] == sorted(expected)
    failed = [r for r in rows if "error" in r]
    event(f"exit code {code}")
    assert code == (1 if failed else 0), err
    assert err.splitlines() == [f"error: {r['error']}" for r in failed]  # one line each, nothing else
    for r in failed:
        assert set(r) == {"file", "error"} and "\n" not in r["error"]
        assert r["error"].startswith(f"{folder / r['file']}: ") and "; " in r["error"]  # file; cause; fix
        if expected[r["file"]].startswith("no lane:"):
            w, h = map(int, expected[r["file"]].split(":")[-1].split("x"))
            assert min(w, h) < min_side_px and TOO_SMALL in r["error"], r
    for r in rows:
        if expected[r["file"]] == "error":
            assert "error" in r
    return [r for r in rows if "error" not in r]


def check_notes(row: dict, expectation: str) -> None:
    """Assert what a valid flat image's row notes: grey and 16-bit."""
    _, mode, depth, suffix, size = expectation.split(":")
    note = row.get("note", "")
    if mode == "grey":
        assert GRAYSCALE_NOTE in note
    assert ("16-bit image: scaled to 8 bits (value >> 8)" in note) == (depth == "16")


@settings(FUZZ, max_examples=200)
@given(specs=st.lists(image_files(), min_size=1, max_size=4))
def test_images_on_fuzzed_folders(tmp_path, capfd, specs):
    folder, expected = write_folder(tmp_path, specs)
    capfd.readouterr()
    code = main(["images", str(folder), "-o", str(folder / "out")])
    out, err = capfd.readouterr()
    rows = json.loads((folder / "out" / "results.json").read_text())
    ran = check_rows(folder, rows, expected, code, err, min_side_px=8)  # 7 px or less may be too small
    for r in ran:
        if expected[r["file"]].startswith("no lane:"):  # a flat colour has no lane
            assert r["found"] is False and r["reason"], r
            check_notes(r, expected[r["file"]])
    assert len(out.strip().splitlines()) == len(ran) + 1  # a line per image that ran, and the total
    assert sorted(p.name for p in (folder / "out").iterdir()) == sorted([r["file"] for r in ran] + ["results.json"])


@settings(FUZZ, max_examples=200)
@given(specs=st.lists(image_files(), min_size=1, max_size=4))
def test_hough_on_fuzzed_folders(tmp_path, capfd, specs):
    folder, expected = write_folder(tmp_path, specs)
    capfd.readouterr()
    code = main(["hough", str(folder), "-o", str(folder / "out")])
    out, err = capfd.readouterr()
    rows = json.loads((folder / "out" / "results.json").read_text())
    ran = check_rows(folder, rows, expected, code, err)
    for r in ran:
        if expected[r["file"]].startswith("no lane:"):
            assert r["left_found"] is False and r["right_found"] is False and r["reason"], r
            check_notes(r, expected[r["file"]])
    assert len(out.strip().splitlines()) == len(ran) + 1


@settings(FUZZ, max_examples=40)
@given(specs=st.lists(image_files(), min_size=1, max_size=3),
       truths=st.lists(st.sampled_from(["copy", "none", "garbage"]), min_size=3, max_size=3))
def test_evaluate_images_on_fuzzed_folders(tmp_path, capfd, specs, truths):
    folder, expected = write_folder(tmp_path, specs)
    truth = ROAD.with_suffix(".json")
    for name, how in zip(sorted(expected), truths):
        if how == "copy":
            shutil.copy(truth, (folder / name).with_suffix(".json"))
        elif how == "garbage":
            (folder / name).with_suffix(".json").write_bytes(b"\x00\xff{" + name.encode())
    shutil.copy(ROAD, folder / "road.jpg")  # one image that scores, so the run has a camera
    shutil.copy(truth, folder / "road.json")
    capfd.readouterr()
    code = main(["evaluate", "images", str(folder), "--json", str(folder / "e.json")])
    out, err = capfd.readouterr()
    assert "Traceback" not in err and code == 1  # none of the fuzzed files is a 1280x720 road
    lines = err.splitlines()
    assert len(lines) == len(expected) and all(line.startswith("error: ") for line in lines)
    for line, name in zip(lines, sorted(expected)):
        assert name in line or Path(name).with_suffix(".json").name in line
    assert f"{len(expected)} of {len(expected) + 1} files failed and are left out of the scores" in out
    figures = json.loads((folder / "e.json").read_text())
    assert figures["frames"] == 1 and figures["files_failed"] == len(expected)


# --------------------------------------------------------------------------- videos

@st.composite
def video_bytes(draw, faststart: bytes) -> bytes:
    """Return random bytes, a cut of videos/project.mp4 (index last) or of ``faststart`` (index first)."""
    kind = draw(st.sampled_from(["random", "cut", "cut index first"]))
    event(f"video: {kind}")
    if kind == "random":
        return draw(st.binary(max_size=4000))
    if kind == "cut":
        data = PROJECT.read_bytes()
        return data[:draw(st.integers(0, len(data) - 1))]
    # the index and up to about six frames (the first, a key frame, takes about 35 kB)
    start = faststart.index(b"mdat")
    return faststart[:draw(st.one_of(st.integers(0, start + 40_000), st.integers(start + 40_000, start + 90_000)))]


@settings(FUZZ, max_examples=60)
@given(data=st.data())
def test_video_on_fuzzed_files(tmp_path, capfd, faststart, data):
    content = data.draw(video_bytes(faststart.read_bytes()))
    folder = Path(tempfile.mkdtemp(dir=tmp_path))
    src, out, log = folder / "in.mp4", folder / "out" / "o.mp4", folder / "out" / "o.csv"
    src.write_bytes(content)
    capfd.readouterr()
    code = main(["video", str(src), "-o", str(out), "--log", str(log), "--no-progress"])
    stdout, err = capfd.readouterr()
    lines = err.splitlines()
    event(f"video exit code {code}")
    assert "Traceback" not in err
    if code == 0:  # a cut in the last bytes of the index (its metadata) leaves a whole video
        assert err == "" and len(content) > 0.99 * PROJECT.stat().st_size
        assert sum(1 for _ in io.VideoReader(out)) == 250 and len(log.read_text().splitlines()) == 251
        return
    assert code in (1, 2) and len(lines) == 1 and lines[0].startswith(f"error: {src}: "), err
    if code == 2:
        assert not out.exists() and not log.exists() and stdout == ""
        assert not (folder / "out").exists() or list((folder / "out").iterdir()) == []
    else:
        n = int(lines[0].split("decoding stopped at frame ")[1].split(":")[0])
        assert lines[0].endswith(f"; wrote {n} frames to {out} and {n} rows to {log}")
        assert sum(1 for _ in io.VideoReader(out)) == n
        assert len(log.read_text().splitlines()) == n + 1  # the header and a row per frame


# --------------------------------------------------------------------------- the real entry point

def run(*args):
    return subprocess.run([sys.executable, "-m", "lanelib", *map(str, args)], capture_output=True,
                          text=True)


def test_the_entry_point_prints_no_traceback(tmp_path, faststart):
    folder = tmp_path / "in"
    folder.mkdir()
    rng = np.random.default_rng(3)
    (folder / "random.jpg").write_bytes(rng.integers(0, 256, 2000, np.uint8).tobytes())
    road = ROAD.read_bytes()
    (folder / "cut.jpg").write_bytes(road[:len(road) // 2])
    png = io.encode_image(rng.integers(0, 256, (40, 50, 3), np.uint8))
    (folder / "cut.png").write_bytes(png[:len(png) // 2])  # libpng complains on fd 2
    (folder / "empty.png").write_bytes(b"")
    cv2.imwrite(str(folder / "grey16.png"), np.full((30, 40), 40000, np.uint16))
    cv2.imwrite(str(folder / "tall.png"), np.full((5000, 3, 4), 90, np.uint8))
    cv2.imwrite(str(folder / "dot.png"), np.full((1, 1, 3), 90, np.uint8))
    for f in (ROAD, ROAD.with_suffix(".json")):
        shutil.copy(f, folder / f.name)
    bad = {"random.jpg", "cut.jpg", "cut.png", "empty.png"}
    for args, n_errors in ((["images", folder, "-o", tmp_path / "o1"], len(bad | {"dot.png"})),
                           (["hough", folder, "-o", tmp_path / "o2"], len(bad)),
                           (["evaluate", "images", folder], 7)):  # only straight_1 has a truth
        p = run(*args)
        assert "Traceback" not in p.stderr and p.returncode == 1, p.stderr
        lines = p.stderr.splitlines()
        assert len(lines) == n_errors and all(line.startswith(f"error: {folder}/") for line in lines), lines
    (tmp_path / "random.mp4").write_bytes(rng.integers(0, 256, 5000, np.uint8).tobytes())
    (tmp_path / "cut.mp4").write_bytes(PROJECT.read_bytes()[:1_000_000])
    head = faststart.read_bytes()
    (tmp_path / "half.mp4").write_bytes(head[:head.index(b"mdat") + 80_000])
    for name, code in (("random.mp4", 2), ("cut.mp4", 2), ("half.mp4", 1)):
        for command in ("video", "hough"):
            p = run(command, tmp_path / name, "-o", tmp_path / f"{command}_{name}", "--no-progress")
            assert "Traceback" not in p.stderr and p.returncode == code, p.stderr
            assert len(p.stderr.splitlines()) == 1 and p.stderr.startswith(f"error: {tmp_path / name}: ")
