"""The docs' learning-curve charts draw the committed CSVs."""

import re
import subprocess
import sys

import pytest

from tools import ROOT
from tools.docs import learning_curves


def test_ticks_are_round_steps_from_zero_past_the_top():
    assert learning_curves.ticks(250.0) == [0, 50, 100, 150, 200, 250]
    assert learning_curves.ticks(125.6) == [0, 20, 40, 60, 80, 100, 120, 140]
    assert learning_curves.ticks(1.0) == [0, 0.2, 0.4, 0.6, 0.8, 1.0]
    assert learning_curves.ticks(0.334) == [0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35]


@pytest.mark.parametrize("curve", learning_curves.CURVES, ids=lambda curve: curve.name)
def test_each_curve_has_a_committed_csv_with_the_columns_it_plots(curve):
    data = learning_curves.read_curve(
        learning_curves.DATA / f"{curve.name}.csv", [p.column for p in curve.panels]
    )
    assert len(data["seconds"]) >= 2
    assert data["seconds"] == sorted(data["seconds"])


def test_a_missing_column_is_named_with_its_file(tmp_path):
    path = tmp_path / "curve.csv"
    path.write_text("seconds,return\n1,2\n", encoding="utf-8")
    with pytest.raises(ValueError, match=r"curve.csv: expected a column 'distance_m'"):
        learning_curves.read_curve(path, ["return", "distance_m"])


def test_chart_puts_the_points_on_the_axes_and_heads_each_panel_with_the_last_value():
    curve = learning_curves.Curve(
        "demo",
        "Demo run",
        (
            learning_curves.Panel("return", "return", 250.0),
            learning_curves.Panel("success", "success rate", 1.0),
        ),
    )
    data = {"seconds": [0.0, 50.0, 100.0], "return": [0.0, 125.0, 250.0]}
    data["success"] = [0.0, float("nan"), 1.0]
    svg = learning_curves.curve_svg(curve, data)
    assert ">Demo run<" in svg
    assert ">return: 250 at 100 s<" in svg
    assert ">success rate: 1 at 100 s<" in svg
    polylines = re.findall(r'<polyline [^>]*points="([^"]*)"', svg)
    # The return rises in a straight line: x from 0 to 100 s, y from 0 to the axis top.
    (x0, y0), (x1, y1), (x2, y2) = (map(float, p.split(",")) for p in polylines[0].split())
    assert x1 - x0 == pytest.approx(x2 - x1) and y0 - y1 == pytest.approx(y1 - y2)
    # A NaN leaves no point.
    assert len(polylines[1].split()) == 2
    assert svg.count("<circle") == 5


def test_builder_writes_a_chart_per_curve(tmp_path):
    subprocess.run(
        [sys.executable, "-m", "tools.docs.learning_curves", str(tmp_path)], check=True, cwd=ROOT
    )
    assert sorted(p.name for p in tmp_path.glob("*.svg")) == sorted(
        f"{curve.name}.svg" for curve in learning_curves.CURVES
    )
