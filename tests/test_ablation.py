"""The ablation's arithmetic on hand-made rows, its choice of parts, and one real run on a synthetic row."""
from __future__ import annotations

import json

import pytest

from lanelib import ablation
from lanelib.ablation import Ablation, Part
from lanelib.cli import main
from lanelib.batch import benchmark_config
from lanelib.config import PipelineConfig, override
from lanelib.errors import InputError
from lanelib.scoreboard import Row

ON = Part("kept part", ("search.grow_margin_px=0",), True, "on by default")
OPT = Part("opt-in part", ("thresholds.clahe=true",), False, "off by default")


def rows(culane_f1, project_pct, synth_pct, tusimple_skipped=False, tusimple=80.0):
    return [Row("culane", "CULane dev", frames=120, figures={"f1_pct": culane_f1, "precision_pct": 80.0}),
            Row("tusimple", "TuSimple dev", skipped="no data") if tusimple_skipped else
            Row("tusimple", "TuSimple dev", frames=10, figures={"accuracy_pct": 85.0, "f1_pct": tusimple}),
            Row("project", "Udacity project video", frames=1260, figures={"plausible_pct": project_pct}),
            Row("synth-clip", "synthetic clip", frames=250, figures={"point_accuracy_pct": synth_pct})]


def test_an_effect_is_positive_where_the_part_helps_whether_it_is_on_by_default_or_opt_in():
    ab = Ablation(rows(57.5, 100.0, 99.0),
                  {ON.name: rows(55.0, 100.0, 99.5),      # off: CULane falls 2.5, synth rises 0.5
                   OPT.name: rows(57.5, 99.0, 100.0, tusimple_skipped=True)},  # on: project falls 1
                  (ON, OPT))
    assert ab.effects(ON.name) == {"culane": 2.5, "tusimple": 0.0, "project": 0.0, "synth-clip": -0.5}
    assert ab.effects(OPT.name) == {"culane": 0.0, "tusimple": None, "project": -1.0, "synth-clip": 1.0}
    assert ab.verdict(ON.name) == "earns its place"  # the synthetic row's loss does not count
    assert ab.verdict(OPT.name) == "worsens a real row"  # its synthetic gain is no reason
    table = ablation.format_table(ab).splitlines()
    assert table[2].split("|")[3:7] == [" 57.5 ", " 80.0 ", " 100.0 ", " 99.0 "]
    assert table[3].split("|")[3:7] == [" 0.21 ", " 2.5 ", " 0.1 ", " 0.4 "]  # one line, or one frame
    assert "| kept part | off: `search.grow_margin_px=0` | +2.5 | +0.0 | +0.0 | -0.5 | earns its place |" in table
    assert "| opt-in part | on: `thresholds.clahe=true` | +0.0 | - | -1.0 | +1.0 | worsens a real row |" in table


def test_a_change_within_a_rows_resolution_says_nothing():
    base = rows(57.5, 100.0, 99.0)
    # off: CULane F1 0.1 lower, less than one line of its 120 frames; the synthetic clip's loss
    ab = Ablation(base, {ON.name: rows(57.4, 100.0, 90.0)}, (ON,))
    assert ab.verdict(ON.name) == "no effect on the real rows"
    # off: CULane 6.5 lower, TuSimple 0.6 higher: less than one line of its 10 frames
    ab = Ablation(base, {ON.name: rows(51.0, 100.0, 99.0, tusimple=80.6)}, (ON,))
    assert ab.effects(ON.name)["tusimple"] == -0.6
    assert ab.verdict(ON.name) == "earns its place"
    # off: TuSimple 3 points higher, more than one line: the part worsens it
    ab = Ablation(base, {ON.name: rows(51.0, 100.0, 99.0, tusimple=83.0)}, (ON,))
    assert ab.verdict(ON.name) == "worsens a real row"


def test_verdicts_without_real_rows():
    synth_only = [Row("synth-clip", "synthetic clip", frames=250, figures={"point_accuracy_pct": 99.0})]
    ab = Ablation(synth_only, {ON.name: synth_only}, (ON,))
    assert ab.verdict(ON.name) == "not measured"


def test_a_tusimple_row_with_frames_over_its_time_limit_is_not_compared():
    slow = rows(57.5, 100.0, 99.0)
    slow[1] = Row("tusimple", "TuSimple dev", frames=10, figures={"f1_pct": 72.0, "over_200ms": 1})
    ab = Ablation(rows(57.5, 100.0, 99.0), {ON.name: slow}, (ON,))
    assert ab.effects(ON.name)["tusimple"] is None
    assert ab.verdict(ON.name) == "no effect on the real rows"


def test_the_ablation_reads_back_from_its_json(tmp_path):
    ab = Ablation(rows(57.5, 100.0, 99.0), {ON.name: rows(55.0, 100.0, 99.5)}, (ON,))
    path = tmp_path / "ablation.json"
    path.write_text(json.dumps(ab.to_dict()))
    back = Ablation.from_dict(json.loads(path.read_text()))
    assert back == ab
    assert ablation.format_table(back) == ablation.format_table(ab)


def test_every_part_is_a_valid_setting_and_parts_are_chosen_by_name():
    for part in ablation.PARTS:  # each switches something, in the default config or a benchmark's
        configs = (PipelineConfig(), benchmark_config("culane"), benchmark_config("tusimple"))
        assert any(override(c, part.settings) != c for c in configs), part.name
    assert [p.name for p in ablation.choose(["CLAHE", "growing margin"])] == ["growing margin", "CLAHE"]
    with pytest.raises(InputError, match="no such part; the parts are fallback masks, "):
        ablation.choose(["no-such-part"])


def test_a_tracker_part_changes_nothing_on_a_predicted_row(tmp_path):
    # the history of bases acts only in the tracker: the predict row's figures do not move
    # (a CULane-format row: its score has no time limit, so a loaded machine cannot move it)
    part = ablation.choose(["history of bases"])
    ab = ablation.run(part, only=["synth-culane"], out=tmp_path)
    assert ab.baseline[0].figures == ab.switched["history of bases"][0].figures
    assert ab.effects("history of bases") == {"synth-culane": 0.0}


def test_the_command_refuses_an_unknown_part_or_row(capsys):
    assert main(["ablation", "--parts", "nothing"]) == 2
    assert "no such part" in capsys.readouterr().err
    assert main(["ablation", "--only", "nothing"]) == 2
    assert "no such row" in capsys.readouterr().err
