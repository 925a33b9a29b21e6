"""What the adapters run next to a sub-environment of a `composer.gym` vector env.

Plain functions of a Gymnasium env, in a module that imports no training library: a Ray
actor unpickles them by importing this module, and so never imports SB3 or torch.
"""

from typing import Any

import gymnasium


def get_attr(env: gymnasium.Env, name: str) -> Any:
    """Attribute `name` of `env` or of the first of its wrappers that has it."""
    return env.get_wrapper_attr(name)


def set_attr(env: gymnasium.Env, name: str, value: Any) -> None:
    """Sets attribute `name` where `env`'s wrappers keep it (see `set_wrapper_attr`)."""
    env.set_wrapper_attr(name, value)


def call_method(env: gymnasium.Env, name: str, args: tuple, kwargs: dict) -> Any:
    """Calls method `name` of `env` (looked up through its wrappers)."""
    return env.get_wrapper_attr(name)(*args, **kwargs)


def is_wrapped(env: gymnasium.Env, wrapper_class: type) -> bool:
    """Whether `env`, or a wrapper inside it, is an instance of `wrapper_class`."""
    while True:
        if isinstance(env, wrapper_class):
            return True
        if not isinstance(env, gymnasium.Wrapper):
            return False
        env = env.env
