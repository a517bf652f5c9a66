"""``lanelib.data``: where the repository's bundled data and the real data beside it are found."""
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


def test_the_benchmark_sets_count_only_with_the_file_they_are_used_by(monkeypatch, tmp_path):
    monkeypatch.setenv("LANELIB_DATA", str(tmp_path))
    assert data.culane_dev() is None and data.tusimple_dev() is None and data.challenge_video() is None
    for name, need in ((data.CULANE_DEV, "list.txt"), (data.TUSIMPLE_DEV, "label_data_fullres.json")):
        assert "culane-dev/ and tusimple-dev/" in data.missing_reason(name=name)
        assert data.missing_reason(name=name).startswith(f"{tmp_path / name / need} not found")
        (tmp_path / name).mkdir()
        assert data.dataset(name) is None  # a folder without the file it is used by is no data set
        # a path inside a set whose file is missing names that file: the fix is there
        assert data.missing_reason("clips", name).startswith(f"{tmp_path / name / need} not found")
        with pytest.raises(InputError, match=f"{need} not found: set LANELIB_DATA"):
            data.require(name, "clips")
        (tmp_path / name / need).write_text("")
        assert data.dataset(name) == tmp_path / name
        assert data.missing_reason("clips", name).startswith(f"{tmp_path / name / 'clips'} not found")
    assert data.culane_dev() == tmp_path / "culane-dev" and data.tusimple_dev() == tmp_path / "tusimple-dev"
    video = tmp_path / "udacity-advanced" / "videos" / "challenge_video.mp4"
    video.parent.mkdir(parents=True)
    video.write_bytes(b"")
    assert data.challenge_video() == video == data.require(data.UDACITY_ADVANCED, data.CHALLENGE_VIDEO)


def test_the_fixtures_give_the_real_benchmark_sets(culane_dev, tusimple_dev):
    assert (culane_dev / "list.txt").is_file() and (culane_dev / "driver_161_90frame").is_dir()
    assert (tusimple_dev / "label_data.json").is_file() and (tusimple_dev / "clips").is_dir()
