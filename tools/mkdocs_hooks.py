"""MkDocs hooks that generate the docs' pictures and gallery before each build (see mkdocs.yml).

Before the files are collected, docs/generated/ (ignored by git) is filled with the task
gallery (tools/docs_gallery.py), the lifecycle and observables diagrams
(tools/docs_figures.py) and the performance charts (tools/docs_charts.py). The marker
`<!-- benchmark-results -->` in a page is replaced by the benchmark tables.

Under `mkdocs serve` the files are generated for the first build only: writing them into
the watched docs folder would otherwise start a new build after every build.
"""

import json
import os
import pathlib
import subprocess
import sys
import time

_ROOT = pathlib.Path(__file__).resolve().parents[1]
_TOOLS = _ROOT / "tools"
_MARKER = "<!-- benchmark-results -->"

sys.path.insert(0, str(_TOOLS))
import docs_charts  # noqa: E402


def _generated_dir(config) -> pathlib.Path:
    return pathlib.Path(config["docs_dir"]) / "generated"


def _run_tool(script: str, out: pathlib.Path) -> None:
    """Runs a generator in its own interpreter (it picks the GL backend before importing)."""
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, str(_TOOLS / script), str(out)],
        check=True,
        cwd=_ROOT,
        env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")},
        stdout=subprocess.DEVNULL,
    )
    print(f"INFO    -  {script}: {time.perf_counter() - start:.1f} s", flush=True)


_generated_in_this_process = False


def on_pre_build(config, **kwargs) -> None:
    global _generated_in_this_process
    if _generated_in_this_process:
        return
    _generated_in_this_process = True
    out = _generated_dir(config)
    out.mkdir(parents=True, exist_ok=True)
    _run_tool("docs_gallery.py", out)
    _run_tool("docs_figures.py", out)
    docs_charts.write_charts(json.loads(docs_charts.RESULTS.read_text(encoding="utf-8")), out)


def on_page_markdown(markdown: str, page, config, files, **kwargs) -> str:
    if _MARKER not in markdown:
        return markdown
    results = json.loads(docs_charts.RESULTS.read_text(encoding="utf-8"))
    return markdown.replace(_MARKER, docs_charts.performance_markdown(results))
