"""Registers the manipulation tasks with Gymnasium once both are imported, in either order.

`import manipulation` must not import gymnasium (an optional extra), yet `gymnasium.make`
should find the tasks whenever both are in use. So importing manipulation either
registers at once, when gymnasium is already imported, or installs a one-shot import
hook (a `sys.meta_path` finder) that registers right after gymnasium's own import
finishes. Registration itself is `manipulation.gym_registration`.
"""

import importlib
import importlib.abc
import importlib.util
import sys

_REGISTRATION = "manipulation.gym_registration"


class _RegisteringLoader(importlib.abc.Loader):
    """Runs gymnasium's own loader, then registers, then steps out of the way."""

    def __init__(self, loader: importlib.abc.Loader):
        self._loader = loader

    def create_module(self, spec):
        return self._loader.create_module(spec)

    def exec_module(self, module) -> None:
        module.__spec__.loader = module.__loader__ = self._loader
        self._loader.exec_module(module)
        importlib.import_module(_REGISTRATION)


class _GymnasiumImportHook(importlib.abc.MetaPathFinder):
    """Finds 'gymnasium' like the other finders do, with a loader that also registers."""

    def find_spec(self, fullname, path, target=None):
        if fullname != "gymnasium":
            return None
        remove_hook()
        spec = importlib.util.find_spec(fullname)
        if spec is None or spec.loader is None:
            return spec
        spec.loader = _RegisteringLoader(spec.loader)
        return spec


def remove_hook() -> None:
    """Removes the import hook, if installed."""
    sys.meta_path[:] = [f for f in sys.meta_path if not isinstance(f, _GymnasiumImportHook)]


def register_when_gymnasium_is_imported() -> None:
    """Registers now if gymnasium is imported, else when it is."""
    if "gymnasium" in sys.modules:
        importlib.import_module(_REGISTRATION)
    elif not any(isinstance(f, _GymnasiumImportHook) for f in sys.meta_path):
        sys.meta_path.insert(0, _GymnasiumImportHook())
