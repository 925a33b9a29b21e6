"""Bad bytes and files give a documented Python exception quickly: no crash, no hang.

The cases (tests/mjcf/bad_input_cases.py) run in a subprocess with a time limit, so that
a segmentation fault or an endless loop fails this test rather than the test run.
"""

import json
import os
import subprocess
import sys

import pytest
from bad_input_cases import DOCUMENTED

import mjcf

_SCRIPT = os.path.join(os.path.dirname(__file__), "bad_input_cases.py")
# The subprocess imports the same mjcf as this process, installed or not.
_ENV = {**os.environ, "PYTHONPATH": os.path.dirname(os.path.dirname(mjcf.__file__))}
_SECONDS_PER_CASE = 5.0
#: Cases that are valid MJCF (at MuJoCo's depth limit, many elements, a UTF-16 file).
_VALID = {"nested 496 bodies", "100k sibling sites", "UTF-16 document"}
_FILE_ERRORS = {
    "missing include": "FileNotFoundError",
    "include of a folder": "FileNotFoundError",
    "missing mesh file": "FileNotFoundError",
    "mesh file is a folder": "FileNotFoundError",
    "model file missing": "FileNotFoundError",
    "model file is a folder": "IsADirectoryError",
}


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    directory = tmp_path_factory.mktemp("bad_input")
    done = subprocess.run(
        [sys.executable, _SCRIPT, str(directory)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
        env=_ENV,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    lines = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    return {line["case"]: line for line in lines}


def test_every_case_ran_to_completion(reports):
    assert len(reports) > 40
    assert _VALID <= set(reports)


def test_bad_input_raises_a_documented_exception_type(reports):
    wrong = {
        case: line["raised"]
        for case, line in reports.items()
        if case not in _VALID and line["raised"] not in DOCUMENTED
    }
    assert wrong == {}


def test_unreadable_files_raise_os_errors_naming_the_problem(reports):
    assert {case: reports[case]["raised"] for case in _FILE_ERRORS} == _FILE_ERRORS


def test_valid_extremes_compile(reports):
    assert {case: reports[case]["raised"] for case in _VALID} == dict.fromkeys(_VALID)


def test_each_case_takes_bounded_time(reports):
    slow = {
        c: line["seconds"] for c, line in reports.items() if line["seconds"] > _SECONDS_PER_CASE
    }
    assert slow == {}
