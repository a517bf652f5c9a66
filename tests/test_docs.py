"""The README stays short and the docs hold together: the README's length, every relative link and
file path named in the README and docs exists, every ``python -m lanelib`` command the README and
docs show parses (``--help``-level: the parser only, nothing runs), the hard-road page's defaults
and ablation rows are the code's and ``docs/ablation.json``'s, and the changelog's newest version
is the package's."""
from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest

import lanelib
from lanelib.ablation import REAL, Ablation
from lanelib.cli import build_parser
from lanelib.config import override, preset, preset_settings

REPO = Path(__file__).resolve().parents[1]
PAGES = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]
CHANGELOG = REPO / "CHANGELOG.md"
HARD_ROADS = REPO / "docs" / "hard-roads.md"
MAX_README_LINES = 250
# paths the pages name that are not in a clone: a file the e2e test writes, a video of the real
# Udacity data (under LANELIB_DATA)
NOT_IN_A_CLONE = {"tests/e2e/output/latency.txt", "videos/project_video.mp4", "videos/challenge_video.mp4"}


def test_the_readme_is_short():
    lines = (REPO / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) <= MAX_README_LINES, f"README.md has {len(lines)} lines; move reference material to docs/"


@pytest.mark.parametrize("page", [*PAGES, CHANGELOG], ids=lambda p: p.name)
def test_every_relative_link_resolves(page):
    text = page.read_text(encoding="utf-8")
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if re.match(r"[a-z]+:", target) or target.startswith("#"):
            continue
        path = (page.parent / target.split("#")[0]).resolve()
        assert path.exists(), f"{page.name}: the link {target} leads nowhere ({path})"


# a path into the repository, wherever a page names it: a code span, a command, a fenced block
REPO_PATH = re.compile(r"(?<![\w./~-])((?:lanelib|tests|bench|notebooks|docs|videos|test_images|camera_cal)"
                       r"/[\w./-]*)")
FENCE = re.compile(r"^```[^\n]*\n(.*?)^```", re.M | re.S)


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_repository_path_named_exists(page):
    """Every file or folder of the repository a page names (``tests/...``, ``bench/x.py``, in
    prose, code spans, commands and fenced blocks) exists; a placeholder (``videos/NAME.mp4``,
    ``*``, ``…``) is left out."""
    text = page.read_text(encoding="utf-8")
    for found in REPO_PATH.findall(text):
        path = found.rstrip(".")
        if any(c in path for c in "*…") or re.search(r"[A-Z]{2,}", path) or path in NOT_IN_A_CLONE:
            continue
        assert (REPO / path.rstrip("/")).exists(), f"{page.name}: `{path}` is not in the repository"


def shown_commands(page: Path) -> list[str]:
    """Return the ``python -m lanelib ...`` commands a page shows: each line of a fenced block, each
    code span (one that wraps onto the next line joined), continuation lines joined."""
    text = page.read_text(encoding="utf-8").replace("\\\n", " ")
    pieces = [line for block in FENCE.findall(text) for line in block.splitlines()]
    pieces += [span.replace("\n", " ") for span in re.findall(r"`([^`]+)`", FENCE.sub("", text))]
    return [m.split("#")[0].strip() for piece in pieces for m in re.findall(r"python -m lanelib .+", piece)]


@pytest.mark.parametrize("page, command", [(page, c) for page in PAGES for c in shown_commands(page)],
                         ids=lambda v: v.name if isinstance(v, Path) else v)
def test_every_shown_command_parses(page, command):
    """A shown alternative ``a|b`` is tried as ``a``; an optional ``[...]`` is left out; a sketch
    (``COMMAND``, ``…``) is not a command."""
    text = re.sub(r"\[[^\]]*\]", "", command)
    words = [w.split("|")[0] for w in shlex.split(text)[3:]]
    if not words or words[0] == "COMMAND" or "…" in command:
        pytest.skip("a placeholder, not a command")
    try:
        build_parser().parse_args(words)
    except SystemExit as e:
        pytest.fail(f"{page.name}: the command does not parse: {command} (exit {e.code})")


def test_the_changelog_starts_with_the_package_version():
    """The newest entry of CHANGELOG.md is the version pyproject.toml gives the package."""
    pyproject = (REPO / "pyproject.toml").read_text(encoding="utf-8")
    version = re.search(r'^version = "([^"]+)"', pyproject, re.M)
    entries = re.findall(r"^## \[?(\d+\.\d+\.\d+)", CHANGELOG.read_text(encoding="utf-8"), re.M)
    assert entries and version, "CHANGELOG.md needs '## X.Y.Z - date' entries; pyproject.toml a version"
    assert entries[0] == version.group(1), (
        f"pyproject.toml says {version.group(1)}, the newest CHANGELOG.md entry {entries[0]}: "
        "add the entry or bump the version")
    assert lanelib.__version__ == version.group(1), "lanelib/__init__.py's __version__ differs from pyproject.toml"


def bullets(text: str, label: str) -> list[str]:
    """Return the text of each ``- **label**`` bullet of a page, its wrapped lines joined."""
    found = re.findall(rf"^- \*\*{label}\*\*:? (.*?)(?=\n- |\n\n|\n#|\Z)", text, re.M | re.S)
    return [" ".join(b.split()) for b in found]


def test_the_hard_road_parameters_are_the_presets():
    """Each ``part.key=value`` a part's Parameters name is the ``hard-roads`` preset's value, and
    the page names each setting by which that preset differs from the built-in defaults."""
    named = [s for b in bullets(HARD_ROADS.read_text(encoding="utf-8"), "Parameters")
             for s in re.findall(r"`([a-z_]+\.[\w.]+=[^`]*)`", b)]
    assert len(named) >= 30, named
    hard = preset("hard-roads")
    wrong = [s for s in named if override(hard, [s]) != hard]
    assert not wrong, f"docs/hard-roads.md names other values than the hard-roads preset's: {wrong}"
    keys = {s.partition("=")[0] for s in named}
    missing = [s for s in preset_settings("hard-roads") if s.partition("=")[0] not in keys]
    assert not missing, f"docs/hard-roads.md names no Parameters line for {missing}"


def test_the_hard_road_ablation_rows_are_the_ablations():
    """Each Ablation line names a part of ``docs/ablation.json`` with its switch, what the real
    rows say of it and each real row it changes; every tracker and edge part has one."""
    ab = Ablation.from_dict(json.loads((REPO / "docs" / "ablation.json").read_text(encoding="utf-8")))
    keys = {r.title: r.key for r in ab.baseline}
    rows = bullets(HARD_ROADS.read_text(encoding="utf-8"), "Ablation")
    named = set()
    for row in rows:
        m = re.fullmatch(r'\("([^"]+)", (off|on): (.+?)\): (earns its place|worsens a real row|'
                         r'no effect on the real rows|not measured)\.?(?:: (.*?)\.?)?', row)
        assert m, f"docs/hard-roads.md: an Ablation line of another form: {row}"
        name, how, switch, verdict, figures = m.groups()
        part = ab.part(name)
        assert ((how == "off") == part.default
                and re.findall(r"`([^`]+)`", switch) == list(part.settings)), (name, how, switch)
        assert verdict == ab.verdict(name), (name, verdict)
        shown = {keys[t]: float(v) for t, v in re.findall(r"([A-Z][\w .]*?) ([+-]\d+\.\d)", figures or "")}
        effects = ab.effects(name)
        changed = {k: round(effects[k], 1) for k in REAL if effects.get(k)}
        assert shown == changed, (name, shown, changed)
        named.add(name)
    hard = {p.name for p in ab.parts if p.settings[0].startswith(("tracking.", "edge."))}
    assert hard <= named, f"docs/hard-roads.md has no Ablation line for {sorted(hard - named)}"
