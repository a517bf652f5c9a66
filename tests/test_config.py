"""PipelineConfig JSON round trip and strict loading."""
from __future__ import annotations

import json

import pytest

from lanelib.config import PipelineConfig, from_dict, load_config, save_config, to_dict
from lanelib.errors import ConfigError, InputError
from lanelib.lanes import SearchConfig
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
