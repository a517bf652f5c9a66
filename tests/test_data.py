"""``lanelib.data``: where the repository's bundled data and the Udacity data are found."""
from __future__ import annotations

import pytest

from lanelib import data
from lanelib.errors import InputError


def test_repo_root_walks_up_to_the_folder_holding_test_images(tmp_path):
    (tmp_path / "test_images").mkdir()
    (tmp_path / "notebooks" / "deeper").mkdir(parents=True)
    assert data.repo_root(tmp_path / "notebooks" / "deeper") == tmp_path
    assert data.bundled("videos", tmp_path / "notebooks") == tmp_path / "videos"


def test_repo_root_outside_a_repo_says_where_it_looked(tmp_path):
    with pytest.raises(InputError, match=f"{tmp_path}: no folder holding test_images"):
        data.repo_root(tmp_path)
    with pytest.raises(InputError, match="camera_cal, test_images, videos"):
        data.bundled("nope", tmp_path)


def test_repo_root_from_anywhere_falls_back_to_this_checkout(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert data.repo_root() == data.PACKAGE_REPO
    assert (data.bundled("test_images") / "straight_1.jpg").is_file()


def test_data_root_follows_lanelib_data(monkeypatch, tmp_path):
    monkeypatch.setenv("LANELIB_DATA", str(tmp_path))
    assert data.data_root() == tmp_path
    monkeypatch.delenv("LANELIB_DATA")
    assert data.data_root() == data.PACKAGE_REPO.parent / "shared" / "data"


def test_udacity_paths_exist_or_say_how_to_point_at_them(monkeypatch, tmp_path):
    monkeypatch.setenv("LANELIB_DATA", str(tmp_path))
    assert data.udacity("test_images") is None
    reason = data.missing_reason("test_images")
    assert str(tmp_path / "udacity-advanced" / "test_images") in reason and "LANELIB_DATA" in reason
    with pytest.raises(InputError, match="set LANELIB_DATA to the folder holding udacity-advanced/"):
        data.require_udacity("camera_cal")
    with pytest.raises(InputError, match="LANELIB_DATA"):
        data.udacity_calibration()
    (tmp_path / "udacity-lanelines-p1" / "test_videos").mkdir(parents=True)
    assert data.udacity("test_videos", data.UDACITY_P1) == tmp_path / "udacity-lanelines-p1" / "test_videos"
