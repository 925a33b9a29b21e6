"""`WeakPhysics`: the weak reference `Environment.physics` returns, which says why it died.

An environment owns its `mjcf.Physics`; `env.physics` must not keep it alive, or a closed or
discarded environment would hold MuJoCo's model and data. A `weakref.proxy` does that, but
once its Physics is gone every use raises "weakly-referenced object no longer exists", which
says neither why (the environment was garbage-collected, closed, or replaced its Physics at a
reset) nor what to do. `WeakPhysics` forwards every attribute like the proxy and, once the
Physics is gone, raises a ReferenceError that says both.

Hooks and observables are still handed a `weakref.proxy`: it forwards in C, at no cost per
attribute, and they run inside the environment, where the Physics is alive.
"""

from __future__ import annotations

import weakref
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import composer
    import mjcf

_ENVIRONMENT_GONE = (
    "env.physics was used after its composer.Environment was garbage-collected, which freed "
    "the Physics: keep a reference to the environment for as long as you use its physics "
    "(env = make_env() and then env.physics, not make_env().physics), or keep a copy made "
    "with env.physics.copy()"
)
_ENVIRONMENT_CLOSED = (
    "env.physics was used after env.close() freed the Physics: call env.reset() and read "
    "env.physics again"
)
_PHYSICS_REPLACED = (
    "env.physics was used after the environment replaced its Physics (at a reset that "
    "recompiled a changed model structure, or the first reset after close()): read "
    "env.physics again after each reset instead of keeping it"
)


class WeakPhysics:
    """A weak reference to an environment's `mjcf.Physics`, used like the Physics itself.

    Reading, writing and calling attributes (`env.physics.data.time`,
    `env.physics.bind(...)`) reach the Physics while its environment holds it;
    `isinstance(env.physics, mjcf.Physics)` is True then, as for a `weakref.proxy`.

    Raises:
      ReferenceError: on any use after the Physics is gone, saying whether its environment
        was garbage-collected, closed, or replaced the Physics, and what to do instead.
    """

    __slots__ = ("_weak_physics", "_weak_environment")

    def __init__(self, physics: mjcf.Physics, environment: composer.Environment):
        object.__setattr__(self, "_weak_physics", weakref.ref(physics))
        object.__setattr__(self, "_weak_environment", weakref.ref(environment))

    def _referent(self) -> mjcf.Physics:
        physics = self._weak_physics()
        if physics is not None:
            return physics
        environment = self._weak_environment()
        if environment is None:
            raise ReferenceError(_ENVIRONMENT_GONE)
        if environment.physics is None:
            raise ReferenceError(_ENVIRONMENT_CLOSED)
        raise ReferenceError(_PHYSICS_REPLACED)

    def __getattr__(self, name: str) -> Any:
        # Only reached for names this class does not define: everything of the Physics.
        return getattr(self._referent(), name)

    def __setattr__(self, name: str, value: Any) -> None:
        setattr(self._referent(), name, value)

    def __delattr__(self, name: str) -> None:
        delattr(self._referent(), name)

    def __dir__(self) -> list[str]:
        return dir(self._referent())

    @property
    def __class__(self) -> type:
        # What `isinstance` consults after the real type, so the Physics's class passes it.
        physics = self._weak_physics()
        return WeakPhysics if physics is None else type(physics)

    def __repr__(self) -> str:
        physics = self._weak_physics()
        if physics is None:
            return "<WeakPhysics to a Physics that no longer exists>"
        return f"<WeakPhysics to {physics!r}>"
