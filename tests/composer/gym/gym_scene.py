"""Small environments for the Gymnasium tests.

`SliderTask`: a 0.1 kg block on a slide joint driven by a motor limited to [-1, 1];
episodes start with the block at a random position, 10 physics steps of 2 ms per action.
`CounterEnv`: a `gymnasium.Env` whose observation is the step count of its episode, for
checking the vector envs' bookkeeping against values known in advance.
"""

import gymnasium
import numpy as np

import composer
import mjcf
from composer.observation import observable


class _Slider(composer.Entity):
    def _build(self):
        self._model = mjcf.RootElement(model="slider")
        body = self._model.worldbody.add("body", name="block")
        self.joint = body.add("joint", name="slide", type="slide", axis=[1, 0, 0])
        body.add("geom", type="box", size=[0.05, 0.05, 0.05], mass=0.1)
        self._model.worldbody.add("camera", name="side", pos=[0, -1, 0], xyaxes=[1, 0, 0, 0, 0, 1])
        self._model.actuator.add("motor", name="push", joint=self.joint, ctrlrange=[-1, 1])

    @property
    def mjcf_model(self):
        return self._model


class SliderTask(composer.Task):
    """Reward 1 per step. With `end_after_steps`, the task ends the episode (discount 0)
    after that many control steps."""

    def __init__(self, end_after_steps=None):
        self._slider = _Slider()
        self._end_after = end_after_steps
        self._steps = 0
        self.set_timesteps(control_timestep=0.02, physics_timestep=0.002)
        position = observable.MJCFFeature("qpos", self._slider.joint)
        position.enabled = True
        velocity = observable.MJCFFeature("qvel", [self._slider.joint])
        velocity.enabled = True
        self._observables = {"position": position, "velocity": velocity}

    @property
    def root_entity(self):
        return self._slider

    @property
    def task_observables(self):
        return self._observables

    def initialize_episode(self, physics, random_state):
        physics.bind(self._slider.joint).qpos = random_state.uniform(-1, 1)
        self._steps = 0

    def after_step(self, physics, random_state):
        self._steps += 1

    def should_terminate_episode(self, physics):
        return self._end_after is not None and self._steps >= self._end_after

    def get_discount(self, physics):
        return 0.0 if self.should_terminate_episode(physics) else 1.0

    def get_reward(self, physics):
        return 1.0


def slider_environment(time_limit=float("inf"), end_after_steps=None, seed=0):
    return composer.Environment(
        SliderTask(end_after_steps), time_limit=time_limit, random_state=seed
    )


class CounterEnv(gymnasium.Env):
    """Observation: [episode_start + steps taken]; reward: the step's number; the episode
    ends after `length` steps (terminated, or truncated with `truncate`). `episode_start`
    is 100 * the seed of the last seeded reset, plus 10 per reset since then."""

    def __init__(self, length, truncate=False, fail_at_step=None):
        self.observation_space = gymnasium.spaces.Box(0, 1e6, shape=(1,), dtype=np.float64)
        self.action_space = gymnasium.spaces.Box(-1, 1, shape=(1,), dtype=np.float64)
        self._length = length
        self._truncate = truncate
        self._fail_at = fail_at_step
        self._start = -10
        self._steps = 0

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self._start = 100 * seed if seed is not None else self._start + 10
        self._steps = 0
        return np.array([self._start], dtype=np.float64), {"reset": True}

    def step(self, action):
        self._steps += 1
        if self._steps == self._fail_at:
            raise ValueError(f"failing at step {self._steps}")
        end = self._steps >= self._length
        observation = np.array([self._start + self._steps], dtype=np.float64)
        info = {"step": self._steps}
        return (
            observation,
            float(self._steps),
            end and not self._truncate,
            end and self._truncate,
            info,
        )
