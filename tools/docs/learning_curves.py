"""Draws the committed learning curves (docs/data/train_*.csv) as SVG charts into OUT.

Usage: python -m tools.docs.learning_curves OUT

Writes OUT/<name>.svg for each curve of `CURVES`: side by side, one panel per plotted
column against the run's wall-clock seconds, each point a circle, the last point's value in
the panel's heading. Plain SVG, like `tools.docs.charts`: no plotting library is needed to
build the docs.
"""

import csv
import html
import math
import pathlib
import sys
from typing import NamedTuple

from tools import ROOT

DATA = ROOT / "docs" / "data"

# A panel is _PANEL_W wide; its plot area leaves _LEFT for the y ticks and _RIGHT free, and
# runs from _TOP (below the chart's title and the panel's heading) down _PLOT_H.
_PANEL_W, _PLOT_H = 340, 180
_LEFT, _RIGHT, _TOP = 60, 20, 60
_MAX_INTERVALS = 8
_COLOUR = "#1c7ed6"


class Panel(NamedTuple):
    """One plotted column of a learning curve's CSV."""

    column: str
    label: str
    #: The y axis's upper end; None: the data's largest value, rounded up to a tick.
    top: float | None = None


class Curve(NamedTuple):
    """A committed learning curve: docs/data/<name>.csv, drawn as <name>.svg."""

    name: str
    title: str
    panels: tuple[Panel, ...]


_RETURN = Panel("eval_return", "evaluation return", 250.0)
#: The curves the docs show, with the columns they plot (each CSV has a `seconds` column).
CURVES = (
    Curve(
        "train_sb3_reach_site",
        "SAC (SB3) on reach_site_features, 2-core CPU",
        (_RETURN, Panel("eval_distance", "final distance to target (m)")),
    ),
    Curve(
        "train_rsl_rl_reach_site_h200",
        "PPO (rsl_rl) on reach_site_features, 4,096 worlds, H200",
        (
            Panel("return", "evaluation return", 250.0),
            Panel("distance_m", "final distance to target (m)"),
        ),
    ),
    Curve(
        "train_sb3_lift_brick",
        "SAC (SB3) on lift_brick_features, 2-core CPU",
        (_RETURN, Panel("eval_success", "evaluation success rate", 1.0)),
    ),
)


def read_curve(path: pathlib.Path, columns: list[str]) -> dict[str, list[float]]:
    """The `seconds` column and `columns` of the CSV at `path`, as floats.

    Raises:
      ValueError: if the CSV lacks one of them; the message names the file and the column.
    """
    with open(path, newline="", encoding="utf-8") as file:
        rows = list(csv.DictReader(file))
    header = list(rows[0]) if rows else []
    for column in ["seconds", *columns]:
        if column not in header:
            raise ValueError(f"{path}: expected a column {column!r}, got columns {header}")
    return {column: [float(row[column]) for row in rows] for column in ["seconds", *columns]}


def ticks(top: float) -> list[float]:
    """Tick values from 0 to the first tick at or above `top` (> 0), at most 8 intervals
    of 1, 2 or 5 times a power of ten."""
    power = 10.0 ** math.floor(math.log10(top / _MAX_INTERVALS))
    step = next(m * power for m in (1, 2, 5, 10) if math.ceil(top / (m * power)) <= _MAX_INTERVALS)
    count = math.ceil(round(top / step, 9))
    return [round(i * step, 12) for i in range(count + 1)]


def _text(x: float, y: float, text: str, *, anchor: str = "start", size: int = 12) -> str:
    return (
        f'<text x="{x:.1f}" y="{y:.1f}" font-size="{size}" text-anchor="{anchor}" '
        f'font-family="sans-serif">{html.escape(text)}</text>'
    )


def _number(value: float) -> str:
    return f"{value:.3g}"


def _panel_svg(x0: float, seconds: list[float], values: list[float], panel: Panel) -> list[str]:
    """The SVG elements of one panel whose left edge is at `x0`."""
    points = [(s, v) for s, v in zip(seconds, values) if not math.isnan(v)]
    x_ticks = ticks(max(seconds))
    y_ticks = ticks(panel.top or max(v for _, v in points) or 1.0)
    left, right = x0 + _LEFT, x0 + _PANEL_W - _RIGHT
    top, bottom = _TOP, _TOP + _PLOT_H
    last_s, last_v = points[-1]

    def x_of(s: float) -> float:
        return left + (right - left) * s / x_ticks[-1]

    def y_of(v: float) -> float:
        return bottom - (bottom - top) * v / y_ticks[-1]

    heading = f"{panel.label}: {_number(last_v)} at {last_s:.0f} s"
    parts = [_text((left + right) / 2, top - 12, heading, anchor="middle", size=13)]
    for v in y_ticks:
        parts += [
            f'<line x1="{left}" y1="{y_of(v):.1f}" x2="{right}" y2="{y_of(v):.1f}" '
            f'stroke="#dee2e6"/>',
            _text(left - 6, y_of(v) + 4, _number(v), anchor="end"),
        ]
    parts += [_text(x_of(s), bottom + 18, _number(s), anchor="middle") for s in x_ticks]
    parts += [
        f'<line x1="{left}" y1="{bottom}" x2="{right}" y2="{bottom}" stroke="#212529"/>',
        f'<line x1="{left}" y1="{top}" x2="{left}" y2="{bottom}" stroke="#212529"/>',
        _text((left + right) / 2, bottom + 38, "wall-clock seconds", anchor="middle"),
        '<polyline fill="none" stroke-width="2" stroke="'
        + _COLOUR
        + '" points="'
        + " ".join(f"{x_of(s):.1f},{y_of(v):.1f}" for s, v in points)
        + '"/>',
    ]
    parts += [
        f'<circle cx="{x_of(s):.1f}" cy="{y_of(v):.1f}" r="3" fill="{_COLOUR}"/>' for s, v in points
    ]
    return parts


def curve_svg(curve: Curve, data: dict[str, list[float]]) -> str:
    """Returns the SVG chart of `curve` from `data`, its columns as `read_curve` returns
    them: a title, then one panel per `curve.panels`, side by side."""
    width, height = _PANEL_W * len(curve.panels), _TOP + _PLOT_H + 50
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
        f'viewBox="0 0 {width} {height}">',
        f'<rect width="{width}" height="{height}" fill="white"/>',
        _text(width / 2, 18, curve.title, anchor="middle", size=14),
    ]
    for i, panel in enumerate(curve.panels):
        parts += _panel_svg(i * _PANEL_W, data["seconds"], data[panel.column], panel)
    parts.append("</svg>")
    return "\n".join(parts)


def write_charts(out: pathlib.Path, data_dir: pathlib.Path = DATA) -> list[pathlib.Path]:
    """Writes OUT/<name>.svg for each of `CURVES`, from `data_dir`/<name>.csv; returns
    their paths."""
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for curve in CURVES:
        data = read_curve(data_dir / f"{curve.name}.csv", [p.column for p in curve.panels])
        path = out / f"{curve.name}.svg"
        path.write_text(curve_svg(curve, data), encoding="utf-8")
        paths.append(path)
    return paths


def main() -> None:
    for path in write_charts(pathlib.Path(sys.argv[1])):
        print(path)


if __name__ == "__main__":
    main()
