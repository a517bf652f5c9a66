"""The real-data tables of ``docs/results.md``, recomputed: the page cannot drift from what the code does.

Each figure is read from the page itself and compared at the precision it means: per image the
lane width within 0.05 m, the offset within 0.03 m and the radius within 5 %; per video the
percentages in the table. The video rows are guarded in ``tests/test_video.py`` beside the runs
that measure them. Skipped, with how to point at the data, where the Udacity data is absent.
"""
from __future__ import annotations

import math

import pytest

from lanelib import io
from lanelib.pipeline import LanePipeline

pytestmark = pytest.mark.udacity


def number(cell: str) -> float:
    """Return the number in a table cell ('2,705', '-0.49', '3.73'); NaN for '-'."""
    text = cell.replace(",", "").replace("**", "").strip()
    return float("nan") if text in ("-", "—", "") else float(text)


def test_number_parses_the_table_cells():
    assert number("2,705") == 2705 and number("-0.49") == -0.49 and number("**3.73**") == 3.73
    assert math.isnan(number("-"))


@pytest.fixture(scope="module")
def udacity_image_results(udacity_advanced, udacity_calibration):
    pipe = LanePipeline(calibration=udacity_calibration)
    return {f.stem: pipe.process(io.read_image(f))
            for f in sorted((udacity_advanced / "test_images").glob("*.jpg"))}


def test_udacity_image_table(readme_table, udacity_image_results):
    rows = readme_table("Udacity test images")
    assert {r["image"].split()[0] for r in rows} == set(udacity_image_results), \
        "the results table lists other images than the Udacity test_images folder holds"
    for row in rows:
        name = row["image"].split()[0]
        result = udacity_image_results[name]
        assert result.found == (row["lane found"] == "yes"), (name, result.reason)
        if not result.found:
            continue
        assert result.lane_width_m == pytest.approx(number(row["lane width (m)"]), abs=0.05), name
        assert result.offset_m == pytest.approx(number(row["offset (m)"]), abs=0.03), name
        assert result.radius_m == pytest.approx(number(row["radius (m)"]), rel=0.05), name
