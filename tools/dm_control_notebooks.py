"""Runs dm_control's tutorial notebooks cell by cell; prints each cell's result.

Usage: `python -m tools.dm_control_notebooks NOTEBOOK.ipynb [...] [--python PYTHON]
[--redirect] [--workdir DIR] [--timeout-per-cell S]`, or with `--compare REFERENCE_PYTHON
PROJECT_PYTHON` in place of `--python`/`--redirect`.

The notebooks are dm_control's and are never kept in this repository; take them from a
dm_control checkout (`tutorial.ipynb` and `dm_control/mujoco/tutorial.ipynb`, 85 code cells
at dm_control 1.0.50) into a scratch folder. The code cells of each notebook run in order in
one persistent Python process of `--python` (a "kernel": cells share their globals, as in a
notebook), in `--workdir` (outside the repository), with `MUJOCO_GL=egl` and `MPLBACKEND=Agg`.
With `--redirect` the kernel first runs `dm_control_compat.install()`, so that
`dm_control.composer` / `mjcf` / `mujoco` are served by this checkout (put first on its
`PYTHONPATH`); the rest of the dm_control installed in that Python stays its own.

Colab-only code is handled by these rules, never by editing a cell by hand:

- a cell whose first line starts with `%%` (a cell magic) is not run ("skipped");
- a line that starts, after its indentation, with `!` (shell) or `%` (line magic), or that
  imports `google.colab`, becomes `pass` at the same indentation, outside multi-line strings;
- nothing else in a cell is changed. The kernel provides what IPython would: `display` (from
  `IPython.display` when installed, else a stub that prints the repr); a cell's last
  expression is evaluated and displayed (its `_repr_png_` / `_repr_html_` and `repr` are
  computed, unless the cell ends with `;`); the open matplotlib figures are drawn to PNG
  and closed after every cell, as the inline backend does; PIL's `Image.show`, which would
  start a viewer program, only encodes the PNG. Packages the notebooks import that are on
  PyPI (IPython, matplotlib, pillow) are to be installed in the venv, not stubbed; with
  `imageio-ffmpeg` installed and no `ffmpeg` on PATH, matplotlib's animation writer uses its
  binary.
- a cell runs for at most `--timeout-per-cell` seconds, or the `timeout` of its Colab
  `#@test {"timeout": N}` annotation when larger. A failing cell does not stop the later
  ones; a kernel that dies or hangs in native code is restarted for the next cell (whose
  globals are then gone, as after a notebook's kernel restart).

Prints a table: notebook, cell number, first code line, result (`ok` with seconds, or the
exception type and the last line of its message); with `--compare` the results of the
reference (real dm_control, no redirect) and of the project (through the redirect) side by
side, then "dm_control K1/N, project K2/N; cells that pass on dm_control and fail here: ...".
Each side's results, with the cells' tracebacks and output tails, are written as JSON to
`results-<side>.json` in its working folder (`--workdir`, or its `dm_control/` and `project/`
with `--compare`), each notebook's kernel stderr to `kernel-<side>-<notebook>.log`.
Exits 1 when a cell fails (with `--compare`: passes on dm_control and fails here).
"""

from __future__ import annotations

import argparse
import io
import json
import os
import queue
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
import tokenize
from pathlib import Path
from typing import NamedTuple

from tools import ROOT

DEFAULT_WORKDIR = Path(tempfile.gettempdir()) / "dm_control_notebooks"
DEFAULT_TIMEOUT_S = 600.0
#: Seconds a kernel may stay silent past a cell's timeout before it is killed: `signal.alarm`
#: cannot interrupt native code (a renderer or ffmpeg that hangs).
HARD_KILL_GRACE_S = 60.0
#: Seconds a kernel may take to start (the redirect and the prelude's imports).
STARTUP_S = 120.0

_MAGIC_LINE = re.compile(r"^\s*[!%]")
_COLAB_IMPORT = re.compile(r"^\s*(from\s+google\.colab\b|import\s+google\.colab\b)")
_TEST_ANNOTATION = re.compile(r"^\s*#@test\s+(\{.*\})\s*$", re.MULTILINE)

#: The kernel: reads the cells, runs each in one shared namespace, and writes one JSON line
#: per cell on the stdout it was started with (cells' own prints are captured; native
#: prints go to stderr). argv: cells.json, index of the first cell to run, redirect (0/1).
_KERNEL = r'''
import ast, builtins, contextlib, io, json, linecache, os, shutil, signal, sys, time
import traceback

protocol = os.fdopen(os.dup(1), "w", buffering=1)
os.dup2(2, 1)
cells = json.load(open(sys.argv[1], encoding="utf-8"))
start, redirect = int(sys.argv[2]), sys.argv[3] == "1"
if redirect:
    from composer import dm_control_compat
    dm_control_compat.install()

try:
    from IPython.display import display
except ImportError:
    def display(*objects, **kwargs):
        for obj in objects:
            print(repr(obj))
try:
    import PIL.Image
    PIL.Image.Image.show = lambda self, *args, **kwargs: self._repr_png_()
except ImportError:
    pass
try:
    import imageio_ffmpeg, matplotlib
    if shutil.which(matplotlib.rcParams["animation.ffmpeg_path"]) is None:
        matplotlib.rcParams["animation.ffmpeg_path"] = imageio_ffmpeg.get_ffmpeg_exe()
except ImportError:
    pass

namespace = {"__name__": "__main__", "__builtins__": builtins, "display": display}


class CellTimeout(BaseException):
    """Raised by the alarm; a BaseException so that `except Exception` in a cell lets it by."""


def on_alarm(signum, frame):
    raise CellTimeout("the cell ran past its timeout")


signal.signal(signal.SIGALRM, on_alarm)


def show(value):
    # What a notebook computes to display an Out[] value.
    if not isinstance(value, type):
        for method in ("_repr_png_", "_repr_html_"):
            render = getattr(value, method, None)
            if callable(render):
                render()
    print(repr(value))


def draw_figures():
    # The inline backend draws the cell's figures to PNG and closes them.
    if "matplotlib.pyplot" in sys.modules:
        plt = sys.modules["matplotlib.pyplot"]
        try:
            for number in plt.get_fignums():
                plt.figure(number).savefig(io.BytesIO(), format="png")
        finally:
            plt.close("all")


def run(number, source):
    filename = f"<cell {number}>"
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    tree = ast.parse(source, filename)
    last = None
    if tree.body and isinstance(tree.body[-1], ast.Expr) and not source.rstrip().endswith(";"):
        last = ast.Expression(tree.body.pop().value)
    exec(compile(tree, filename, "exec"), namespace)
    if last is not None:
        value = eval(compile(last, filename, "eval"), namespace)
        if value is not None:
            show(value)


for cell in cells[start:]:
    output = io.StringIO()
    error, trace = "", ""
    began = time.perf_counter()
    signal.alarm(max(1, int(cell["timeout"])))
    try:
        with contextlib.redirect_stdout(output), contextlib.redirect_stderr(output):
            try:
                run(cell["number"], cell["source"])
            finally:
                draw_figures()
    except BaseException as e:
        message = str(e).strip().splitlines()
        error = type(e).__name__ + (": " + message[-1] if message else "")
        trace = traceback.format_exc()
    finally:
        signal.alarm(0)
    result = {
        "number": cell["number"],
        "status": "timeout" if error.startswith("CellTimeout") else "error" if error else "ok",
        "error": error,
        "seconds": time.perf_counter() - began,
        "traceback": trace[-4000:],
        "output": output.getvalue()[-2000:],
    }
    protocol.write(json.dumps(result) + "\n")
'''


class Cell(NamedTuple):
    """One code cell of a notebook, after the Colab rules."""

    number: int  # 1-based, among the notebook's code cells
    source: str
    first_line: str  # the first line that is not blank or a comment
    timeout: float
    skip: str  # why the cell is not run; empty when it is


class CellResult(NamedTuple):
    """What running one cell gave."""

    number: int
    first_line: str
    status: str  # "ok", "error", "timeout", "crashed" or "skipped"
    error: str  # "Type: last line of the message", or why the cell was not run
    seconds: float
    traceback: str = ""
    output: str = ""

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def describe(self, width: int) -> str:
        """`ok (1.2 s)` or the failure, shortened to `width` characters."""
        if self.ok:
            return f"ok ({self.seconds:.1f} s)"
        text = f"{self.status.upper()} {self.error}".strip()
        return text if len(text) <= width else text[: width - 3] + "..."


def _without_magics(source: str) -> str:
    """Replaces shell, magic and `google.colab` import lines by `pass`, except inside
    multi-line strings (found by tokenizing the result)."""
    lines = source.splitlines(keepends=True)
    replaced = {
        index
        for index, line in enumerate(lines)
        if _MAGIC_LINE.match(line) or _COLAB_IMPORT.match(line)
    }
    if not replaced:
        return source
    edited = list(lines)
    for index in replaced:
        indent = lines[index][: len(lines[index]) - len(lines[index].lstrip())]
        edited[index] = indent + "pass\n"
    try:
        tokens = list(tokenize.generate_tokens(io.StringIO("".join(edited)).readline))
    except (tokenize.TokenError, SyntaxError):
        return "".join(edited)
    for token in tokens:
        if token.type == tokenize.STRING and token.end[0] > token.start[0]:
            # Rows are 1-based: a line inside the string keeps its text.
            for row in range(token.start[0], token.end[0] + 1):
                if row - 1 in replaced:
                    edited[row - 1] = lines[row - 1]
    return "".join(edited)


def _first_code_line(source: str) -> str:
    for line in source.splitlines():
        if line.strip() and not line.lstrip().startswith("#"):
            return line.strip()
    return ""


def read_cells(notebook: Path, default_timeout: float) -> list[Cell]:
    """Returns the notebook's code cells in order, with the Colab rules applied."""
    document = json.loads(notebook.read_text(encoding="utf-8"))
    cells = []
    code = [cell for cell in document["cells"] if cell.get("cell_type") == "code"]
    for number, cell in enumerate(code, start=1):
        raw = cell["source"]
        source = "".join(raw) if isinstance(raw, list) else raw
        timeout = default_timeout
        annotation = _TEST_ANNOTATION.search(source)
        if annotation:
            timeout = max(timeout, float(json.loads(annotation.group(1)).get("timeout", 0)))
        skip = "cell magic" if source.lstrip().startswith("%%") else ""
        cells.append(Cell(number, _without_magics(source), _first_code_line(source), timeout, skip))
    return cells


def _kernel_env(redirect: bool) -> dict[str, str]:
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"), MPLBACKEND="Agg")
    if redirect:
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    return env


def _lines(stream) -> queue.Queue:
    """A queue that a thread fills with the lines of `stream`, then "" at its end (so that
    a wait for the next line can time out)."""
    lines: queue.Queue = queue.Queue()

    def pump() -> None:
        for line in stream:
            lines.put(line)
        lines.put("")

    threading.Thread(target=pump, daemon=True).start()
    return lines


def _next_line(lines: queue.Queue, seconds: float) -> str | None:
    """The kernel's next line; "" when it ended, None when it stayed silent for `seconds`."""
    try:
        return lines.get(timeout=max(0.0, seconds))
    except queue.Empty:
        return None


def run_notebook(
    python: str, cells: list[Cell], *, redirect: bool, workdir: Path, log_name: str
) -> list[CellResult]:
    """Runs `cells` in kernels of `python` in `workdir`; returns one result per cell."""
    workdir.mkdir(parents=True, exist_ok=True)
    runnable = [cell for cell in cells if not cell.skip]
    cells_file = workdir / f"cells-{log_name}.json"
    cells_file.write_text(
        json.dumps(
            [{"number": c.number, "source": c.source, "timeout": c.timeout} for c in runnable]
        )
    )
    results: dict[int, CellResult] = {
        cell.number: CellResult(cell.number, cell.first_line, "skipped", cell.skip, 0.0)
        for cell in cells
        if cell.skip
    }
    next_index = 0
    with open(workdir / f"kernel-{log_name}.log", "a", encoding="utf-8") as log:
        while next_index < len(runnable):
            log.write(f"--- kernel started at cell {runnable[next_index].number}\n")
            log.flush()
            kernel = subprocess.Popen(
                [python, "-c", _KERNEL, str(cells_file), str(next_index), str(int(redirect))],
                cwd=workdir,
                env=_kernel_env(redirect),
                stdin=subprocess.DEVNULL,
                stdout=subprocess.PIPE,
                stderr=log,
                text=True,
                start_new_session=True,
            )
            lines = _lines(kernel.stdout)
            began, wait = time.perf_counter(), STARTUP_S
            while next_index < len(runnable):
                cell = runnable[next_index]
                line = _next_line(lines, wait + cell.timeout + HARD_KILL_GRACE_S)
                if line:
                    outcome = json.loads(line)
                    result = CellResult(
                        cell.number,
                        cell.first_line,
                        outcome["status"],
                        outcome["error"],
                        outcome["seconds"],
                        outcome["traceback"],
                        outcome["output"],
                    )
                else:
                    seconds = time.perf_counter() - began
                    result = _kernel_lost(kernel, cell, seconds, ended=line == "")
                results[cell.number] = result
                print(f"  cell {cell.number}: {result.describe(70)}", file=sys.stderr)
                began, wait = time.perf_counter(), 0.0
                next_index += 1
                if not line:
                    break
            try:
                kernel.wait(timeout=60)
            except subprocess.TimeoutExpired:  # hangs on its way out
                os.killpg(kernel.pid, signal.SIGKILL)
                kernel.wait()
    return [results[cell.number] for cell in cells]


def _kernel_lost(
    kernel: subprocess.Popen, cell: Cell, seconds: float, *, ended: bool
) -> CellResult:
    """Kills a silent kernel (and what it started), or names how it died."""
    if ended:
        kernel.wait()
    if kernel.poll() is None:
        os.killpg(kernel.pid, signal.SIGKILL)
        kernel.wait()
        return CellResult(
            cell.number, cell.first_line, "timeout", "killed: silent past its timeout", seconds
        )
    code = kernel.returncode
    how = f"signal {signal.Signals(-code).name}" if code < 0 else f"exit status {code}"
    return CellResult(cell.number, cell.first_line, "crashed", f"kernel died ({how})", seconds)


def run_notebooks(
    python: str,
    notebooks: dict[str, list[Cell]],
    *,
    redirect: bool,
    workdir: Path,
    side: str,
) -> dict[str, list[CellResult]]:
    """Runs every notebook in its own kernel; writes `results-<side>.json` to `workdir`."""
    results = {}
    for label, cells in notebooks.items():
        print(f"running {label} ({len(cells)} code cells) on {side} ...", file=sys.stderr)
        log_name = f"{side}-{label.replace('/', '_')}"
        results[label] = run_notebook(
            python, cells, redirect=redirect, workdir=workdir, log_name=log_name
        )
    path = workdir / f"results-{side}.json"
    path.write_text(
        json.dumps(
            {label: [r._asdict() for r in cells] for label, cells in results.items()}, indent=1
        )
    )
    return results


def _labels(paths: list[Path]) -> dict[str, Path]:
    """Names notebooks by file stem, with the parent folder where stems repeat."""
    stems = [path.stem for path in paths]
    return {
        (f"{path.parent.name}/{path.stem}" if stems.count(path.stem) > 1 else path.stem): path
        for path in paths
    }


def _shorten(text: str, width: int) -> str:
    return text if len(text) <= width else text[: width - 3] + "..."


def print_table(results: dict[str, list[CellResult]]) -> int:
    """Prints one row per cell and the totals; returns how many cells did not pass."""
    width = max(len("notebook"), *(len(label) for label in results))
    print(f"{'notebook':<{width}}  cell  {'first code line':<40}  result")
    for label, cells in results.items():
        for r in cells:
            print(
                f"{label:<{width}}  {r.number:4d}  {_shorten(r.first_line, 40):<40}  "
                f"{r.describe(70)}"
            )
    failed = sum(not r.ok for cells in results.values() for r in cells)
    total = sum(len(cells) for cells in results.values())
    print(f"passed {total - failed}/{total}")
    return failed


def print_comparison(
    reference: dict[str, list[CellResult]], project: dict[str, list[CellResult]]
) -> int:
    """Prints both sides per cell and the summary line; returns how many cells pass on
    dm_control and fail through the redirect."""
    width = max(len("notebook"), *(len(label) for label in reference))
    print(f"{'notebook':<{width}}  cell  {'first code line':<36}  {'dm_control':<34}  project")
    regressions = []
    for label, cells in reference.items():
        for ours, theirs in zip(project[label], cells):
            print(
                f"{label:<{width}}  {ours.number:4d}  {_shorten(ours.first_line, 36):<36}  "
                f"{theirs.describe(34):<34}  {ours.describe(60)}"
            )
            if theirs.ok and not ours.ok:
                regressions.append((label, ours))
    total = sum(len(cells) for cells in reference.values())
    passed_reference = sum(r.ok for cells in reference.values() for r in cells)
    passed_project = sum(r.ok for cells in project.values() for r in cells)
    names = ", ".join(f"{label}#{r.number}" for label, r in regressions) or "none"
    print(
        f"dm_control {passed_reference}/{total}, project {passed_project}/{total}; "
        f"cells that pass on dm_control and fail here: {names}"
    )
    for label, r in regressions:
        print(f"  {label}#{r.number} {r.first_line}\n      {r.status}: {r.error}")
    return len(regressions)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebooks", nargs="+", type=Path, metavar="NOTEBOOK.ipynb")
    parser.add_argument("--python", default=sys.executable, help="the kernel's interpreter")
    parser.add_argument(
        "--redirect", action="store_true", help="serve dm_control's packages from this project"
    )
    parser.add_argument(
        "--compare",
        nargs=2,
        metavar=("REFERENCE_PYTHON", "PROJECT_PYTHON"),
        help="run on real dm_control, then through the redirect, and compare",
    )
    parser.add_argument("--workdir", type=Path, default=DEFAULT_WORKDIR)
    parser.add_argument("--timeout-per-cell", type=float, default=DEFAULT_TIMEOUT_S)
    args = parser.parse_args()
    workdir = args.workdir.resolve()
    if workdir == ROOT or ROOT in workdir.parents:
        parser.error(f"--workdir must be outside the repository {ROOT}, got {workdir}")
    notebooks = {
        label: read_cells(path, args.timeout_per_cell)
        for label, path in _labels(args.notebooks).items()
    }
    if args.compare:
        reference_python, project_python = args.compare
        reference = run_notebooks(
            reference_python,
            notebooks,
            redirect=False,
            workdir=workdir / "dm_control",
            side="dm_control",
        )
        project = run_notebooks(
            project_python,
            notebooks,
            redirect=True,
            workdir=workdir / "project",
            side="project",
        )
        return int(print_comparison(reference, project) > 0)
    side = "project" if args.redirect else "dm_control"
    results = run_notebooks(
        args.python, notebooks, redirect=args.redirect, workdir=workdir, side=side
    )
    return int(print_table(results) > 0)


if __name__ == "__main__":
    sys.exit(main())
