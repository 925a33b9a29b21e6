"""The order in which composer.Environment draws from its random state: dm_control's.

dm_control's environment resets its observation updater after every compile (at
construction and at each episode's recompile) and again after `initialize_episode`; a
corrupted observable draws its noise at each of those resets. With a fixed initial state,
the model's and the physics' initialisation each restart from the state the random state
had after construction. An observable without an array spec is sampled twice at each
updater reset (once for its shape), so its corruptor draws twice. The expected values below
are computed from a bare `np.random.RandomState` following that order; dm_control 1.0.50
on mujoco 3.17 gives the same numbers for this task.
"""

import numpy as np

import composer
from composer.observation import observable

SEED = 3


class NoisyTask(composer.Task):
    """A free-standing task whose one observable is a constant plus uniform noise, and
    whose hooks each draw one number (recorded)."""

    def __init__(self):
        self._arena = composer.Arena()
        self._arena.mjcf_model.worldbody.add("geom", type="sphere", size=[0.1])
        constant = observable.Generic(lambda physics: np.zeros(1))
        constant.corruptor = lambda value, random_state: value + random_state.uniform()
        constant.enabled = True
        self._noisy = constant
        self.mjcf_draws = []
        self.episode_draws = []

    @property
    def root_entity(self):
        return self._arena

    @property
    def task_observables(self):
        return {"noisy": self._noisy}

    def initialize_episode_mjcf(self, random_state):
        self.mjcf_draws.append(random_state.uniform())

    def initialize_episode(self, physics, random_state):
        self.episode_draws.append(random_state.uniform())

    def get_reward(self, physics):
        return 0.0


def _first_noise(env) -> float:
    return float(np.ravel(env.reset().observation["noisy"])[0])


def test_first_observation_takes_the_draw_after_both_updater_resets():
    # Construction: updater reset (draws 0, 1). Reset: mjcf hook (2), updater reset after
    # the compile (3, 4), episode hook (5), updater reset (6, 7).
    draws = np.random.RandomState(SEED).uniform(size=8)
    task = NoisyTask()
    env = composer.Environment(task, random_state=SEED)
    assert _first_noise(env) == draws[7]
    assert task.mjcf_draws == [draws[2]]
    assert task.episode_draws == [draws[5]]


def test_without_recompiles_later_resets_skip_the_compile_draws():
    # The second episode neither runs the mjcf hook nor recompiles: episode hook (8),
    # updater reset (9, 10).
    draws = np.random.RandomState(SEED).uniform(size=11)
    task = NoisyTask()
    env = composer.Environment(task, random_state=SEED, recompile_mjcf_every_episode=False)
    _first_noise(env)
    assert _first_noise(env) == draws[10]
    assert task.mjcf_draws == [draws[2]]
    assert task.episode_draws == [draws[5], draws[8]]


def test_fixed_initial_state_restarts_both_initialisations_from_construction():
    # Both hooks start from the state after construction (two draws in), so both get
    # draw 2; the updater reset that follows the episode hook draws 3 and 4.
    draws = np.random.RandomState(SEED).uniform(size=5)
    task = NoisyTask()
    env = composer.Environment(task, random_state=SEED, fixed_initial_state=True)
    first, second = _first_noise(env), _first_noise(env)
    assert first == second == draws[4]
    assert task.mjcf_draws == task.episode_draws == [draws[2], draws[2]]
