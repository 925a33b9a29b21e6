"""Serve `dm_control.composer`, `dm_control.mjcf`, `dm_control.mujoco`,
`dm_control.viewer` and `dm_control.utils.inverse_kinematics` from this project's packages.

`install()` puts an import hook in front of `sys.meta_path`: afterwards
`import dm_control.composer` (and every `dm_control.composer.*` / `dm_control.mjcf.*` /
`dm_control.mujoco.*` module) returns this project's `composer` / `mjcf` /
`mujoco_physics` module of the same path, and `dm_control.utils.inverse_kinematics` is
`composer.utils.inverse_kinematics` (the same results bit for bit, in less time). The
rest of an installed dm_control (`dm_control.suite`, `dm_control.rl`,
`dm_control.locomotion`, `dm_control.entities`, `dm_control.manipulation`, the other
`dm_control.utils` modules, ...) stays the real one and, since it imports those packages
through the same names, runs on this project.
`dm_control.rl.control.PhysicsError` becomes this project's `PhysicsError`, so that
dm_control's code catches the errors our `Physics` raises. `dm_control.viewer` is the
package `composer.viewer`, whose `launch` takes dm_control's arguments; of dm_control's
viewer submodules only `gui`, `renderer` and `viewer` are served (the parts that code
such as MoMa's rendering observer uses); importing another (`dm_control.viewer.application`,
...) raises `ModuleNotFoundError`. Without an installed dm_control, a bare
`dm_control` package is provided so that `from dm_control import composer, mjcf` works.

Run a script written for dm_control without editing it:

```bash
python -m composer.dm_control_compat SCRIPT [ARGS...]
```

Modules imported under the `dm_control` names before `install()` keep what they hold;
call it before anything imports dm_control.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import os
import runpy
import sys
import types

#: dm_control package names served from this project, mapped to the package serving them.
REDIRECTED_PACKAGES: dict[str, str] = {
    "dm_control.composer": "composer",
    "dm_control.mjcf": "mjcf",
    "dm_control.mujoco": "mujoco_physics",
    "dm_control.viewer": "composer.viewer",
    "dm_control.utils.inverse_kinematics": "composer.utils.inverse_kinematics",
}

#: Attributes of real dm_control modules replaced, once such a module is loaded, by this
#: project's object of the same meaning: module -> {attribute: "module:attribute"}.
SHARED_ATTRIBUTES: dict[str, dict[str, str]] = {
    "dm_control.rl.control": {"PhysicsError": "mujoco_physics.engine:PhysicsError"},
}


def _target_name(fullname: str) -> str | None:
    """Returns this project's module name serving `fullname`, or None if not redirected."""
    for prefix, target in REDIRECTED_PACKAGES.items():
        if fullname == prefix or fullname.startswith(prefix + "."):
            return target + fullname[len(prefix) :]
    return None


class _AliasLoader(importlib.abc.Loader):
    """Loads a redirected name as the already imported module of this project."""

    def __init__(self, target: str):
        self._target = target
        self._target_spec = None

    def create_module(self, spec):
        module = importlib.import_module(self._target)
        self._target_spec = module.__spec__
        return module

    def exec_module(self, module):
        # The import system stamps the alias spec onto the module; give it its own back so
        # that reloads and relative imports keep working under the project's name.
        module.__spec__ = self._target_spec


class _SharingLoader(importlib.abc.Loader):
    """Runs a real dm_control module, then points its `SHARED_ATTRIBUTES` at ours."""

    def __init__(self, loader: importlib.abc.Loader, shared: dict[str, str]):
        self._loader = loader
        self._shared = shared

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module):
        self._loader.exec_module(module)
        for attribute, source in self._shared.items():
            module_name, _, name = source.partition(":")
            setattr(module, attribute, getattr(importlib.import_module(module_name), name))


class _BareDmControlLoader(importlib.abc.Loader):
    """Creates an empty `dm_control` package when no real one is installed."""

    def create_module(self, spec):
        return None

    def exec_module(self, module):
        module.__doc__ = (
            "Stand-in dm_control package: composer, mjcf, mujoco and viewer come from this project."
        )


class DmControlRedirect(importlib.abc.MetaPathFinder):
    """Finder that serves the names in `REDIRECTED_PACKAGES` from this project."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname == "dm_control":
            return self._dm_control_spec()
        if fullname in SHARED_ATTRIBUTES:
            return self._sharing_spec(fullname, path)
        target_name = _target_name(fullname)
        if target_name is None:
            return None
        try:
            target_spec = importlib.util.find_spec(target_name)
        except ModuleNotFoundError:
            # A parent this project does not have (a dm_control module registered by hand
            # under a served package): let the other finders look.
            return None
        if target_spec is None:
            return None
        return importlib.machinery.ModuleSpec(
            fullname,
            _AliasLoader(target_name),
            is_package=target_spec.submodule_search_locations is not None,
        )

    def _sharing_spec(self, fullname, path):
        spec = self._spec_from_other_finders(fullname, path)
        if spec is not None and spec.loader is not None:
            spec.loader = _SharingLoader(spec.loader, SHARED_ATTRIBUTES[fullname])
        return spec

    def _spec_from_other_finders(self, fullname, path):
        for finder in sys.meta_path:
            if finder is self or not hasattr(finder, "find_spec"):
                continue
            spec = finder.find_spec(fullname, path)
            if spec is not None:
                return spec
        return None

    def _dm_control_spec(self):
        spec = self._spec_from_other_finders("dm_control", None)
        if spec is not None:
            return spec
        return importlib.machinery.ModuleSpec("dm_control", _BareDmControlLoader(), is_package=True)


def installed() -> bool:
    """Returns whether the redirect is active in this interpreter."""
    return any(isinstance(finder, DmControlRedirect) for finder in sys.meta_path)


def install() -> None:
    """Serves `REDIRECTED_PACKAGES` from this project from now on.

    Idempotent. Raises `RuntimeError` naming the modules when dm_control's own
    `composer`, `mjcf`, `mujoco` or `viewer` is already imported, since objects made
    from those would not mix with this project's.
    """
    if installed():
        return
    already = sorted(name for name in sys.modules if _target_name(name) is not None)
    real = [name for name in already if not _is_alias(name)]
    if real:
        raise RuntimeError(
            "dm_control_compat.install(): dm_control's own modules are already imported "
            f"({', '.join(real[:5])}); install the redirect before importing dm_control"
        )
    sys.meta_path.insert(0, DmControlRedirect())


def uninstall() -> None:
    """Removes the redirect and forgets the aliases of `REDIRECTED_PACKAGES`."""
    sys.meta_path[:] = [f for f in sys.meta_path if not isinstance(f, DmControlRedirect)]
    for name in [name for name in sys.modules if _target_name(name) is not None]:
        del sys.modules[name]


def real_package_dir(package: str) -> str | None:
    """The folder of dm_control's own `package` ('composer', ...) while the redirect serves
    it from this project and dm_control is installed; None otherwise.

    dm_control code names some files relative to its own folders (its arenas give texture
    paths relative to `dm_control/composer`, where its arena model lives); this project's
    classes serving those names resolve such paths there.
    """
    if not installed():
        return None
    spec = DmControlRedirect()._dm_control_spec()
    locations = spec.submodule_search_locations or []
    folder = os.path.join(locations[0], package) if locations else None
    return folder if folder and os.path.isdir(folder) else None


def _is_alias(name: str) -> bool:
    module = sys.modules[name]
    return isinstance(module, types.ModuleType) and module.__name__ == _target_name(name)


def main(argv: list[str] | None = None) -> int:
    """Runs `SCRIPT [ARGS...]` (or `-m MODULE [ARGS...]`) with the redirect installed."""
    argv = list(sys.argv[1:] if argv is None else argv)
    usage = "usage: python -m composer.dm_control_compat (SCRIPT | -m MODULE) [ARGS...]"
    if not argv or argv[0] in ("-h", "--help"):
        print(usage, file=sys.stderr)
        return 0 if argv else 2
    install()
    if argv[0] == "-m":
        if len(argv) < 2:
            print(usage, file=sys.stderr)
            return 2
        sys.argv = argv[1:]
        runpy.run_module(argv[1], run_name="__main__", alter_sys=True)
    else:
        sys.argv = argv
        sys.path[0] = os.path.dirname(os.path.abspath(argv[0]))
        runpy.run_path(argv[0], run_name="__main__")
    return 0


if __name__ == "__main__":
    # Run the copy imported under the package name, so the installed finder is the one that
    # `installed()` and `install()` of `composer.dm_control_compat` see.
    from composer.dm_control_compat import main as _main

    sys.exit(_main())
