"""Records seeded episode starts of dm_control's composer environments (run by
`tools.dm_control_seeds`, inside a scratch venv; not library code).

Usage: `python tools/seed_episode_runner.py (reference | project) OUT.npz SEEDS STEPS
[ONLY [SHARD/SHARDS]]`

`reference` runs the installed dm_control as it is; `project` first installs this
project's redirect, so dm_control's environments run on this project's composer, mjcf and
engine. For every environment of dm_control's manipulation suite and the locomotion
examples, and every seed, it seeds NumPy's and Python's global generators with the seed
(some of dm_control's tasks draw from them), makes the environment, and records:

- every draw from the environment's random state, in order: the method called, a
  fingerprint of the generator's state after it, and the caller (`file:function`);
- the physics state after `reset()` (time, qpos, qvel, act);
- the first observation and the observations and rewards of `STEPS` steps under fixed
  actions (the same for both sides, a function of the step and action index only).

A harness setting, applied identically to both sides right after each environment is made
(before its first reset): `RENDER_QUALITY` lowers the MJCF model's
`<visual><quality shadowsize offsamples>` to a 512-pixel shadow map without
multisampling. Most of the run's CPU time is software rendering of the camera
observations, which this makes several times cheaper; dm_control recompiles at every
reset and the project updates its compiled model in place (render contexts included), so
both render the first episode with it, and the images are still compared at the same
tolerance.

It writes them to `OUT.npz`: arrays under `ENV/SEED/QUANTITY`, and the draws and errors
as JSON under `draws` and `errors`. `ONLY` (comma-separated names, or empty for all) and
`SHARD/SHARDS` (`1/2`: every second environment, from the second) pick the environments.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import json
import os
import random
import sys
import traceback

import numpy as np

_NOT_DRAWS = {"get_state", "seed", "tomaxint"}


class RecordingRandomState(np.random.RandomState):
    """A RandomState that logs each public method call that draws or sets its state."""

    def __init__(self, seed: int):
        super().__init__(seed)
        self.draws: list[list[str]] = []

    def fingerprint(self) -> str:
        _, key, position, has_gauss, gauss = super().get_state()
        digest = hashlib.sha1(key.tobytes())
        digest.update(f"{position}/{has_gauss}/{gauss!r}".encode())
        return digest.hexdigest()[:12]


def _recorded(name: str):
    method = getattr(np.random.RandomState, name)

    @functools.wraps(method)
    def call(self, *args, **kwargs):
        result = method(self, *args, **kwargs)
        frame = sys._getframe(1)
        where = f"{os.path.basename(frame.f_code.co_filename)}:{frame.f_code.co_name}"
        self.draws.append([name, self.fingerprint(), where])
        return result

    return call


for _name in dir(np.random.RandomState):
    if not _name.startswith("_") and _name not in _NOT_DRAWS:
        if callable(getattr(np.random.RandomState, _name)):
            setattr(RecordingRandomState, _name, _recorded(_name))


def environments():
    """Yields (name, constructor taking a random state) for every environment compared."""
    from dm_control import manipulation
    from dm_control.locomotion.examples import basic_cmu_2019, basic_rodent_2020

    def load_manipulation(name, random_state):
        return manipulation.load(name, seed=random_state)

    for name in sorted(manipulation.ALL):
        yield name, functools.partial(load_manipulation, name)
    for module in (basic_cmu_2019, basic_rodent_2020):
        for name, function in inspect.getmembers(module, inspect.isfunction):
            if function.__module__ == module.__name__ and not name.startswith("_"):
                yield name, function


#: `<visual><quality>` attributes set on both sides before the first reset (see above).
RENDER_QUALITY = {"shadowsize": 512, "offsamples": 0}


def render_cheaply(env) -> None:
    """Sets `RENDER_QUALITY` on the MJCF model of `env`'s task; the next reset compiles it."""
    quality = env.task.root_entity.mjcf_model.visual.quality
    for attribute, value in RENDER_QUALITY.items():
        setattr(quality, attribute, value)


def fixed_action(spec, step: int) -> np.ndarray:
    """The action of `step`: within the spec's bounds, different per index and step."""
    index = np.arange(int(np.prod(spec.shape))).reshape(spec.shape)
    wave = 0.5 + 0.4 * np.sin(1.3 * step + 0.7 * index)
    bounded = (np.abs(spec.minimum) < 1e9) & (np.abs(spec.maximum) < 1e9)
    low = np.where(bounded, spec.minimum, -1.0)
    high = np.where(bounded, spec.maximum, 1.0)
    return (low + (high - low) * wave).astype(spec.dtype)


def _flat_observation(observation) -> dict[str, np.ndarray]:
    return {key: np.asarray(value, dtype=np.float64).ravel() for key, value in observation.items()}


def record(name: str, make, seed: int, steps: int, arrays: dict, draws: dict) -> None:
    # Some of dm_control's tasks draw from NumPy's global generator too (the locomotion
    # tasks' spawn rotations), which makes their episodes differ from run to run even on
    # dm_control: both sides seed it, and Python's, the same way before each episode.
    np.random.seed(seed)
    random.seed(seed)
    random_state = RecordingRandomState(seed)
    env = make(random_state=random_state)
    render_cheaply(env)
    timestep = env.reset()
    prefix = f"{name}/{seed}"
    draws[prefix + "/reset"] = list(random_state.draws)
    del random_state.draws[:]
    data = env.physics.data
    arrays[prefix + "/time"] = np.array([data.time])
    for field in ("qpos", "qvel", "act"):
        arrays[prefix + "/" + field] = np.array(getattr(data, field), dtype=np.float64)
    observations = [_flat_observation(timestep.observation)]
    rewards = []
    spec = env.action_spec()
    for step in range(steps):
        timestep = env.step(fixed_action(spec, step))
        observations.append(_flat_observation(timestep.observation))
        rewards.append(np.nan if timestep.reward is None else float(timestep.reward))
    for key in observations[0]:
        arrays[f"{prefix}/observation/{key}"] = np.stack([o[key] for o in observations])
    arrays[prefix + "/reward"] = np.array(rewards)
    draws[prefix + "/steps"] = list(random_state.draws)
    env.close()


def main() -> int:
    side, out, seeds, steps = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    only = sys.argv[5].split(",") if len(sys.argv) > 5 and sys.argv[5] else None
    shard, shards = map(int, sys.argv[6].split("/")) if len(sys.argv) > 6 else (0, 1)
    if side == "project":
        from composer import dm_control_compat

        dm_control_compat.install()
    arrays: dict[str, np.ndarray] = {}
    draws: dict[str, list] = {}
    errors: dict[str, str] = {}
    for index, (name, make) in enumerate(environments()):
        if (only is not None and name not in only) or index % shards != shard:
            continue
        for seed in range(seeds):
            try:
                record(name, make, seed, steps, arrays, draws)
            except Exception as error:  # every environment is reported, whatever fails
                last = traceback.extract_tb(error.__traceback__)[-1]
                where = f"{os.path.basename(last.filename)}:{last.lineno}"
                errors[f"{name}/{seed}"] = f"{type(error).__name__}: {error} ({where})"[:400]
        print(name, flush=True)
    import mujoco

    np.savez_compressed(
        out,
        __meta__=np.array(
            json.dumps({"draws": draws, "errors": errors, "mujoco": mujoco.__version__})
        ),
        **arrays,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
