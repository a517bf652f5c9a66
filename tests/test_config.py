"""PipelineConfig JSON round trip and strict loading."""
from __future__ import annotations

import json

import pytest

from lanelib import config
from lanelib.config import PipelineConfig, from_dict, load_config, override, save_config, to_dict
from lanelib.errors import ConfigError, InputError
from lanelib.params import SearchConfig
from lanelib.thresholds import ChannelMask


def test_default_config_round_trips(tmp_path):
    path = save_config(PipelineConfig(), tmp_path / "c.json")
    assert load_config(path) == PipelineConfig()


def test_changed_config_round_trips(tmp_path):
    import dataclasses

    cfg = PipelineConfig()
    cfg = dataclasses.replace(
        cfg, search=SearchConfig(n_windows=12, margin_px=70),
        thresholds=dataclasses.replace(cfg.thresholds, s_channel=ChannelMask("hls", "s", 120, 250, False),
                                       rule="s_channel | white"))
    back = load_config(save_config(cfg, tmp_path / "c.json"))
    assert back == cfg and back.thresholds.s_channel.low == 120
    assert isinstance(back.perspective.src_px[0], tuple)


def test_the_seeds_switches_round_trip(tmp_path):
    import dataclasses

    from lanelib.thresholds import ColorRange

    cfg = PipelineConfig()
    cfg = dataclasses.replace(
        cfg, search=SearchConfig(trim_outliers_pct=95.0, window_histogram=True, centre_first=True,
                                 grow_margin_px=30),
        thresholds=dataclasses.replace(cfg.thresholds, clahe=True, clahe_clip_limit=3.0, clahe_tile_px=100,
                                       yellow=ColorRange("hsv", (15, 80, 120), (35, 255, 255), open_px=3),
                                       s_channel=ChannelMask("hls", "s", 170, 255, open_px=5)))
    back = load_config(save_config(cfg, tmp_path / "c.json"))
    assert back == cfg
    saved = json.loads((tmp_path / "c.json").read_text())
    assert saved["search"]["trim_outliers_pct"] == 95.0 and saved["search"]["grow_margin_px"] == 30
    assert saved["thresholds"]["clahe"] is True and saved["thresholds"]["yellow"]["open_px"] == 3
    # the defaults: every switch off (the growing margin is a part of the hard-roads preset)
    d = to_dict(PipelineConfig())
    assert (d["search"]["trim_outliers_pct"], d["search"]["window_histogram"], d["search"]["centre_first"],
            d["search"]["grow_margin_px"]) == (0.0, False, False, 0)
    assert d["thresholds"]["clahe"] is False and d["thresholds"]["white"]["open_px"] == 0


def test_partial_file_keeps_defaults(tmp_path):
    p = tmp_path / "c.json"
    p.write_text(json.dumps({"search": {"margin_px": 50}, "thresholds": {"white": {"low": [0, 190, 0]}}}))
    cfg = load_config(p)
    assert cfg.search.margin_px == 50 and cfg.search.n_windows == SearchConfig().n_windows
    assert cfg.thresholds.white.low == (0, 190, 0) and cfg.thresholds.white.space == "hls"


@pytest.mark.parametrize("data,message", [
    ({"serch": {}}, r"serch: unknown key"),
    ({"search": {"margin": 3}}, r"search\.margin: unknown key"),
    ({"search": {"margin_px": "wide"}}, r"search\.margin_px: expected a whole number"),
    ({"search": {"n_windows": 9.5}}, r"search\.n_windows: expected a whole number"),
    ({"thresholds": {"white": {"low": [0, 200]}}}, r"thresholds\.white\.low: expected 3 values"),
    ({"thresholds": {"yellow": {"enabled": "yes"}}}, r"thresholds\.yellow\.enabled: expected true or false"),
    ({"thresholds": {"rule": "white | nothing"}}, r"unknown mask 'nothing'"),
    ({"perspective": {"lane_width_m": True}}, r"perspective\.lane_width_m: expected a number"),
    ({"lines": {"follow_ahead_m": -5}}, r"lines: follow_ahead_m -5\.0, seen_window_m 2\.0, contrast_full 0\.0, "
                                      r"refine_points_px 0\.0, min_lane_fraction 0\.0 and tight_scatter_m 0\.0 "
                                      r"must be 0 \(off\) or more"),
    ({"lines": {"contrast_full": -1}}, r"contrast_full -1\.0, refine_points_px 0\.0, min_lane_fraction 0\.0 and"),
    ({"lines": {"refine_points_px": -6}}, r"refine_points_px -6\.0, min_lane_fraction 0\.0 and tight_scatter_m"),
    ({"lines": {"min_lane_fraction": -0.7}}, r"min_lane_fraction -0\.7 and tight_scatter_m 0\.0 must be 0 \(off\)"),
    ({"lines": {"tight_scatter_m": -0.04}}, r"tight_scatter_m -0\.04 must be 0 \(off\) or more"),
])
def test_bad_keys_and_types_name_the_key(tmp_path, data, message):
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(data))
    with pytest.raises(ConfigError, match=message):
        load_config(p)


def test_unreadable_files(tmp_path):
    with pytest.raises(InputError, match="no such config file"):
        load_config(tmp_path / "missing.json")
    p = tmp_path / "broken.json"
    p.write_text("{not json")
    with pytest.raises(InputError, match="not valid JSON"):
        load_config(p)
    p.write_text("[1, 2]")
    with pytest.raises(ConfigError, match="JSON object"):
        load_config(p)


def test_to_dict_from_dict_are_inverse():
    d = to_dict(PipelineConfig())
    assert from_dict(PipelineConfig, d) == PipelineConfig()
    json.dumps(d)  # JSON-able


def test_the_checks_of_older_files_move_from_tracking_to_checks(tmp_path):
    p = tmp_path / "old.json"
    p.write_text(json.dumps({"tracking": {"min_width_m": 2.8, "max_width_m": 4.2, "max_width_spread_m": 0.9,
                                          "max_curvature_diff_1pm": 0.003, "max_band_fill": 0.5,
                                          "check_rows": 10, "max_jump_m": 0.4}}))
    cfg = load_config(p)
    assert (cfg.checks.min_width_m, cfg.checks.max_width_m, cfg.checks.max_width_spread_m,
            cfg.checks.max_curvature_diff_per_m, cfg.checks.max_band_fill, cfg.checks.check_rows) == \
        (2.8, 4.2, 0.9, 0.003, 0.5, 10)
    assert cfg.tracking.max_bend_m == 0.9 and cfg.tracking.max_jump_m == 0.4  # the old key limited both
    assert cfg.checks.max_band_scatter == PipelineConfig().checks.max_band_scatter
    assert load_config(save_config(cfg, tmp_path / "new.json")) == cfg
    assert "min_width_m" not in json.loads((tmp_path / "new.json").read_text())["tracking"]


def test_the_old_1pm_name_of_a_curvature_key_still_loads(tmp_path):
    p = tmp_path / "old.json"
    p.write_text(json.dumps({"checks": {"max_curvature_diff_1pm": 0.002}}))
    assert load_config(p).checks.max_curvature_diff_per_m == 0.002


def test_an_old_key_may_not_contradict_its_new_key(tmp_path):
    p = tmp_path / "both.json"
    p.write_text(json.dumps({"tracking": {"min_width_m": 2.8}, "checks": {"min_width_m": 3.1}}))
    with pytest.raises(ConfigError, match=r"tracking\.min_width_m is now checks\.min_width_m.*keep only "
                                          r"checks\.min_width_m"):
        load_config(p)
    p.write_text(json.dumps({"tracking": {"min_width_m": 3.1, "max_width_spread_m": 0.9, "max_bend_m": 0.5},
                             "checks": {"min_width_m": 3.1}}))
    cfg = load_config(p)
    assert cfg.checks.min_width_m == 3.1 and cfg.checks.max_width_spread_m == 0.9
    assert cfg.tracking.max_bend_m == 0.5  # set in the file: not overwritten by the old key


def test_override_sets_dotted_keys_with_their_types():
    from lanelib.config import override
    cfg = override(PipelineConfig(), ["search.trim_outliers_pct=95", "thresholds.clahe=true",
                                      "thresholds.yellow.open_px=3", "thresholds.rule=yellow | white",
                                      "checks.min_width_m=2.8", "tracking.base_history_frames=25"])
    assert cfg.search.trim_outliers_pct == 95.0 and isinstance(cfg.search.trim_outliers_pct, float)
    assert cfg.thresholds.clahe is True and cfg.thresholds.yellow.open_px == 3
    assert cfg.thresholds.rule == "yellow | white"
    assert cfg.checks.min_width_m == 2.8 and cfg.tracking.base_history_frames == 25
    # everything else stays as it was, and the later setting wins
    assert cfg.search.margin_px == PipelineConfig().search.margin_px
    assert override(cfg, ["search.margin_px=40", "search.margin_px=50"]).search.margin_px == 50
    assert override(PipelineConfig(), []) == PipelineConfig()


@pytest.mark.parametrize("setting, message", [
    ("search.trim_outliers_pct", "write it as part.key=value"),
    ("search.trim=95", "search.trim is not a key; known keys in search: candidates, centre_first"),
    ("serch.margin_px=3", "serch is not a part of the config; its parts: checks, draw"),
    ("search.margin_px.x=3", "search.margin_px is not a part of search"),
    ("search.margin_px=wide", "search.margin_px: expected a whole number, got 'wide'"),
    ("search.trim_outliers_pct=200", "trim_outliers_pct 200.0 must lie in 0-100"),
])
def test_a_bad_override_names_the_setting_and_the_fix(setting, message):
    from lanelib.config import override
    with pytest.raises(ConfigError) as e:
        override(PipelineConfig(), [setting])
    assert message in str(e.value) and repr(setting) in str(e.value)
    assert "search: search:" not in str(e.value)


def test_the_trend_and_blind_hold_of_the_tracker_round_trip(tmp_path):
    import dataclasses

    cfg = PipelineConfig()
    assert (cfg.tracking.trend_frames, cfg.tracking.blind_hold_frames) == (0, 0)  # off: hard-roads parts
    assert (config.preset("hard-roads").tracking.trend_frames, config.preset("hard-roads").tracking.blind_hold_frames) == (5, 12)
    cfg = dataclasses.replace(cfg, tracking=dataclasses.replace(cfg.tracking, trend_frames=3, blind_hold_frames=4))
    back = load_config(save_config(cfg, tmp_path / "c.json"))
    assert back == cfg
    saved = json.loads((tmp_path / "c.json").read_text())["tracking"]
    assert (saved["trend_frames"], saved["blind_hold_frames"]) == (3, 4)


def test_the_lines_part_is_set_saved_and_loaded(tmp_path):
    cfg = override(PipelineConfig(), ["lines.max_slope=0.3", "lines.bands=3"])
    assert (cfg.lines.max_slope, cfg.lines.bands) == (0.3, 3)
    save_config(cfg, tmp_path / "c.json")
    assert load_config(tmp_path / "c.json").lines == cfg.lines != PipelineConfig().lines
