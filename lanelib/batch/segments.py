"""A video in segments of frames on Dask workers, joined into the output of one process.

Each segment starts ``cluster.WARMUP_FRAMES`` early to warm the tracker up (``video_segment``);
a segment whose tracker did not reach the previous segment's final state in that warm-up runs
again from that state (``cluster.settle_joints``, ``FrameState``). The parts are joined without
re-encoding (``join_videos``), so the frames, the log and the results are those of one
process.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Iterable, Sequence

import imageio_ffmpeg
from tqdm import tqdm

from .. import cluster, io
from ..errors import DecodeStoppedError, InputError, PartialOutputError
from .video import FrameFn, VideoRun, VideoWriter, CsvLog, clip_frames


@dataclass(frozen=True)
class FrameState:
    """How a video's ``process`` carries its state (the tracker) from frame to frame, for the
    joints of Dask segments (``cluster.settle_joints``): ``key()`` the fingerprint of the state
    now (equal keys: the same results on the same next frames), ``get()`` the state (picklable),
    ``put(state)`` go on from a state that ``get`` gave in another process (before any frame)."""

    key: Callable[[], bytes | None]
    get: Callable[[], object]
    put: Callable[[object], None]
    core: Callable[[], bytes | None] = lambda: None  # the part the results depend on now (``cluster.Carry``)


# a FrameFn, the list its notes go to (what happened on the way: GeometryWatch.notes) and its state
FrameFnMaker = Callable[[], tuple[FrameFn, list[str], FrameState]]


@dataclass(frozen=True)
class SegmentOutcome:
    """What ``video_segment`` did with one segment: the log rows of its kept frames, the frames
    with a lane found, where decoding stopped (empty when it did not) and the notes of its kept
    frames (a warm-up's are the previous segment's)."""

    rows: tuple[dict, ...]
    found: int
    stopped: str = ""
    notes: tuple[str, ...] = ()
    carry: cluster.Carry = cluster.Carry()  # the state at its ends, to check its joints


def video_segment(chunk: Sequence[tuple[int, int, int, bool]], in_path: Path, parts: Path,
                  make: FrameFnMaker, threads: int | None = None, state: object = None
                  ) -> list[SegmentOutcome]:
    """Return the outcome of each segment of a chunk after writing its part video (a Dask task).

    A segment ``(first, start, stop, to_end)`` (``cluster.segments``) is run from frame
    ``first`` with a fresh ``make()``; the frames before ``start`` only warm the tracker up and
    are dropped; the frames ``start .. stop - 1`` (to the clip's end when ``to_end``) go to
    ``parts/<start>.mp4`` (written atomically, only when it holds a frame). A clip that stops
    decoding in the segment (or before it) ends the segment there, with ``stopped`` saying why.
    ``state`` (``FrameState.get`` of another process, or planned: ``plan_lane_restarts``): the
    segments go on from it, not from a fresh state (a re-run of a joint that did not settle in
    the warm-up, from ``start``; a restart from the warm-up with the geometry planned). Each outcome's
    ``carry`` holds the state's fingerprint before frame ``start`` and the state after the last.
    """
    out = []
    for first, start, stop, to_end in chunk:
        process, notes, carried = make()
        if state is not None:
            carried.put(state)
        rows, found, stopped, entry, entry_core, noted = [], 0, "", None, None, len(notes)
        writer = None
        try:
            try:
                reader = io.VideoReader(in_path, first, None if to_end else stop)
                writer = VideoWriter(parts / f"{start:09d}.mp4", reader.info.fps, inputs=[in_path],
                                        threads=threads)
                with reader:
                    for n, frame in enumerate(reader):
                        index = first + n
                        if index == start:
                            entry, entry_core, noted = carried.key(), carried.core(), len(notes)
                        image, row, lane = process(frame, index, index / reader.info.fps)
                        if index >= start:
                            writer.write(image)
                            rows.append(row)
                            found += bool(lane)
            except DecodeStoppedError as e:
                stopped = str(e)
            except InputError as e:  # no frame from `first` on: the clip broke off before
                if writer is None and first == 0:
                    raise
                stopped = str(e)
            if writer is not None and writer.frames_written:
                writer.close()
            elif writer is not None:
                writer.abort()
        except BaseException:
            if writer is not None:
                writer.abort()
            raise
        carry = cluster.Carry(entry, carried.key(), carried.get(), entry_core, carried.core())
        out.append(SegmentOutcome(tuple(rows), found, stopped, tuple(notes[noted:] if rows else ()), carry))
    return out


def run_video_segments(in_path: str | os.PathLike, out_path: str | os.PathLike, make: FrameFnMaker,
                       client, log_path: str | os.PathLike | None = None, progress: bool = True,
                       desc: str = "frames", threads: int | None = None, start_s: float | None = None,
                       end_s: float | None = None, warmup: int = cluster.WARMUP_FRAMES,
                       carry: Callable[[object, object, int], tuple[object, bytes] | None] | None = None,
                       plan: Callable[[object, Sequence[object], Sequence[tuple[int, int, int, bool]]],
                                      dict[int, object]] | None = None) -> VideoRun:
    """Return what a run did, as ``run_video``, with the clip split into segments run by the
    workers of a Dask ``client``.

    The frames (all, or ``start_s`` .. ``end_s``: ``clip_frames``) are split into consecutive
    segments (``cluster.segments``, ``cluster.segment_count``); each worker runs a fresh
    ``make()`` over its segment from ``warmup`` frames earlier (the warm-up frames are dropped)
    and writes the segment's video to a folder of parts beside ``out_path``. Each joint is then
    checked (``cluster.settle_joints``): where the warm-up did not bring the tracker to the state
    the previous segment ended in, the segment is run again from that state, so the frames and
    the log are those of one process; ``VideoRun.joints`` counts the re-runs. ``carry(state
    before, end state, start)`` (``carry_lane_state``): where the states differ only in evidence
    kept for later (``FrameState.core``), carry the previous state through the segment instead
    of running it again (``cluster.settle_joints``). ``plan(fresh state, end states, segments)``
    (``plan_lane_restarts``): before the joints are checked, the segments whose start was wrong
    as the end states' records tell (``fresh state``: ``make()``'s before any frame), each with
    the state to run it again from its warm-up; they run again at once (one round). This process joins
    the parts (``join_videos``, no re-encoding) and writes the per-frame log, both
    atomically, and removes the parts. One progress bar counts the frames of the segments done
    (re-runs included). A clip that stops decoding keeps the frames before the break, as
    ``run_video`` (``PartialOutputError``).
    """
    in_path, out = Path(in_path), Path(out_path)
    t0 = time.perf_counter()
    frames, spans, segs = _plan_segments(in_path, out, log_path, client, start_s, end_s, warmup)

    def carry_on(k: int, before: object, o: SegmentOutcome) -> SegmentOutcome | None:
        got = None if carry is None else carry(before, o.carry.end_state, segs[k][1])
        return None if got is None else replace(o, carry=replace(o.carry, end_state=got[0], end_key=got[1]))

    def plan_restarts(outcomes: Sequence[SegmentOutcome]) -> dict[int, object]:
        ends = []
        for o in outcomes:
            ends.append(o.carry.end_state)
            if o.stopped:
                break
        return plan(make()[2].get(), ends, segs)

    parts = Path(tempfile.mkdtemp(prefix=f".{out.stem}.", suffix=".parts", dir=out.parent))
    try:
        with tqdm(total=len(frames) or None, desc=desc, unit="frame", disable=not progress,
                  dynamic_ncols=True) as bar:
            settled, joints = cluster.map_segments(client, video_segment, segs, bar, lambda o: o.carry,
                                                   lambda o: bool(o.stopped), rebase=carry_on,
                                                   plan=plan_restarts if plan is not None else None,
                                                   in_path=in_path.resolve(), parts=parts.resolve(),
                                                   make=make, threads=threads)
        outcomes = _join_parts(in_path, out, log_path, spans, settled, parts)
    finally:
        shutil.rmtree(parts, ignore_errors=True)
    return _segments_run(outcomes, out, log_path, frames, time.perf_counter() - t0, joints)


def _plan_segments(in_path: Path, out: Path, log_path: str | os.PathLike | None, client,
                   start_s: float | None, end_s: float | None, warmup: int
                   ) -> tuple[range, list[tuple[int, int, int]], list[tuple[int, int, int, bool]]]:
    """Return the frames of a ``run_video_segments`` run, its segments ``(first, start, stop)``
    (``cluster.segments``) and their tasks ``(first, start, stop, to_end)``, after checking that
    no output lies over an input and making the output's folder."""
    info = io.video_info(in_path)
    whole = start_s is None and end_s is None
    frames = range(info.n_frames) if whole else clip_frames(info, start_s, end_s)
    inputs = [in_path]
    io.check_not_input(out, inputs)
    if log_path is not None:
        io.check_not_input(log_path, inputs + [out])
    count = cluster.segment_count(len(frames), cluster.total_threads(client), warmup)
    spans = cluster.segments(frames, count, warmup)
    segs = [(first, start, stop, end_s is None and stop == frames.stop) for first, start, stop in spans]
    out.parent.mkdir(parents=True, exist_ok=True)
    return frames, spans, segs


def _join_parts(in_path: Path, out: Path, log_path: str | os.PathLike | None,
                spans: Sequence[tuple[int, int, int]], settled: Sequence[SegmentOutcome],
                parts: Path) -> list[SegmentOutcome]:
    """Return the outcomes of the segments up to the first that stopped decoding, after joining
    their part videos into ``out`` and writing their log rows to ``log_path``, both atomically.

    Raises
    ------
    InputError
        If no segment holds a frame (the clip could not be decoded).
    """
    inputs = [in_path]
    outcomes, files = [], []
    for (_, start, _), o in zip(spans, settled):
        outcomes.append(o)
        if o.rows:
            files.append(parts / f"{start:09d}.mp4")
        if o.stopped:
            break
    if not files:
        raise InputError(f"{in_path}: no frame could be decoded ({outcomes[0].stopped}); "
                         "pass a readable video")
    log = CsvLog(Path(log_path) if log_path else None, inputs)
    ok = False
    try:
        for o in outcomes:
            for row in o.rows:
                log.write(row)
        join_videos(files, out, inputs=inputs)
        ok = True
    finally:
        log.finish(ok)
    return outcomes


def join_videos(parts: Iterable[str | os.PathLike], path: str | os.PathLike,
                inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write the videos ``parts`` one after the other to ``path``, atomically; return the path.

    The parts (same codec, size and frame rate: one run's segments) are joined by ffmpeg's concat
    demuxer without re-encoding (``-c copy``), so the frames are those of the parts.

    Raises
    ------
    InputError
        If there is no part, or ffmpeg cannot join them (its cause in the message).
    """
    parts = [Path(p).resolve() for p in parts]
    target = Path(path)
    if not parts:
        raise InputError(f"{target}: no video parts to join")
    with io.atomic_path(target, inputs=[*inputs, *parts]) as tmp:
        listing = tmp.with_name(tmp.name + ".txt")
        # the concat demuxer's list: one `file '...'` line per part, quotes escaped as '\''
        listing.write_text("".join("file '" + str(p).replace("'", "'\\''") + "'\n" for p in parts))
        try:
            done = subprocess.run([imageio_ffmpeg.get_ffmpeg_exe(), "-y", "-v", "error", "-f", "concat",
                                   "-safe", "0", "-i", str(listing), "-c", "copy", "-map", "0:v",
                                   str(tmp)], capture_output=True, text=True)
        finally:
            listing.unlink(missing_ok=True)
        if done.returncode != 0:
            raise InputError(f"{target}: ffmpeg could not join {len(parts)} video parts "
                             f"({io.ffmpeg_cause(done.stderr)}); check the parts ({parts[0]}, ...)")
    return target


def _segments_run(outcomes: Sequence[SegmentOutcome], out: Path, log_path: str | os.PathLike | None,
                  frames: range, seconds: float, joints: cluster.Joints) -> VideoRun:
    """Return the ``VideoRun`` of the joined segments; raise ``PartialOutputError`` when one
    stopped decoding (the outputs then keep the frames before the break)."""
    n = sum(len(o.rows) for o in outcomes)
    found = sum(o.found for o in outcomes)
    notes = tuple(note for o in outcomes for note in o.notes)
    stopped = next((o.stopped for o in outcomes if o.stopped), "")
    if stopped:
        wrote = f"wrote {n} frames to {out}" + (f" and {n} rows to {log_path}" if log_path else "")
        raise PartialOutputError(f"{stopped}; {wrote}", n)
    return VideoRun(n, seconds, n / seconds if seconds > 0 else float("nan"), found, frames.start, notes,
                    joints)
