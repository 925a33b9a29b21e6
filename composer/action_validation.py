"""Checks the agent's actions against the environment's action spec before they are applied.

`action_validator(spec)` returns the check for a task's action spec: an `ActionValidator`
for a single array spec, or a `NestedActionValidator` for a list, tuple or dict of specs
(multi-agent tasks give one spec per agent).
"""

import math
from collections.abc import Mapping, Sequence

import numpy as np
from dm_env import specs


class ActionValidator:
    """Converts an action to an array of the spec's dtype and rejects malformed ones.

    Checks what can be checked cheaply on every step: that the action converts to the
    spec's dtype, has the spec's shape, and (for float specs) holds no NaN or infinity.
    Bounds are not enforced: MuJoCo clamps controls to their ctrlrange.
    """

    __slots__ = ("_spec", "_path", "_dtype", "_shape", "_check_finite", "_sum_floats")

    def __init__(self, spec: specs.Array, path: str = "action"):
        self._spec = spec
        self._path = path
        self._dtype = np.dtype(spec.dtype)
        self._shape = tuple(spec.shape)
        self._check_finite = np.issubdtype(self._dtype, np.inexact)
        # A vector of real floats is summed as Python floats: less work than a NumPy call.
        self._sum_floats = self._dtype.kind == "f" and len(self._shape) == 1

    def __call__(self, action) -> np.ndarray:
        """Returns `action` as an array of the spec's dtype.

        Raises:
          ValueError: naming the expected shape, dtype, bounds and actuators, if the
            action cannot be cast, has another shape, or holds NaN or infinity.
        """
        if type(action) is np.ndarray and action.dtype == self._dtype:
            array = action
        else:
            try:
                array = np.asarray(action, dtype=self._dtype)
            except (TypeError, ValueError) as error:
                raise ValueError(self._message(f"a value that cannot be cast: {error}")) from None
        if array.shape != self._shape:
            raise ValueError(self._message(f"shape {array.shape}"))
        # A finite sum proves every value finite, and costs a fraction of isfinite().all();
        # only a sum that overflowed needs the exact check.
        if self._check_finite:
            if self._sum_floats:
                total = sum(array.tolist())
            else:
                total = np.vdot(array, array).real
            if not math.isfinite(total) and not np.isfinite(array).all():
                raise ValueError(self._message(f"non-finite values {array}"))
        return array

    def _message(self, got: str) -> str:
        spec = self._spec
        bounds = ""
        if isinstance(spec, specs.BoundedArray):
            bounds = f", bounds [{spec.minimum}, {spec.maximum}]"
        names = spec.name.replace("\t", ", ") if spec.name else "unnamed"
        return (
            f"{self._path}: expected shape {self._shape}, dtype {self._dtype}{bounds} "
            f"(actuators: {names}); got {got}"
        )


class NestedActionValidator:
    """Checks a list, tuple or dict of actions against a spec of the same structure.

    Returns the actions in the spec's structure, each converted by its own
    `ActionValidator` (so each is checked for shape, dtype and finiteness).
    """

    __slots__ = ("_path", "_children")

    def __init__(self, spec: Mapping | Sequence, path: str = "action"):
        self._path = path
        if isinstance(spec, Mapping):
            self._children = {
                key: action_validator(child, f"{path}[{key!r}]") for key, child in spec.items()
            }
        else:
            self._children = [
                action_validator(child, f"{path}[{index}]") for index, child in enumerate(spec)
            ]

    def __call__(self, action):
        """Returns `action` with every leaf converted by its spec's validator.

        Raises:
          ValueError: if the structure differs from the spec's (other keys or length), or
            a leaf fails its check; the message names the leaf (`action[1]`, `action['a']`).
        """
        children = self._children
        if isinstance(children, dict):
            if not isinstance(action, Mapping) or action.keys() != children.keys():
                got = sorted(action) if isinstance(action, Mapping) else type(action).__name__
                raise ValueError(
                    f"{self._path}: expected a dict with keys {sorted(children)}, got {got}"
                )
            return {key: check(action[key]) for key, check in children.items()}
        if isinstance(action, (str, bytes, Mapping)) or not hasattr(action, "__len__"):
            raise ValueError(
                f"{self._path}: expected a sequence of {len(children)} actions, "
                f"got {type(action).__name__}"
            )
        if len(action) != len(children):
            raise ValueError(
                f"{self._path}: expected a sequence of {len(children)} actions, got {len(action)}"
            )
        return [check(item) for check, item in zip(children, action)]


def action_validator(spec, path: str = "action") -> ActionValidator | NestedActionValidator:
    """Returns the check for actions of `spec`: one array spec, or a list/tuple/dict of them.

    Raises:
      TypeError: if `spec` (or a leaf of it) is neither an array spec nor a container.
    """
    if isinstance(spec, specs.Array):
        return ActionValidator(spec, path)
    if isinstance(spec, (Mapping, Sequence)) and not isinstance(spec, (str, bytes)):
        return NestedActionValidator(spec, path)
    raise TypeError(
        f"{path} spec: expected a dm_env.specs.Array or a list, tuple or dict of them, got {spec!r}"
    )
