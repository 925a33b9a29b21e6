"""dm_control's Control Suite, imported from the user's dm_control through the redirect.

The suite's code and models are dm_control's own, read at run time from the installed
`dm_control` (this project copies none of them); `composer.dm_control_compat` serves the
`dm_control.mujoco` they import from this project's engine, which runs on the installed
MuJoCo (4 and later included).
"""

import difflib
import importlib.util
from types import ModuleType

import numpy as np

from composer import dm_control_compat

__all__ = ["check_task_name", "import_suite"]

#: How to get the suite when dm_control is missing.
INSTALL_HINT = (
    "pip install dm-control --no-deps scipy (the suite's code and models come from dm_control; "
    "--no-deps keeps the installed MuJoCo, and quadruped's terrain needs scipy)"
)


def import_suite() -> ModuleType:
    """Returns `dm_control.suite`, imported through this project's redirect.

    Raises:
      ImportError: when dm_control is not installed, saying what to install, or NumPy is
        older than 2.0.
      RuntimeError: when dm_control's own engine was imported before the redirect (from
        `dm_control_compat.install`, naming the modules).
    """
    try:
        found = importlib.util.find_spec("dm_control.suite") is not None
    except ModuleNotFoundError:  # no dm_control package at all
        found = False
    if not found:
        raise ImportError(
            f"the batched Control Suite runs dm_control's own suite, which is not installed: "
            f"{INSTALL_HINT}"
        )
    if not hasattr(np, "vecdot"):
        # The array code matches the suite's np.dot and np.linalg.norm row by row with it.
        raise ImportError(
            f"the batched Control Suite needs NumPy >= 2.0 (np.vecdot); found {np.__version__}"
        )
    dm_control_compat.install()
    from dm_control import suite

    return suite


def check_task_name(suite: ModuleType, domain_name: str, task_name: str) -> None:
    """Checks that `domain_name` and `task_name` name a task of `suite.ALL_TASKS`.

    Raises:
      ValueError: naming the unknown domain or task and the closest known ones.
    """
    domains = sorted({domain for domain, _ in suite.ALL_TASKS})
    if domain_name not in domains:
        raise ValueError(
            f"domain_name: {domain_name!r} is not a Control Suite domain; "
            f"{_closest(domain_name, domains)}"
        )
    tasks = sorted(task for domain, task in suite.ALL_TASKS if domain == domain_name)
    if task_name not in tasks:
        raise ValueError(
            f"task_name: domain {domain_name!r} has no task {task_name!r}; "
            f"{_closest(task_name, tasks)}"
        )


def _closest(name: str, known: list[str]) -> str:
    close = difflib.get_close_matches(name, known, n=3, cutoff=0.5)
    if close:
        return f"did you mean {', '.join(map(repr, close))}? (known: {', '.join(known)})"
    return f"known: {', '.join(known)}"
