"""Which attribute changes `mjcf.patching.model_patch` may write in place on the installed
MuJoCo, and where the proofs of them are kept.

A change patches only where a proof showed, on the installed MuJoCo release, that writing
its compiled value gives the same model as a recompile. Three sources, one `ProvenTable`:

- The checked-in table `mjcf.patching.patchable_attributes`, made by `PROOF_COMMAND` over
  the task suite's models: on the release it was proven on, every pair it proves patches
  in every context, and every pair it refuses for differing fields recompiles.
- On any other release, the same command's proof run there, cached
  (`write_cache`): pair verdicts in the same sense.
- Proofs at first use (`mjcf.patching.first_use_proof`): a change in a context that no
  pair verdict covers (a pair no model of the corpus has, or every pair on a release with
  no corpus proof) is proven on the model at hand, and its verdict is kept per
  `PatchContext` (`record`): the contexts proven, each with the models it was proven on,
  and the sets of contexts that failed together, with the fields that differed.

Everything is cached in the user's cache directory, one file per MuJoCo release
(`cache_path`), so that later processes start patched. Writes merge into the file under a
lock (`fcntl.flock`, waited for at most `LOCK_TIMEOUT` seconds) and replace it by a rename:
concurrent processes (Ray workers, producers, pytest-xdist) never read half a file and
never lose each other's proofs. A process reads the file once, and again before it proves
anything itself (another process may have). A cache file that cannot be read, or that
holds proofs for another MuJoCo or another version of this project, is ignored with a
warning that names it, and replaced at the next write.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.metadata
import json
import os
import time
import warnings
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import NamedTuple

import mujoco

from mjcf.patching import patchable_attributes
from mjcf.patching.patch_context import PatchContext

try:
    import fcntl
except ImportError:  # Windows: writes are not serialised, a rename still keeps files whole
    fcntl = None

__all__ = [
    "LOCK_TIMEOUT",
    "PROOF_COMMAND",
    "ContextProof",
    "GroupRefusal",
    "ProvenTable",
    "cache_path",
    "current",
    "record",
    "refresh",
    "write_cache",
]

#: The command that proves every pair on the task suite's models (the maintainers' check
#: of the checked-in table; on another release, a warm start for the cache):
#: `mjcf.patching.patch_proof` on the manipulation suite's models and its own scenes.
PROOF_COMMAND = "python -m manipulation.patch_proof"

#: How long a write waits for another process's write to the same cache file, in seconds;
#: past it the proof is kept in this process only, with a warning.
LOCK_TIMEOUT = 10.0

# The distribution whose version a cached proof was made by; its code decides how a pair
# patches, so another version's proof does not count.
_DISTRIBUTION = "mujoco-composer"
# Bumped when the cache file's layout changes.
_FORMAT = 2
# Reasons of pair verdicts that are no verdict on the pair: left to proofs at first use.
_NOT_IN_CORPUS = "no model of the corpus has it"
_DECLINED = "declined by mjcf.patching.model_patch wherever the corpus has it"
_CHECKED_IN = "mjcf/patching/patchable_attributes.py"

Pair = tuple[str, str]


class ContextProof(NamedTuple):
    """A context proven at first use."""

    #: Whether `mj_setConst` must run after the write.
    set_const: bool
    #: The models it was proven on ('name (xml sha1 prefix)').
    models: tuple[str, ...]


class GroupRefusal(NamedTuple):
    """Contexts unproven until a change of all of them together failed its proof."""

    #: The fields that differed from a recompile.
    why: str
    #: The models it failed on.
    models: tuple[str, ...]


@dataclasses.dataclass
class ProvenTable:
    """The proofs that apply to the installed MuJoCo (see the module docstring).

    Attributes:
      mujoco_version: the installed MuJoCo release.
      proven: (tag, attribute) -> whether `mj_setConst` must run after the write, in
        every context (the checked-in table on its release, or the corpus command's cache).
      refused: (tag, attribute) -> why it recompiles (or why the corpus could not tell).
      source: where the pair verdicts come from: the checked-in module, the cache file's
        path, or 'none' (every change is proven at first use).
      contexts: proofs at first use, by context.
      refused_together: sets of contexts whose change failed its proof, with why.
    """

    mujoco_version: str
    proven: dict[Pair, bool]
    refused: dict[Pair, str]
    source: str
    contexts: dict[PatchContext, ContextProof] = dataclasses.field(default_factory=dict)
    refused_together: dict[frozenset[PatchContext], GroupRefusal] = dataclasses.field(
        default_factory=dict
    )

    def pair_verdict(self, pair: Pair) -> bool | str | None:
        """A pair verdict: whether `mj_setConst` must follow (proven), why it recompiles
        (refused), or None when no pair verdict applies (contexts are proven at first use)."""
        set_const = self.proven.get(pair)
        if set_const is not None:
            return set_const
        why = self.refused.get(pair)
        if why is None or why in (_NOT_IN_CORPUS, _DECLINED):
            return None
        return why

    def context_verdict(self, context: PatchContext) -> bool | None:
        """Whether `mj_setConst` must follow a change in `context`, proven at first use, or
        None when unproven."""
        proof = self.contexts.get(context)
        return None if proof is None else proof.set_const

    def refusal_of(self, unproven: Iterable[PatchContext]) -> GroupRefusal | None:
        """The refusal of a set of contexts that `unproven` includes, if any: a change of
        them all failed its proof, so a change with them recompiles unproven."""
        unproven = frozenset(unproven)
        for group, refusal in self.refused_together.items():
            if group <= unproven:
                return refusal
        return None


def cache_path(mujoco_version: str | None = None) -> Path:
    """The cache file of the proofs for `mujoco_version` (default: the installed release).

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


# The process's tables, by (installed release, checked-in table's release, cache file).
_TABLES: dict[tuple[str, str, Path], ProvenTable] = {}
# The cache file's (mtime_ns, size) when last read into the table of that key.
_READ_STAMPS: dict[tuple[str, str, Path], tuple[int, int] | None] = {}


def current() -> ProvenTable:
    """The proofs for the installed MuJoCo: the checked-in table on the release it was
    proven on, else the corpus command's cached proof (if any), with the cached proofs at
    first use; read from the cache file once per process (see `refresh`)."""
    key = (mujoco.__version__, patchable_attributes.MUJOCO_VERSION, cache_path())
    table = _TABLES.get(key)
    if table is None:
        table = _TABLES[key] = _empty_table(*key)
        _merge_file(key, table)
    return table


def refresh() -> ProvenTable:
    """`current()`, with what other processes have cached since it was read."""
    table = current()
    _merge_file((table.mujoco_version, patchable_attributes.MUJOCO_VERSION, cache_path()), table)
    return table


def _empty_table(installed: str, table_version: str, path: Path) -> ProvenTable:
    if installed == table_version:
        return ProvenTable(
            installed,
            patchable_attributes.PROVEN,
            patchable_attributes.REFUSED,
            _CHECKED_IN,
        )
    return ProvenTable(installed, {}, {}, "none")


def _stamp(path: Path) -> tuple[int, int] | None:
    try:
        status = path.stat()
    except OSError:
        return None
    return (status.st_mtime_ns, status.st_size)


def _merge_file(key, table: ProvenTable) -> None:
    """Merges the cache file into `table` when it changed since the last read."""
    path = key[2]
    stamp = _stamp(path)
    if stamp is None or _READ_STAMPS.get(key) == stamp:
        return
    _READ_STAMPS[key] = stamp
    try:
        cached = _read(path, table.mujoco_version)
    except (OSError, ValueError, TypeError, KeyError) as error:
        warnings.warn(
            f"mjcf: ignoring the cached patch proof {path}: {error}. Changes it would have "
            "patched are proven again on first use, and the file is replaced",
            RuntimeWarning,
            stacklevel=4,
        )
        return
    _merge(table, cached)


def _merge(table: ProvenTable, other: ProvenTable) -> None:
    """Adds `other`'s proofs to `table` (the checked-in table's pair verdicts stay)."""
    if table.source != _CHECKED_IN and other.source != "none":
        table.proven, table.refused, table.source = other.proven, other.refused, other.source
    for context, proof in other.contexts.items():
        mine = table.contexts.get(context)
        models = proof.models if mine is None else _union(mine.models, proof.models)
        table.contexts[context] = ContextProof(proof.set_const, models)
    for group, refusal in other.refused_together.items():
        mine = table.refused_together.get(group)
        models = refusal.models if mine is None else _union(mine.models, refusal.models)
        table.refused_together[group] = GroupRefusal(refusal.why, models)


def _union(first: tuple[str, ...], second: tuple[str, ...]) -> tuple[str, ...]:
    return tuple(dict.fromkeys(first + second))


def record(
    proven: Mapping[PatchContext, bool],
    refused: Mapping[frozenset[PatchContext], str],
    model: str,
) -> None:
    """Keeps proofs at first use made on `model`, in this process and in the cache file.

    Args:
      proven: context -> whether `mj_setConst` must follow.
      refused: set of contexts -> the fields that differed when changed together.
      model: the model they were proven on ('name (xml sha1 prefix)').
    """
    new = ProvenTable(mujoco.__version__, {}, {}, "none")
    new.contexts = {context: ContextProof(s, (model,)) for context, s in proven.items()}
    new.refused_together = {group: GroupRefusal(why, (model,)) for group, why in refused.items()}
    _merge(current(), new)
    _write_merged(new)


def write_cache(proven: dict[Pair, bool], refused: dict[Pair, str]) -> Path:
    """Saves the corpus command's pair verdicts made on the installed MuJoCo where `current`
    finds them, beside the proofs at first use already cached.

    Args:
      proven: (tag, attribute) -> whether `mj_setConst` must run after the write.
      refused: (tag, attribute) -> why it recompiles.

    Returns:
      The path written (`cache_path()`).
    """
    table = ProvenTable(mujoco.__version__, dict(proven), dict(refused), str(cache_path()))
    _write_merged(table)
    return cache_path()


def _write_merged(new: ProvenTable) -> None:
    """Merges `new` into the cache file under its lock, then renames the result in place."""
    path = cache_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    with _locked(path) as locked:
        if not locked:
            warnings.warn(
                f"mjcf: the cache file {path} stayed locked by another process for "
                f"{LOCK_TIMEOUT:.0f} s; the patch proofs just made are kept in this process "
                "only, and made again in the next",
                RuntimeWarning,
                stacklevel=4,
            )
            return
        try:
            merged = _read(path, new.mujoco_version)
        except (OSError, ValueError, TypeError, KeyError):
            merged = ProvenTable(new.mujoco_version, {}, {}, "none")
        _merge(merged, new)
        # Written whole, then renamed: a process reading it meanwhile never sees half a file.
        partial = path.with_name(f".{path.name}.{os.getpid()}")
        partial.write_text(json.dumps(_as_record(merged), indent=1), encoding="utf-8")
        partial.replace(path)


class _locked:
    """Holds an exclusive `flock` on `<path>.lock` for a `with` block, waiting at most
    `LOCK_TIMEOUT`; `as` gives whether it got it (always True without `fcntl`)."""

    def __init__(self, path: Path):
        self._path = path.with_name(path.name + ".lock")
        self._fd: int | None = None

    def __enter__(self) -> bool:
        if fcntl is None:
            return True
        self._fd = os.open(self._path, os.O_RDWR | os.O_CREAT, 0o644)
        deadline = time.monotonic() + LOCK_TIMEOUT
        while True:
            try:
                fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                return True
            except BlockingIOError:
                if time.monotonic() >= deadline:
                    return False
                time.sleep(0.01)

    def __exit__(self, *exc_info) -> None:
        if self._fd is not None:
            os.close(self._fd)  # releases the lock


def _context_record(context: PatchContext) -> dict:
    return {
        "tag": context.tag,
        "attribute": context.attribute,
        "where": context.where,
        "from_unset": context.from_unset,
        "variety": list(context.variety),
    }


def _context_of(record: dict) -> PatchContext:
    return PatchContext(
        str(record["tag"]),
        str(record["attribute"]),
        str(record["where"]),
        bool(record["from_unset"]),
        tuple(str(part) for part in record["variety"]),
    )


def _as_record(table: ProvenTable) -> dict:
    return {
        "format": _FORMAT,
        "mujoco": table.mujoco_version,
        "project": _project_version(),
        "proven": [
            [tag, name, set_const] for (tag, name), set_const in sorted(table.proven.items())
        ],
        "refused": [[tag, name, why] for (tag, name), why in sorted(table.refused.items())],
        "contexts": [
            dict(_context_record(context), set_const=proof.set_const, models=list(proof.models))
            for context, proof in sorted(table.contexts.items())
        ],
        "refused_together": [
            {
                "contexts": [_context_record(context) for context in sorted(group)],
                "why": refusal.why,
                "models": list(refusal.models),
            }
            for group, refusal in sorted(
                table.refused_together.items(), key=lambda item: sorted(item[0])
            )
        ],
    }


def _read(path: Path, installed: str) -> ProvenTable:
    """The proofs in the cache file at `path`; raises ValueError (or OSError, TypeError,
    KeyError for a malformed file) when they do not apply to `installed`."""
    record = json.loads(path.read_text(encoding="utf-8"))
    if not isinstance(record, dict) or "format" not in record:
        raise ValueError(f"expected proofs of format {_FORMAT}, got {str(record)[:80]!r}")
    if record["format"] != _FORMAT:
        raise ValueError(
            f"it holds proofs of format {record['format']!r} (another version of "
            f"{_DISTRIBUTION} wrote it), this one reads format {_FORMAT}"
        )
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
    table = ProvenTable(installed, proven, refused, str(path) if proven or refused else "none")
    for entry in record["contexts"]:
        models = tuple(str(model) for model in entry["models"])
        table.contexts[_context_of(entry)] = ContextProof(bool(entry["set_const"]), models)
    for entry in record["refused_together"]:
        group = frozenset(_context_of(context) for context in entry["contexts"])
        models = tuple(str(model) for model in entry["models"])
        table.refused_together[group] = GroupRefusal(str(entry["why"]), models)
    return table


@functools.cache
def _project_version() -> str:
    """This project's installed version (what a cache file must have been written by)."""
    try:
        return importlib.metadata.version(_DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        return "unknown"
