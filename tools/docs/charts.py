"""Draws the performance charts and tables from docs/data/benchmark_results.json into OUT.

Usage: python -m tools.docs.charts OUT

Writes OUT/perf_<name>.svg per benchmark and OUT/performance_tables.md, the Markdown that the
docs hook puts in place of the performance page's marker.

Each chart is a horizontal bar per measured row, its length the ratio to the baseline
measured in the same run, with a line at 1 (as fast as the baseline) and the two absolute
times written beside the bar. Plain SVG: no plotting library is needed to build the docs.
"""

import html
import json
import pathlib
import sys

from tools.docs import RESULTS

#: The Markdown of `performance_markdown`, written next to the charts.
TABLES_FILE = "performance_tables.md"

_WIDTH, _BAR_W, _ROW_H, _TOP, _LEFT = 680, 400, 44, 34, 12
# Units by size, so that times read as "4.59 ms", never "4.59e+03 µs".
_SECONDS_PER_UNIT = {"s": 1.0, "ms": 1e-3, "us": 1e-6}


def _text(x: float, y: float, text: str, *, anchor: str = "start", size: int = 13) -> str:
    return (
        f'<text x="{x}" y="{y}" font-size="{size}" text-anchor="{anchor}" '
        f'font-family="sans-serif">{html.escape(text)}</text>'
    )


def format_time(value: float, unit: str) -> str:
    """`value` in `unit` ('s', 'ms' or 'us') written in the unit that keeps it in [1, 1000)."""
    seconds = value * _SECONDS_PER_UNIT[unit]
    for name, scale in (("s", 1.0), ("ms", 1e-3), ("µs", 1e-6)):
        if abs(seconds) >= scale:
            return f"{seconds / scale:.3g} {name}"
    return f"{seconds / 1e-6:.3g} µs"


def ratio_chart_svg(benchmark: dict) -> str:
    """Returns an SVG bar chart of a benchmark's rows as ratios to their baselines.

    Each row is its label, and below it a bar as long as the ratio, with the ratio and the
    two absolute times beside it; a dashed line marks 1 (as fast as the baseline).
    """
    rows = benchmark["rows"]
    scale_max = max(1.5, max(row["ratio"] for row in rows) * 1.05)
    height = _TOP + len(rows) * _ROW_H + 30

    def x_of(ratio: float) -> float:
        return _LEFT + _BAR_W * min(ratio, scale_max) / scale_max

    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{_WIDTH}" height="{height}" '
        f'viewBox="0 0 {_WIDTH} {height}">',
        f'<rect width="{_WIDTH}" height="{height}" fill="white"/>',
        _text(_LEFT, 18, "time / baseline time (shorter is faster)", size=12),
    ]
    for i, row in enumerate(rows):
        y = _TOP + i * _ROW_H
        colour = "#1c7ed6" if row["ratio"] <= 1 else "#f08c00"
        bar_end = x_of(row["ratio"])
        parts += [
            _text(_LEFT, y + 12, row["label"]),
            f'<rect x="{_LEFT}" y="{y + 18}" width="{max(bar_end - _LEFT, 1):.1f}" '
            f'height="16" fill="{colour}"/>',
            _text(
                bar_end + 6,
                y + 31,
                f"{row['ratio']:.3g}×   {format_time(row['time'], row['unit'])} vs "
                f"{format_time(row['baseline'], row['unit'])}",
                size=12,
            ),
        ]
    one = x_of(1.0)
    # The baseline mark runs through the bars only, so that it does not cross the labels.
    parts += [
        f'<line x1="{one}" y1="{_TOP + i * _ROW_H + 15}" x2="{one}" '
        f'y2="{_TOP + i * _ROW_H + 37}" stroke="#212529" stroke-dasharray="4 2"/>'
        for i in range(len(rows))
    ]
    parts += [
        _text(one, height - 8, "| 1 = baseline", anchor="start", size=12),
        "</svg>",
    ]
    return "\n".join(parts)


def performance_markdown(results: dict) -> str:
    """Returns the machine table and, per benchmark, its chart and its table as Markdown."""
    machine = results["machine"]
    lines = [
        f"Measured {results['measured']} at commit `{results['commit']}` on:",
        "",
        "| machine | |",
        "|---|---|",
        f"| CPU | {machine['cpu']} ({machine['cores']} cores) |",
        f"| OS | {machine['os']} |",
        f"| Python | {machine['python']} |",
        f"| MuJoCo | {machine['mujoco']} |",
        *([f"| note | {machine['note']} |"] if machine.get("note") else []),
        "",
    ]
    for benchmark in results["benchmarks"]:
        lines += [
            f"## {benchmark['title']}",
            "",
            f"`{benchmark['command']}`. Baseline, measured in the same run: "
            f"{benchmark['baseline']}.",
            "",
            f"![{benchmark['title']}](generated/perf_{benchmark['name']}.svg)",
            "",
            "| measurement | time | baseline | ratio | target |",
            "|---|---|---|---|---|",
        ]
        lines += [
            f"| {row['label']} | {format_time(row['time'], row['unit'])} | "
            f"{format_time(row['baseline'], row['unit'])} | {row['ratio']:.3g} | "
            f"{html.escape(row['target']) or '—'} |"
            for row in benchmark["rows"]
        ]
        lines.append("")
    return "\n".join(lines)


def write_charts(results: dict, out: pathlib.Path) -> list[pathlib.Path]:
    """Writes one `perf_<name>.svg` per benchmark into `out` and returns their paths."""
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for benchmark in results["benchmarks"]:
        path = out / f"perf_{benchmark['name']}.svg"
        path.write_text(ratio_chart_svg(benchmark), encoding="utf-8")
        paths.append(path)
    return paths


def main() -> None:
    out = pathlib.Path(sys.argv[1])
    results = json.loads(RESULTS.read_text(encoding="utf-8"))
    for path in write_charts(results, out):
        print(path)
    tables = out / TABLES_FILE
    tables.write_text(performance_markdown(results), encoding="utf-8")
    print(tables)


if __name__ == "__main__":
    main()
