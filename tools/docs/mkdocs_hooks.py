"""MkDocs hooks that generate the docs' pictures and gallery before each build (see mkdocs.yml).

Before the files are collected, docs/generated/ (ignored by git) is filled with the task
gallery (`tools.docs.gallery`), the lifecycle and observables diagrams (`tools.docs.figures`),
the performance charts and tables (`tools.docs.charts`) and the learning curves
(`tools.docs.learning_curves`). The marker
`<!-- benchmark-results -->` in a page is replaced by those tables.

Each builder runs as `python -m tools.docs.NAME` in its own interpreter, from the folder of
mkdocs.yml (the repository root): it picks the GL backend before importing MuJoCo.

Under `mkdocs serve` the files are generated for the first build only: writing them into
the watched docs folder would otherwise start a new build after every build.
"""

import os
import pathlib
import subprocess
import sys
import time

_MARKER = "<!-- benchmark-results -->"
# `tools.docs.charts.TABLES_FILE`, which this hook, loaded from its file, cannot import.
_TABLES_FILE = "performance_tables.md"


def _generated_dir(config) -> pathlib.Path:
    return pathlib.Path(config["docs_dir"]) / "generated"


def _run_builder(config, module: str, out: pathlib.Path) -> None:
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", module, str(out)],
        check=True,
        cwd=pathlib.Path(config["config_file_path"]).parent,
        env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")},
        stdout=subprocess.DEVNULL,
    )
    print(f"INFO    -  {module}: {time.perf_counter() - start:.1f} s", flush=True)


_generated_in_this_process = False


def on_pre_build(config, **kwargs) -> None:
    global _generated_in_this_process
    if _generated_in_this_process:
        return
    _generated_in_this_process = True
    out = _generated_dir(config)
    out.mkdir(parents=True, exist_ok=True)
    for module in (
        "tools.docs.gallery",
        "tools.docs.figures",
        "tools.docs.charts",
        "tools.docs.learning_curves",
    ):
        _run_builder(config, module, out)


def on_page_markdown(markdown: str, page, config, files, **kwargs) -> str:
    if _MARKER not in markdown:
        return markdown
    tables = (_generated_dir(config) / _TABLES_FILE).read_text(encoding="utf-8")
    return markdown.replace(_MARKER, tables)
