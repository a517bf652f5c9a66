"""The ablation: each part of the pipeline switched alone, measured on every row of the scoreboard.

A part is a few settings (``config.override``'s ``"part.key=value"``) that turn one piece of the
pipeline off (a part on by default) or on (an opt-in part). ``run`` measures the scoreboard once as
it is (the baseline) and once per part with its settings set on every row's own config (the preset
of a benchmark row, the default config of a clip row), and ``format_table`` prints, per part, the
change of each row's headline figure (``HEADLINE``) that the part makes: the baseline minus the
run without it for a part on by default, the run with it minus the baseline for an opt-in part.
So a positive figure always says the part helps there.

``verdict`` reads the real rows only (``REAL``): a part is on by default only when it improves a
real row and worsens none, each by more than the row's resolution (``resolution``: what one frame
changes on a clip, one line of one frame on a benchmark set; at least the figures' rounding). The
synthetic rows stand beside them; a part that helps only there is no reason to be on.

``python -m lanelib ablation`` runs it (``make ablation``; about a minute per part on one core,
``--workers`` runs parts side by side).
"""
from __future__ import annotations

import concurrent.futures
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

from .config import PipelineConfig, override, preset_settings
from .errors import InputError
from .scoreboard import ROWS, Row, run as run_scoreboard, select

DEFAULT_OUT = Path("out") / "ablation"
# the figure of each row that the ablation compares (higher is better on every one; TuSimple's
# F1 of its FP and FN rates, which counts false lines: its accuracy credits them)
HEADLINE = {"culane": "f1_pct", "culane-moved": "f1_pct", "tusimple": "f1_pct", "tusimple-bilinear": "f1_pct",
            "project": "plausible_pct", "challenge": "plausible_pct", "p1-white": "plausible_pct",
            "p1-yellow": "plausible_pct", "synth-culane": "f1_pct", "synth-tusimple": "f1_pct",
            "synth-clip": "point_accuracy_pct"}
REAL = ("culane", "culane-moved", "tusimple", "tusimple-bilinear", "project", "challenge", "p1-white", "p1-yellow")
PER_LINE = ("culane", "culane-moved", "tusimple", "tusimple-bilinear", "synth-culane", "synth-tusimple")  # by line
LINES_PER_FRAME = 4  # about as many lines as a benchmark frame labels
ROUNDING = 0.1  # percentage points: the figures are rounded to 0.1


def resolution(row: Row) -> float:
    """Return the least change (percentage points) of a row's headline figure that says more
    than one item of its set: one frame of a clip, one line of one frame of a benchmark set
    (``LINES_PER_FRAME`` a frame), and at least the figures' rounding.

    Examples
    --------
    >>> resolution(Row("tusimple", "TuSimple dev", frames=10)), resolution(Row("challenge", "", frames=484))
    (2.5, 0.21)
    >>> resolution(Row("project", "", frames=1260))
    0.1
    """
    items = (row.frames or 1) * (LINES_PER_FRAME if row.key in PER_LINE else 1)
    return max(ROUNDING, round(100.0 / items, 2))


@dataclass(frozen=True)
class Part:
    """One part: its name, the settings that switch it, whether it is on by default (the
    settings switch it off) or opt-in (they switch it on), and what it does."""

    name: str
    settings: tuple[str, ...]
    default: bool
    what: str


# the ``hard-roads`` preset's settings: every part from "fallback masks" to "shoulder" below
HARD_ROADS = preset_settings("hard-roads")

PARTS: tuple[Part, ...] = (
    Part("fallback masks", ("thresholds.fallback_rule=yellow | (white & line_tophat) | shade_tophat",), False,
         "a lane refused on the main mask is looked for again on the fallback rule's mask"),
    Part("shorter views", ("search.short_views=[0.6, 0.4]",), False,
         "a refused lane is looked for again in shorter look-aheads (tight bends)"),
    Part("growing margin", ("search.grow_margin_px=15",), False,
         "a sliding window widens after each empty window"),
    Part("inner stripe of a double line", ("search.double_line_px=38",), False,
         "a line of two stripes is fitted to the stripe nearer the lane"),
    Part("asphalt edge", ("edge.enabled=true",), False,
         "a side with no paint takes the edge of the asphalt as its line"),
    Part("lane trend", ("tracking.trend_frames=5",), False,
         "the tracked lane is predicted along the trend of its recent centre lines"),
    Part("blind hold", ("tracking.blind_hold_frames=12",), False,
         "frames that see nothing at all hold the lane without counting toward a reset"),
    Part("near-gap join", ("tracking.near_gap_m=1",), False,
         "on a bend, a line seen only ahead of the car is joined to the inferred line near it"),
    Part("grade pair check", ("tracking.grade_pair_check=true", "search.double_line_px=38"), False,
         "a pair refused as not parallel is checked again against a grade read from stripes"),
    Part("stripe spread", ("tracking.stripe_spread=true", "search.double_line_px=38"), False,
         "an inferred line follows the width change read from the seen line's double stripes"),
    Part("re-acquisition", ("tracking.reacquire_after_frames=3",), False,
         "a line inferred for frames is looked for in a wider band"),
    Part("restart from one line", ("tracking.restart_frames=25",), False,
         "after a reset one line alone restarts the lane where the lost track was"),
    Part("road view", ("tracking.road_view_run_m=1",), False,
         "a refused frame's look-ahead ends where the lane no longer looks like the road"),
    Part("shoulder", ("tracking.shoulder_frames=10", "edge.enabled=true"), False,
         "a faded line is placed its measured shoulder inside the asphalt edge"),
    Part("pitched start", ("tracking.pitched_start_frames=0",), True,
         "a track starts from a pair that is parallel in a pitched view"),
    Part("vote: bends followed", ("lines.follow_bends=false",), True,
         "a voted line is traced by windows where it bends (benchmark presets)"),
    Part("vote: several headings", ("lines.headings=1",), True,
         "the vote tries several common headings and keeps the one with the most paint"),
    Part("vote: row weights", ("lines.row_weight_power=0",), True,
         "far rows of the lines view count less in the vote"),
    Part("vote: vehicle edges refused", ("lines.min_offset_m=0",), True,
         "a line under the car whose paint starts ahead is refused"),
    Part("vote: crossing lines kept", ("lines.refused_clear_crossings=true",), True,
         "a refused line (a vehicle's edge, scattered paint) hides no line that crosses it (culane preset)"),
    Part("vote: seen span", ("lines.seen_window_m=0",), True,
         "a voted line spans the rows where its runs hug it, not a vehicle's edges ahead of it"),
    Part("vote: lines followed ahead", ("lines.follow_ahead_m=0",), True,
         "each line is followed along its paint 40 m beyond the lines view (tusimple preset)"),
    Part("vote: paint contrast", ("lines.contrast_full=0",), True,
         "a run votes by how clearly it is brighter than the road beside it (culane and tusimple presets)"),
    Part("vote: lanes apart", ("lines.min_lane_fraction=0",), True,
         "a line nearer than 0.7 of a lane beside the line inside it is refused (tusimple preset: "
         "highway lanes are never that narrow)"),
    Part("vote: tight lines of other headings", ("lines.tight_scatter_m=0",), True,
         "a line tighter than 4 cm found at another heading than the one kept is reported too, "
         "apart from the lines kept: a bend's chord, a merging lane (culane and tusimple presets)"),
    Part("points refined from the lines", ("lines.refine_points_px=0",), True,
         "predict moves a sequence's bird's-eye points to where its lines meet, when that is far "
         "from where the points' sides meet: a camera pitched or turned otherwise than the preset's"),
    Part("CLAHE", ("thresholds.clahe=true",), False,
         "the bird's-eye view's lightness is equalised before the masks"),
    Part("window histogram", ("search.window_histogram=true",), False,
         "a window recentres on the fullest column, not the mean x"),
    Part("centre side first", ("search.centre_first=true",), False,
         "a window takes the cluster of pixels nearest the lane's centre"),
    Part("outlier trimming", ("search.trim_outliers_pct=95",), False,
         "each line is refitted to the 95 % of its pixels nearest its fit"),
    Part("other histogram peaks", ("search.candidates=3",), False,
         "a refused lane is looked for again from weaker histogram peaks"),
    Part("history of bases", ("tracking.base_history_frames=25",), False,
         "a weak histogram base is replaced by a remembered one"),
    Part("every hard-road part", HARD_ROADS, False,
         "the fourteen parts above from fallback masks to shoulder at once: the hard-roads preset"),
)


@dataclass(frozen=True)
class Ablation:
    """The baseline scoreboard and, per part's name, the scoreboard with the part switched."""

    baseline: list[Row]
    switched: dict[str, list[Row]] = field(default_factory=dict)
    parts: tuple[Part, ...] = PARTS

    def part(self, name: str) -> Part:
        """Return the part called ``name``."""
        return next(p for p in self.parts if p.name == name)

    def effects(self, name: str) -> dict[str, float | None]:
        """Return, per row, how much the part raises the row's headline figure (percentage
        points, positive: it helps); None where a row was skipped, failed or ran over
        TuSimple's time limit in either run."""
        base = {r.key: _headline(r) for r in self.baseline}
        sign = 1.0 if self.part(name).default else -1.0
        out = {}
        for r in self.switched[name]:
            new, old = _headline(r), base.get(r.key)
            out[r.key] = None if new is None or old is None else round(sign * (old - new), 1) + 0.0
        return out

    def verdict(self, name: str) -> str:
        """Return what the real rows say of the part: "earns its place" (it improves a real row
        and worsens none, each by more than the row's ``resolution``), "worsens a real row", "no
        effect on the real rows" or "not measured"."""
        limit = {r.key: resolution(r) for r in self.baseline}
        real = [(v, limit[k]) for k, v in self.effects(name).items() if k in REAL and v is not None]
        if not real:
            return "not measured"
        if any(v < -lim for v, lim in real):
            return "worsens a real row"
        if any(v > lim for v, lim in real):
            return "earns its place"
        return "no effect on the real rows"

    def to_dict(self) -> dict:
        """Return the ablation as JSON-able values (the rows as ``Row.to_dict``)."""
        return {"baseline": [r.to_dict() for r in self.baseline],
                "parts": [{"name": p.name, "settings": list(p.settings), "default": p.default,
                           "what": p.what, "rows": [r.to_dict() for r in self.switched[p.name]]}
                          for p in self.parts if p.name in self.switched]}

    @classmethod
    def from_dict(cls, d: dict) -> "Ablation":
        """Return the ablation ``to_dict`` wrote (e.g. read back from its JSON file)."""
        parts = tuple(Part(p["name"], tuple(p["settings"]), p["default"], p["what"]) for p in d["parts"])
        return cls([Row(**r) for r in d["baseline"]],
                   {p["name"]: [Row(**r) for r in p["rows"]] for p in d["parts"]}, parts)


def _headline(row: Row) -> float | None:
    """Return the row's headline figure; None when it was skipped, failed, or had frames over
    TuSimple's time limit (scored 0 for the time alone: the machine's load, not the part)."""
    if row.skipped or row.error or row.figures.get("over_200ms"):
        return None
    return row.figures.get(HEADLINE[row.key])


def choose(names: Sequence[str] | None = None) -> tuple[Part, ...]:
    """Return the parts called ``names`` in ``PARTS``' order (all for None); an unknown name
    raises ``InputError`` naming the parts there are."""
    if names is None:
        return PARTS
    known = {p.name for p in PARTS}
    unknown = [n for n in names if n not in known]
    if unknown or not names:
        raise InputError(f"--parts {unknown[0] if unknown else ''!r}: no such part; the parts are "
                         + ", ".join(p.name for p in PARTS))
    return tuple(p for p in PARTS if p.name in names)


def _slug(name: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")


def run(parts: Sequence[Part] = PARTS, only: Sequence[str] | None = None, out: str | Path = DEFAULT_OUT,
        workers: int = 1, on_done: Callable[[str], None] | None = None) -> Ablation:
    """Return the ablation of ``parts`` on the scoreboard's rows ``only`` (all for None).

    The baseline and each part run as ``scoreboard.run`` (one thread each) with their files in
    ``out/<part>/``; ``workers`` > 1 runs that many side by side in processes (the figures are
    the same, the ms per frame slower). ``on_done`` is called with each run's name as it ends.
    Bad settings or rows raise before anything runs.
    """
    keys = select(only)
    for p in parts:
        override(PipelineConfig(), p.settings)
    if workers < 1:
        raise InputError(f"--workers {workers}: give 1 or more")
    out = Path(out)
    jobs = {"baseline": ()} | {p.name: p.settings for p in parts}
    results: dict[str, list[Row]] = {}
    if workers == 1:
        for name, settings in jobs.items():
            results[name] = run_scoreboard(out / _slug(name), keys, settings=settings)
            if on_done:
                on_done(name)
    else:
        with concurrent.futures.ProcessPoolExecutor(workers) as pool:
            futures = {pool.submit(run_scoreboard, out / _slug(n), keys, settings=s): n
                       for n, s in jobs.items()}
            for f in concurrent.futures.as_completed(futures):
                results[futures[f]] = f.result()
                if on_done:
                    on_done(futures[f])
    return Ablation(results.pop("baseline"), {p.name: results[p.name] for p in parts}, tuple(parts))


def format_table(ablation: Ablation) -> str:
    """Return the ablation as a Markdown table: the baseline's headline figures and each row's
    resolution, then per part its effect on each row (percentage points; + helps) and the real
    rows' verdict."""
    keys = [r.key for r in ablation.baseline]
    head = ["part", "switched"] + [ROWS[k][0] for k in keys] + ["real rows say"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    base = [f"{v:.1f}" if (v := _headline(r)) is not None else "-" for r in ablation.baseline]
    lines.append("| baseline (headline figure, %) | | " + " | ".join(base) + " | |")
    res = [f"{resolution(r):g}" for r in ablation.baseline]
    lines.append("| resolution (one frame or line) | | " + " | ".join(res) + " | |")
    for p in ablation.parts:
        if p.name not in ablation.switched:
            continue
        eff = ablation.effects(p.name)
        cells = [("-" if eff.get(k) is None else f"{eff[k]:+.1f}") for k in keys]
        how = "off" if p.default else "on"
        switch = " ".join(p.settings).replace("|", "\\|")  # a rule's | would end the cell
        lines.append(f"| {p.name} | {how}: `{switch}` | " + " | ".join(cells)
                     + f" | {ablation.verdict(p.name)} |")
    return "\n".join(lines)
