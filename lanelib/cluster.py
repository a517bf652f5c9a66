"""Dataset-scale runs on Dask: a client for ``--workers N`` or ``--scheduler ADDRESS``, and a map
of chunks of work items over it with one progress bar.

``dask_client(workers, scheduler)`` gives no client for one worker (the run stays in this process,
as without Dask), a ``distributed.LocalCluster`` of ``workers`` single-threaded processes for more,
or a client of an existing Dask cluster (``dask scheduler`` and ``dask worker`` on any machines)
for ``scheduler``. ``map_chunks`` sends the chunks (lists of work items) to the workers and
returns each chunk's results in the chunks' order, updating one tqdm bar per item as chunks come
back; ``map_items`` does both (chunks, map) and returns the items' results in order; ``segments``
splits a video's frames into ranges for ``runs`` and ``evaluate`` to track on the workers, each
warmed up over the end of the one before, and ``settle_joints`` makes each joint exact: where
the warm-up did not bring the tracker to the previous segment's final state (compared by a
fingerprint, ``LaneTracker.state_key``), the segment runs again from that state; segments that
the records of the first round show started from a wrong state (a video's geometry refined in
an earlier segment) first run again all at once from the state planned for them, so a change
early in a long video costs one round, not one re-run after another (``map_segments`` does
both, map and joints). The workers read and write the files themselves:
with ``--scheduler`` the dataset and the output folder must lie on a filesystem every worker sees at the same path (a shared mount).

``dask`` and ``distributed`` are imported inside the functions that need them (the documented
exception to lanelib's module-level imports, docs/architecture.md): they take a few hundred ms
to import, and only a run with ``--workers`` or ``--scheduler`` uses them.
"""
from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Iterator, Sequence, TypeVar

from tqdm import tqdm

from .errors import InputError

if TYPE_CHECKING:
    import distributed

T = TypeVar("T")

# a chunk is at most this many work items (frames): the per-chunk set-up (a pipeline's remap maps,
# ~30 ms) is paid once per chunk, and a task of 32 frames (~1-2 s) keeps the scheduler's overhead small
MAX_CHUNK = 32
# chunks per worker thread when there are few items, so the workers finish close together
CHUNKS_PER_THREAD = 4
CONNECT_TIMEOUT_S = 10
# Dask's nannies start their workers with MALLOC_TRIM_THRESHOLD_=65536, which makes glibc mmap and
# unmap every frame-sized array: a frame's detection takes twice as long (33 vs 15 ms at
# 1280x720). Our workers keep glibc's default. Workers started by `dask worker` need the same in
# their environment: DASK_DISTRIBUTED__NANNY__PRE_SPAWN_ENVIRON__MALLOC_TRIM_THRESHOLD_=None
WORKER_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
WORKER_ENVIRON = {"DASK_DISTRIBUTED__NANNY__PRE_SPAWN_ENVIRON__MALLOC_TRIM_THRESHOLD_": "None"}


@contextmanager
def dask_client(workers: int = 1, scheduler: str | None = None) -> Iterator[distributed.Client | None]:
    """Yield a Dask client for a run's work, or None when it runs in this process; close it after.

    Parameters
    ----------
    workers : 1 (default): no Dask; more: a ``LocalCluster`` of that many worker processes of one
        thread each, started here and closed at the end.
    scheduler : the address of a running Dask scheduler (``tcp://HOST:PORT``); ``workers`` is then
        ignored (the cluster has the workers it has).

    Raises
    ------
    InputError
        If ``workers`` is below 1, or no scheduler answers at ``scheduler``.
    """
    if scheduler:
        import distributed  # lazy: only a Dask run pays for it (module docstring)
        try:
            client = distributed.Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError) as e:
            raise InputError(f"--scheduler {scheduler}: no Dask scheduler answered ({e}); start one "
                             "with `dask scheduler` and workers with `dask worker ADDRESS`, or pass "
                             "--workers N for workers on this machine") from None
        with client:
            yield client
        return
    if workers < 1:
        raise InputError(f"--workers {workers}: give 1 worker or more")
    if workers == 1:
        yield None
        return
    import dask  # lazy: only a Dask run pays for them (module docstring)
    import distributed
    with dask.config.set(WORKER_CONFIG), \
            distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                     # its HTTP server on any free port: runs side by side never fight for 8787
                                     dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        yield client


def chunk_size(items: int, threads: int) -> int:
    """Return how many items to put in a chunk: about ``CHUNKS_PER_THREAD`` chunks per worker
    thread, 1 to ``MAX_CHUNK`` items each."""
    return max(1, min(MAX_CHUNK, math.ceil(items / (CHUNKS_PER_THREAD * max(1, threads)))))


def split(items: Sequence[T], size: int) -> list[list[T]]:
    """Return ``items`` in consecutive chunks of ``size`` (the last may be shorter)."""
    return [list(items[i:i + size]) for i in range(0, len(items), size)]


def map_chunks(client: distributed.Client, fn: Callable[..., list], chunks: Sequence[Sequence],
               bar: tqdm, sizes: Sequence[int] | None = None, states: Sequence[object] | None = None,
               **kwargs) -> list[list]:
    """Return ``[fn(chunk, **kwargs) for chunk in chunks]``, run by the client's workers.

    ``fn`` must be importable by the workers (a module-level function of lanelib) and return one
    result per item; ``bar`` is updated by the chunk's length (or its entry of ``sizes``: e.g.
    the frames of a video segment) as each chunk comes back. ``states``: one per chunk, passed
    as ``fn(chunk, state=state, **kwargs)`` (the states a video's segments run again from). An
    exception raised by ``fn`` cancels the chunks not yet run and is raised here.
    """
    import distributed  # lazy (module docstring)
    if states is None:
        futures = client.map(fn, chunks, pure=False, **kwargs)
    else:
        futures = [client.submit(fn, chunk, state=state, pure=False, **kwargs)
                   for chunk, state in zip(chunks, states)]
    index = {f.key: i for i, f in enumerate(futures)}
    results: list[list | None] = [None] * len(futures)
    try:
        for future in distributed.as_completed(futures):
            results[index[future.key]] = future.result()
            i = index[future.key]
            bar.update(len(chunks[i]) if sizes is None else sizes[i])
    except BaseException:
        client.cancel(futures)
        raise
    return results  # type: ignore[return-value]


def map_ordered(client: distributed.Client, fn: Callable[..., T], items: Sequence, **kwargs) -> list[T]:
    """Return ``[fn(item, **kwargs) for item in items]``, run by the client's workers (all sent at
    once); the first exception raised by ``fn``, in the items' order, cancels the rest."""
    futures = client.map(fn, items, pure=False, **kwargs)
    try:
        return [future.result() for future in futures]
    except BaseException:
        client.cancel(futures)
        raise


def total_threads(client: distributed.Client) -> int:
    """Return the worker threads of the client's cluster (at least 1)."""
    return max(1, sum(client.nthreads().values()))


def map_items(client: distributed.Client, fn: Callable[..., list], items: Sequence, bar: tqdm,
              **kwargs) -> list:
    """Return the results of ``fn`` on every item, in the items' order, run by the client's workers.

    The items go in chunks (``chunk_size`` for the cluster's threads, ``split``) as tasks
    ``fn(chunk, **kwargs)``, each returning one result per item of its chunk (``map_chunks``: one
    bar update per item as chunks come back). A failed item is ``fn``'s to record in its result
    (a row with an ``error``, an outcome with its message) so the run goes on; an exception
    raised by ``fn`` (a bug, a bad config that fails every item) stops the run.
    """
    chunks = split(items, chunk_size(len(items), total_threads(client)))
    return [r for chunk in map_chunks(client, fn, chunks, bar, **kwargs) for r in chunk]


def run_items(fn: Callable[..., list], items: Sequence, workers: int = 1, scheduler: str | None = None,
              desc: str = "", unit: str = "item", progress: bool = False, **kwargs) -> list:
    """Return the results of ``fn`` on every item, in the items' order: ``fn(chunk, **kwargs)``
    gives one result per item of a chunk, run in this process (one item at a time) or on Dask
    (``dask_client(workers, scheduler)``, ``map_items``), with one tqdm bar when ``progress``."""
    with dask_client(workers, scheduler) as client, \
            tqdm(total=len(items), desc=desc, unit=unit, disable=not progress, dynamic_ncols=True) as bar:
        if client is not None:
            return map_items(client, fn, items, bar, **kwargs)
        out = []
        for item in items:
            out += fn([item], **kwargs)
            bar.update(1)
        return out


# frames a segment of a tracked video is run before its first frame and dropped (``segments``):
# the tracker's state (smoothing over 5 frames, the prior fits, held lines) mostly forgets a start
# this far back, and the segment's frames come out as those of one run through the whole clip;
# where it does not (on a hairpin the fits may agree again only after many frames, or never
# before the segment ends), ``settle_joints`` finds it and runs the segment again
WARMUP_FRAMES = 50
# a segment is at least this many warm-up lengths long, so the warm-up costs at most ~1/8 more
MIN_SEGMENT_WARMUPS = 8


def segments(frames: range, parts: int, warmup: int = 0) -> list[tuple[int, int, int]]:
    """Return ``(first, start, stop)`` of each of ``parts`` consecutive frame ranges of ``frames``.

    The segments cover ``frames`` in order with sizes differing by at most one frame (fewer
    segments when there are fewer frames than ``parts``); a segment's kept frames are
    ``start .. stop - 1`` and it is run from ``first = max(frames.start, start - warmup)``, the
    frames before ``start`` only warming the tracker up.
    """
    n = len(frames)
    parts = max(1, min(parts, n))
    bounds = [frames.start + (n * k) // parts for k in range(parts + 1)]
    return [(max(frames.start, a - warmup), a, b) for a, b in zip(bounds, bounds[1:]) if b > a]


def segment_count(frames: int, threads: int, warmup: int = WARMUP_FRAMES) -> int:
    """Return how many segments to split a video of ``frames`` into: one or more per worker
    thread (``CHUNKS_PER_THREAD`` at most), each at least ``MIN_SEGMENT_WARMUPS * warmup`` frames
    long when the clip allows more than one per thread."""
    longest = max(1, frames // max(1, MIN_SEGMENT_WARMUPS * warmup))
    return max(1, min(frames, max(threads, min(threads * CHUNKS_PER_THREAD, longest))))


# --------------------------------------------------------------------------- the joints of a video's segments

@dataclass(frozen=True)
class Carry:
    """A segment's tracker state at its two ends, to check the joint with its neighbours.

    ``entry_key``: the fingerprint of the state just before the segment's first kept frame (after
    its warm-up); ``end_key`` and ``end_state``: the fingerprint and the state itself (picklable,
    e.g. the ``LaneTracker``) after its last frame. Fingerprints are None without a state (a
    run without a tracker): two Nones are the same state. ``entry_core`` and ``end_core``: the
    fingerprints of the part of the state the frames' results depend on now (a video's
    ``GeometryWatch`` keeps evidence that matters only once it changes the geometry: the core
    leaves it out); None: no such part (the keys decide alone).
    """

    entry_key: bytes | None = None
    end_key: bytes | None = None
    end_state: object = None
    entry_core: bytes | None = None
    end_core: bytes | None = None


@dataclass(frozen=True)
class Joints:
    """How the joints between a clip's segments were made exact (``settle_joints``): ``joints``
    checked, ``rerun`` of them run again from the previous segment's state, one after another,
    ``rebased`` carried on by the evidence alone, and ``restarted`` segments run again first,
    all at once, from the states the segments' records gave (``plan``)."""

    joints: int = 0
    rerun: int = 0
    rebased: int = 0
    restarted: int = 0

    @property
    def rounds(self) -> int:
        """The rounds of re-runs that waited on each other: the restarts (one round, run in
        parallel), then each re-run of a joint (one at a time)."""
        return (self.restarted > 0) + self.rerun

    def __str__(self) -> str:
        settled = self.joints - self.rerun - self.rebased
        rebased = f", {self.rebased} carried on by the evidence alone" if self.rebased else ""
        restarted = (f" ({self.restarted} segment{'' if self.restarted == 1 else 's'} first run again at "
                     "once from the state the records gave)" if self.restarted else "")
        return (f"{self.joints + 1} segments; {settled} of {self.joints} joint"
                f"{'' if self.joints == 1 else 's'} settled in the warm-up{rebased}, {self.rerun} re-run"
                f"{restarted}")


def settle_joints(outcomes: Sequence[T], carry: Callable[[T], Carry], rerun: Callable[[int, object], T],
                  ended: Callable[[T], bool] = lambda o: False,
                  rebase: Callable[[int, object, T], T | None] | None = None,
                  plan: Callable[[Sequence[T]], dict[int, object]] | None = None,
                  restart: Callable[[dict[int, object]], dict[int, T]] | None = None
                  ) -> tuple[list[T], Joints]:
    """Return the segments' outcomes with every joint exact, and how many joints needed a re-run.

    A segment's warm-up runs over the end of the one before it: when its tracker's state before
    its first kept frame (``Carry.entry_key``) is that of the previous segment after its last
    frame (``end_key``), the two runs agree from there on, and the segment's frames are those of
    one process through the clip. When not (the tracker's memory outlasted the warm-up: a hold,
    a trend over a hairpin), ``rerun(k, state)`` runs segment ``k`` again from the previous
    segment's final state (``end_state``); the segments are checked in order, each against the
    final state of the one before as it now is (a chain of re-runs, one after another). A
    segment for which ``ended`` is true (the clip broke off in it) ends the check: the later
    ones are not used. Where the keys differ but the cores agree (``Carry.entry_core``: the
    results depend on the same state now; only evidence kept for later differs),
    ``rebase(k, state, outcome)`` may carry the previous segment's evidence through the
    segment's own record without running it again: it returns the outcome with its end state
    (and keys) so carried on, or None when the evidence would have changed the results (then
    the segment is run again).

    Before the checks, ``plan(outcomes)`` may tell, from the segments' records alone, which
    segments started from a wrong state and the state each should have had at its first
    (warm-up) frame (a video's geometry refined in an earlier segment: every later one started
    from the first estimate); ``restart(states)`` runs those again all at once (one round) and
    returns their outcomes. The checks then go on as above: a plan is a guess the keys verify,
    and a restarted segment whose warm-up still did not settle is run again from the state
    before it. ``Joints.rounds`` counts the rounds of re-runs that waited on each other.
    """
    out = list(outcomes)
    restarted = 0
    if plan is not None and restart is not None:
        states = plan(out)
        for k, outcome in restart(states).items() if states else ():
            out[k] = outcome
        restarted = len(states)
    checked = reruns = rebased = 0
    for k in range(1, len(out)):
        if ended(out[k - 1]):
            break
        checked += 1
        before, here = carry(out[k - 1]), carry(out[k])
        if here.entry_key == before.end_key:
            continue
        if rebase is not None and here.entry_core is not None and here.entry_core == before.end_core:
            carried = rebase(k, before.end_state, out[k])
            if carried is not None:
                out[k] = carried
                rebased += 1
                continue
        out[k] = rerun(k, before.end_state)
        reruns += 1
    return out, Joints(checked, reruns, rebased, restarted)


def map_segments(client: distributed.Client, fn: Callable[..., list],
                 spans: Sequence[tuple[int, int, int, bool]], bar: tqdm, carry: Callable[[T], Carry], ended: Callable[[T], bool] = lambda o: False,
                 rebase: Callable[[int, object, T], T | None] | None = None,
                 plan: Callable[[Sequence[T]], dict[int, object]] | None = None, **kwargs) -> tuple[list[T], Joints]:
    """Return the outcome of each segment of a video run by the client's workers, every joint
    exact (``settle_joints``), and how many joints needed a re-run.

    ``fn([(first, start, stop, to_end)], state=None, **kwargs)`` runs one segment (``segments``;
    ``to_end``: read on to the clip's end) from frame ``first`` with a fresh tracker, or with a
    ``state`` put in before frame ``first``, and returns ``[outcome]``; ``carry(outcome)`` is
    its ``Carry``. The segments go to the workers at once; then the segments ``plan`` names go
    again at once, each from its first (warm-up) frame and the state planned for it; re-runs of
    joints, one after another, as single tasks from frame ``start`` (``rebase``, ``plan``: as
    ``settle_joints``). ``bar`` counts the kept frames done, re-runs included.
    """
    done = map_chunks(client, fn, [[span] for span in spans], bar,
                      sizes=[stop - start for _, start, stop, _ in spans], **kwargs)

    def rerun(k: int, state: object) -> T:
        _, start, stop, to_end = spans[k]
        bar.total += stop - start
        (outcome,) = map_ordered(client, fn, [[(start, start, stop, to_end)]], state=state, **kwargs)[0]
        bar.update(stop - start)
        return outcome

    def restart(states: dict[int, object]) -> dict[int, T]:
        ks = sorted(states)
        sizes = [spans[k][2] - spans[k][1] for k in ks]
        bar.total += sum(sizes)
        again = map_chunks(client, fn, [[spans[k]] for k in ks], bar, sizes=sizes,
                           states=[states[k] for k in ks], **kwargs)
        return {k: o for k, (o,) in zip(ks, again)}

    return settle_joints([o for (o,) in done], carry, rerun, ended, rebase, plan, restart)
