"""The docs' generated pictures, gallery and benchmark tables show what the code does."""

import json
import pathlib
import struct
import subprocess
import sys

import pytest

from tools import ROOT
from tools.docs import RESULTS, benchmark_results
from tools.docs import charts as docs_charts
from tools.docs import figures as docs_figures
from tools.docs import gallery as docs_gallery


def test_hook_trace_records_reset_hooks_task_first_then_entity():
    trace = docs_figures.hook_trace()
    assert trace.reset == (
        "task.initialize_episode_mjcf",
        "entity.initialize_episode_mjcf",
        "task.after_compile",
        "entity.after_compile",
        # dm_control samples the observables after every compile, then after the episode's
        # initialisation (each sample may draw a corruptor's noise).
        "observables sampled",
        "task.initialize_episode",
        "entity.initialize_episode",
        "observables sampled",
    )


def test_hook_trace_step_has_one_physics_step_per_sub_step_between_the_substep_hooks():
    trace = docs_figures.hook_trace()
    assert trace.n_sub_steps == 2
    one_sub_step = (
        "task.before_substep",
        "entity.before_substep",
        "physics step (mj_step)",
        "task.after_substep",
        "entity.after_substep",
    )
    assert trace.step == (
        ("task.before_step", "entity.before_step")
        + one_sub_step * 2
        + (
            "task.after_step",
            "entity.after_step",
            "observables sampled",
            "task.get_reward",
            "task.get_discount",
            "task.should_terminate_episode",
        )
    )


def test_lifecycle_svg_draws_the_sub_step_once_and_marks_it_repeated():
    svg = docs_figures.lifecycle_svg(docs_figures.hook_trace())
    assert svg.count(">physics step (mj_step)<") == 1
    assert "× n_sub_steps" in svg
    assert svg.count(">task.initialize_episode<") == 1


def test_observation_timeline_shows_what_each_option_delivers_after_step_two():
    rows = {row.label: row for row in docs_figures.observation_timeline()}
    # Five sub-steps per control step: step 2 ends at sub-step 10.
    assert rows["default (interval 1, buffer 1)"].observations[2] == (10.0,)
    assert rows["update_interval=2, buffer_size=3"].observations[2] == (6.0, 8.0, 10.0)
    # A delay of 3 holds back the samples of sub-steps 8 and 10.
    assert rows["update_interval=2, buffer_size=3, delay=3"].observations[2] == (2.0, 4.0, 6.0)
    # The mean of sub-steps 6 to 10.
    assert rows["buffer_size=5, aggregator='mean'"].observations[2] == (8.0,)
    assert rows["update_interval=2, buffer_size=3"].samples == (0, 2, 4, 6, 8, 10, 12, 14)


def test_timeline_svg_rings_the_samples_the_agent_sees():
    rows = docs_figures.observation_timeline()
    svg = docs_figures.timeline_svg(rows)
    # 1 + 3 + 3 + 5 rings in the rows, plus one in the legend.
    assert svg.count('r="10" fill="none"') == 13


def _png_size(path: pathlib.Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = struct.unpack(">II", data[16:24])
    return width, height


def test_gallery_renders_a_task_and_lists_its_specs(tmp_path):
    entry = docs_gallery.render_task("reach_site_features", tmp_path, ("features", "easy"))
    assert _png_size(tmp_path / "reach_site_features.png") == (400, 300)
    observations = {row.name: row.shape for row in entry.observations}
    assert observations["jaco_arm/joints_pos"] == (1, 6, 2)
    assert observations["target_position"] == (1, 3)
    assert len(entry.actions) == 9
    assert entry.actions[0].name == "jaco_arm/joint_1_velocity"

    markdown = docs_gallery.gallery_markdown([entry], seconds=1.0)
    assert "## reach_site_features" in markdown
    assert "![reach_site_features after reset](reach_site_features.png)" in markdown
    assert "| `target_position` | (1, 3) | float64 |" in markdown
    assert "Tags: `features`, `easy`." in markdown


_RESULTS = {
    "measured": "2026-01-01 00:00 UTC",
    "commit": "abc1234",
    "machine": {"cpu": "Test CPU", "cores": 4, "os": "Linux", "python": "3.11", "mujoco": "4"},
    "benchmarks": [
        {
            "name": "demo",
            "title": "Demo",
            "baseline": "raw calls",
            "command": "python benchmarks/demo.py",
            "rows": [
                {
                    "label": "fast",
                    "time": 50.0,
                    "baseline": 100.0,
                    "unit": "us",
                    "ratio": 0.5,
                    "target": "<= 1",
                },
                {
                    "label": "slow",
                    "time": 4590.0,
                    "baseline": 3670.0,
                    "unit": "us",
                    "ratio": 1.25,
                    "target": "",
                },
            ],
        }
    ],
}


def test_times_are_written_in_the_unit_that_fits_them():
    assert docs_charts.format_time(4590.0, "us") == "4.59 ms"
    assert docs_charts.format_time(0.428, "ms") == "428 µs"
    assert docs_charts.format_time(1500.0, "ms") == "1.5 s"
    assert docs_charts.format_time(0.0, "ms") == "0 µs"


def test_chart_has_a_bar_per_row_coloured_by_side_of_the_baseline():
    svg = docs_charts.ratio_chart_svg(_RESULTS["benchmarks"][0])
    assert svg.count('fill="#1c7ed6"') == 1  # fast: below the baseline
    assert svg.count('fill="#f08c00"') == 1  # slow: above it
    assert "0.5×   50 µs vs 100 µs" in svg
    assert "1.25×   4.59 ms vs 3.67 ms" in svg


def test_performance_markdown_names_the_machine_and_links_each_chart():
    markdown = docs_charts.performance_markdown(_RESULTS)
    assert "| CPU | Test CPU (4 cores) |" in markdown
    assert "![Demo](generated/perf_demo.svg)" in markdown
    assert "| fast | 50 µs | 100 µs | 0.5 | &lt;= 1 |" in markdown


def test_step_overhead_table_is_parsed_into_rows():
    output = (
        "scene / measurement          time (us)  baseline (us)   ratio   target\n"
        "mesh links: env.step / 20 x mj_step   646.8   538.5   0.940  <= 1.15\n"
        "capsule links: reset, MJCF unchanged / XML compile  113.4  680.9   0.167\n"
    )
    rows = benchmark_results.parse_step_overhead(output)
    assert rows == [
        benchmark_results.Row(
            "mesh links: env.step / 20 x mj_step", 646.8, 538.5, "us", 0.94, "<= 1.15"
        ),
        benchmark_results.Row(
            "capsule links: reset, MJCF unchanged / XML compile", 113.4, 680.9, "us", 0.167, ""
        ),
    ]


def test_mjcf_compile_rows_take_the_baseline_of_their_unit():
    output = (
        "Baseline: compile 11.60 ms (median of 70); direct geom_xpos[ids] read 1.03 us\n"
        "row   median  ratio best-of-N target  result\n"
        "to_xml_string, first call                 1.74 ms  0.17x     0.19x  0.50x  PASS\n"
        "bind(20 geoms).xpos                       0.64 us  0.62x     0.64x  3.00x  PASS\n"
    )
    rows = benchmark_results.parse_mjcf_compile(output)
    assert [(row.label, row.baseline, row.unit) for row in rows] == [
        ("to_xml_string, first call", 11.6, "ms"),
        ("bind(20 geoms).xpos", 1.03, "us"),
    ]


def test_observation_updater_and_manipulation_tables_are_parsed():
    updater = benchmark_results.parse_observation_updater(
        "baseline: 20 x mujoco.mj_step = 712.0 us per control step (35.6 us per mj_step)\n"
        "defaults                       at sample_steps       4.7       0.007\n"
    )
    assert updater == [benchmark_results.Row("defaults (at sample_steps)", 4.7, 712.0, "us", 0.007)]
    manipulation = benchmark_results.parse_manipulation(
        "task    reset ms  step ms   raw ms  overhead  render\n"
        "reach_site_features       8.63    0.428    0.214     1.957          > target\n"
    )
    assert manipulation == [
        benchmark_results.Row("reach_site_features", 0.428, 0.214, "ms", 1.957, "<= 1.1")
    ]


def test_committed_benchmark_results_cover_every_benchmark_and_name_the_machine():
    results = json.loads(RESULTS.read_text(encoding="utf-8"))
    assert [b["name"] for b in results["benchmarks"]] == [
        b.name for b in benchmark_results.BENCHMARKS
    ]
    assert all(b["rows"] for b in results["benchmarks"])
    assert results["machine"]["cpu"] and results["machine"]["cores"] >= 1


_TOOL_MODULES = sorted((ROOT / "tools").rglob("*.py"))


@pytest.mark.parametrize("script", _TOOL_MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_every_tool_says_what_it_does_in_its_first_docstring_line(script):
    first_line = script.read_text(encoding="utf-8").splitlines()[0]
    assert first_line.startswith('"""') and len(first_line) > 20


@pytest.mark.parametrize("script", _TOOL_MODULES, ids=lambda p: str(p.relative_to(ROOT)))
def test_no_tool_edits_the_import_path(script):
    assert "sys.path" not in script.read_text(encoding="utf-8")


def test_charts_builder_writes_a_chart_per_benchmark_and_the_performance_tables(tmp_path):
    subprocess.run([sys.executable, "-m", "tools.docs.charts", str(tmp_path)], check=True, cwd=ROOT)
    names = [b["name"] for b in json.loads(RESULTS.read_text(encoding="utf-8"))["benchmarks"]]
    assert sorted(p.name for p in tmp_path.glob("*.svg")) == sorted(f"perf_{n}.svg" for n in names)
    tables = (tmp_path / "performance_tables.md").read_text(encoding="utf-8")
    assert tables.startswith("Measured ")
    assert tables.count("| measurement | time | baseline | ratio | target |") == len(names)
