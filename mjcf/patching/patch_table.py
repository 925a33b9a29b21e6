"""Which attributes `mjcf.patching.model_patch` may write in place on the installed MuJoCo.

A (tag, attribute) pair patches only where a proof showed, on the installed MuJoCo release,
that writing its compiled value gives the same model as a recompile
(`mjcf.patching.patch_proof`). The checked-in table `mjcf.patching.patchable_attributes`
holds the proof for one release. For any other, `PROOF_COMMAND` proves the pairs on it and
caches the result in the user's cache directory, one file per MuJoCo release (`cache_path`);
every later process reads that file, once.

Without a proof for the installed release nothing patches: every change of an MJCF
attribute recompiles the model, which makes resets several times slower. That is never
silent: the first look warns, once per process, naming the command that proves the table.
A cache file that cannot be read, or that holds a proof for another MuJoCo or another
version of this project, is ignored with a warning that names it.
"""

from __future__ import annotations

import functools
import importlib.metadata
import json
import os
import warnings
from pathlib import Path
from typing import NamedTuple

import mujoco

from mjcf.patching import patchable_attributes

__all__ = ["PROOF_COMMAND", "ProvenTable", "cache_path", "current", "write_cache"]

#: The command that proves the table on the installed MuJoCo and caches it:
#: `mjcf.patching.patch_proof` on the manipulation suite's models (shipped in this
#: distribution) and its own scenes.
PROOF_COMMAND = "python -m manipulation.patch_proof"

# The distribution whose version a cached proof was made by; its code decides how a pair
# patches, so another version's proof does not count.
_DISTRIBUTION = "mujoco-composer"
# Bumped when the cache file's layout changes.
_FORMAT = 1

Pair = tuple[str, str]


class ProvenTable(NamedTuple):
    """The proof that applies to the installed MuJoCo."""

    #: The MuJoCo release the pairs were proven on.
    mujoco_version: str
    #: (tag, attribute) -> whether `mj_setConst` must run after the write.
    proven: dict[Pair, bool]
    #: (tag, attribute) -> why it recompiles.
    refused: dict[Pair, str]
    #: Where the proof comes from: the checked-in module or the cache file's path.
    source: str


def cache_path(mujoco_version: str | None = None) -> Path:
    """The cache file of the proof for `mujoco_version` (default: the installed release).

    Returns:
      `$XDG_CACHE_HOME/mujoco-composer/patch_proof/mujoco-<version>.json`, with
      `~/.cache` where `XDG_CACHE_HOME` is unset or empty.
    """
    version = mujoco.__version__ if mujoco_version is None else mujoco_version
    environ = os.environ
    return _cache_path(version, environ.get("XDG_CACHE_HOME"), environ.get("HOME"))


@functools.cache
def _cache_path(version: str, xdg_cache_home: str | None, home: str | None) -> Path:
    # Keyed by the variables the path is made of: building it costs more than a patched
    # reset's own work, and `current` runs at every reset that patches.
    del home  # part of the key only: `Path.home()` reads it
    root = xdg_cache_home or str(Path.home() / ".cache")
    return Path(root) / _DISTRIBUTION / "patch_proof" / f"mujoco-{version}.json"


def current() -> ProvenTable | None:
    """The proof for the installed MuJoCo: the checked-in table on the release it was
    proven on, else the cached proof for the installed release.

    Returns:
      The `ProvenTable`, or None when no proof applies (then nothing patches; the first
      call of the process with that outcome warns, naming `PROOF_COMMAND`).
    """
    installed, table_version = mujoco.__version__, patchable_attributes.MUJOCO_VERSION
    if installed == table_version:
        return _checked_in_table(table_version)
    return _lookup(installed, table_version, cache_path())


def write_cache(proven: dict[Pair, bool], refused: dict[Pair, str]) -> Path:
    """Saves a proof made on the installed MuJoCo where `current` finds it.

    Args:
      proven: (tag, attribute) -> whether `mj_setConst` must run after the write.
      refused: (tag, attribute) -> why it recompiles.

    Returns:
      The path written (`cache_path()`).
    """
    path = cache_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    record = {
        "format": _FORMAT,
        "mujoco": mujoco.__version__,
        "project": _project_version(),
        "proven": [[tag, name, set_const] for (tag, name), set_const in sorted(proven.items())],
        "refused": [[tag, name, why] for (tag, name), why in sorted(refused.items())],
    }
    # Written whole, then renamed: a process reading it meanwhile never sees half a file.
    partial = path.with_name(f".{path.name}.{os.getpid()}")
    partial.write_text(json.dumps(record, indent=1), encoding="utf-8")
    partial.replace(path)
    return path


@functools.cache
def _checked_in_table(table_version: str) -> ProvenTable:
    return ProvenTable(
        table_version,
        patchable_attributes.PROVEN,
        patchable_attributes.REFUSED,
        "mjcf/patching/patchable_attributes.py",
    )


@functools.cache
def _lookup(installed: str, table_version: str, path: Path) -> ProvenTable | None:
    if not path.exists():
        _warn(
            f"mjcf: the MJCF attributes a reset may write into the compiled model are "
            f"proven on mujoco {table_version}, not on the installed {installed}, and no "
            f"proof for it is cached at {path}"
        )
        return None
    try:
        return _read(path, installed)
    except (OSError, ValueError, TypeError, KeyError) as error:
        _warn(f"mjcf: ignoring the cached patch proof {path}: {error}")
        return None


def _read(path: Path, installed: str) -> ProvenTable:
    """The proof in the cache file at `path`; raises ValueError (or OSError, TypeError,
    KeyError for a malformed file) when it does not apply to `installed`."""
    record = json.loads(path.read_text(encoding="utf-8"))
    if not isinstance(record, dict) or record.get("format") != _FORMAT:
        raise ValueError(f"expected a proof of format {_FORMAT}, got {str(record)[:80]!r}")
    if record["mujoco"] != installed:
        raise ValueError(
            f"it was proven on mujoco {record['mujoco']}, the installed one is {installed}"
        )
    if record["project"] != _project_version():
        raise ValueError(
            f"it was proven by {_DISTRIBUTION} {record['project']}, this is {_project_version()}"
        )
    proven = {(str(tag), str(name)): bool(set_const) for tag, name, set_const in record["proven"]}
    refused = {(str(tag), str(name)): str(why) for tag, name, why in record["refused"]}
    return ProvenTable(installed, proven, refused, str(path))


def _warn(problem: str) -> None:
    warnings.warn(
        f"{problem}. Every MJCF attribute change recompiles the model (resets run several "
        f"times slower). Prove the table on this release once with `{PROOF_COMMAND}`; "
        "later processes use its cached result.",
        RuntimeWarning,
        stacklevel=4,
    )


def _project_version() -> str:
    try:
        return importlib.metadata.version(_DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        return "unknown"
