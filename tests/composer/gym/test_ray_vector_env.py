"""RayVectorEnv on a real local Ray with 2 CPUs: equality with the threaded vector env,
restarts after an actor is killed, errors that name the sub-environment, clean closing.

Marked `ray` (deselect with -m "not ray"); skipped when Ray is not installed.
"""

import functools
import importlib.util
import pathlib
import re
import time

import gymnasium
import numpy as np
import pytest
from gym_scene import CounterEnv, slider_environment
from ray_actors import wait_until_dead

import manipulation  # noqa: F401  (registers the composer/<name>-v0 ids)
from composer.gym import GymnasiumEnv, RayVectorEnv, SubEnvironmentError, ThreadedVectorEnv

pytestmark = pytest.mark.ray

_HERE = pathlib.Path(__file__).resolve().parent
_EXAMPLE = _HERE.parents[2] / "examples" / "ray_rollouts.py"
_README = _HERE.parents[2] / "README.md"


@pytest.fixture(scope="module")
def ray():
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install -e '.[ray]')")
    # The actors' processes import gym_scene (pickled by reference) from this folder. A
    # new local Ray ("local"), whatever a killed earlier run left behind.
    ray.init(
        address="local",
        num_cpus=2,
        include_dashboard=False,
        runtime_env={"env_vars": {"PYTHONPATH": str(_HERE)}},
    )
    yield ray
    ray.shutdown()


@pytest.fixture
def closing():
    """Returns `keep(vector_env)`, which closes it after the test, passed or failed: an
    actor left alive keeps its CPU, and the next test's actors would wait for it."""
    kept = []
    yield lambda envs: kept.append(envs) or envs
    for envs in kept:
        envs.close()


def _counters(lengths, **kwargs):
    return [functools.partial(CounterEnv, length, **kwargs) for length in lengths]


def _kill(ray, actor):
    """Kills `actor` and waits until it is dead (`ray.kill` only sends the request)."""
    ray.kill(actor)
    wait_until_dead(ray, actor)


def _slider():
    return GymnasiumEnv(slider_environment(time_limit=0.1))


def _bits(value):
    """`value` (arrays, or dicts and tuples of them) as bytes: equality is bit for bit."""
    if isinstance(value, dict):
        return sorted((key, _bits(part)) for key, part in value.items())
    if isinstance(value, tuple):
        return [_bits(part) for part in value]
    return np.asarray(value).tobytes()


def test_same_seeds_and_actions_give_bit_identical_results_to_the_threaded_env(ray, closing):
    # Episodes of 5 control steps: 12 steps cross two NEXT_STEP autoresets.
    ours = closing(RayVectorEnv([_slider] * 4, envs_per_actor=2))
    reference = closing(ThreadedVectorEnv([_slider] * 4, num_threads=2))
    assert ours.single_observation_space == reference.single_observation_space
    first, expected = ours.reset(seed=7), reference.reset(seed=7)
    assert _bits(first) == _bits(expected)
    actions = np.random.default_rng(0).uniform(-1, 1, size=(12, 4, 1))
    ended = 0
    for action in actions:
        got, expected = ours.step(action), reference.step(action)
        assert _bits(got) == _bits(expected)
        ended += int(got[3].sum())
    assert ended == 8


def _ending_slider(steps):
    return GymnasiumEnv(slider_environment(end_after_steps=steps))


def test_same_step_autoreset_final_observations_match_the_threaded_envs(ray, closing):
    # Each actor's sub-environments write into one flat buffer; the final observation of
    # an episode reset in the same step must survive the reset written over it.
    fns = [functools.partial(_ending_slider, n) for n in (1, 2, 3, 2)]
    ours = closing(RayVectorEnv(fns, envs_per_actor=2, autoreset_mode="SameStep"))
    reference = closing(ThreadedVectorEnv(fns, num_threads=2, autoreset_mode="SameStep"))
    assert _bits(ours.reset(seed=3)[0]) == _bits(reference.reset(seed=3)[0])
    finals = 0
    for action in np.random.default_rng(1).uniform(-1, 1, size=(5, 4, 1)):
        got, expected = ours.step(action), reference.step(action)
        assert _bits(got[:4]) == _bits(expected[:4])
        assert got[4]["_final_obs"].tolist() == expected[4]["_final_obs"].tolist()
        for i in np.flatnonzero(expected[4]["_final_obs"]):
            assert _bits(got[4]["final_obs"][i]) == _bits(expected[4]["final_obs"][i])
            finals += 1
    assert finals == 5 + 2 + 1 + 2


def test_make_vec_with_backend_ray_matches_the_threads_backend(ray, closing):
    made = {
        backend: closing(
            gymnasium.make_vec(
                "composer/reach_site_features-v0",
                num_envs=2,
                vectorization_mode="vector_entry_point",
                backend=backend,
            )
        )
        for backend in ("ray", "threads")
    }
    assert isinstance(made["ray"], RayVectorEnv)
    assert made["ray"].envs_per_actor == 1
    got, expected = (envs.reset(seed=3) for envs in made.values())
    assert len(got[0]) > 1
    assert _bits(got) == _bits(expected)
    for action in np.random.default_rng(1).uniform(-1, 1, size=(3, 2, 9)):
        got, expected = (envs.step(action) for envs in made.values())
        assert _bits(got) == _bits(expected)


def test_make_vec_passes_the_ray_timeouts_on(ray, closing):
    envs = closing(
        gymnasium.make_vec(
            "composer/reach_site_features-v0",
            num_envs=1,
            vectorization_mode="vector_entry_point",
            backend="ray",
            start_timeout=30,
            call_timeout=45,
        )
    )
    assert (envs.start_timeout, envs.call_timeout) == (30.0, 45.0)


def test_a_registered_id_is_made_with_gymnasium_make_in_the_actors(ray, closing):
    envs = closing(RayVectorEnv("composer/reach_site_features-v0", num_envs=2, envs_per_actor=2))
    assert len(envs.actors) == 1
    assert envs.single_action_space.shape == (9,)
    observations, _ = envs.reset(seed=0)
    assert observations["jaco_arm/joints_pos"].shape == (2, 6, 2)


def test_a_killed_actor_is_restarted_and_only_its_sub_envs_report_truncation(ray, closing):
    lengths = [4, 6, 3, 6]
    envs = closing(RayVectorEnv(_counters(lengths), envs_per_actor=2))
    reference = closing(ThreadedVectorEnv(_counters(lengths), num_threads=2))
    zeros = np.zeros((4, 1))
    for vector in (envs, reference):
        vector.reset(seed=0)
        vector.step(zeros)
        vector.step(zeros)
    _kill(ray, envs.actors[1])
    observations, rewards, terminated, truncated, infos = envs.step(zeros)
    expected = reference.step(zeros)
    assert observations[:2].tolist() == expected[0][:2].tolist()
    # Sub-envs 0 and 1 lose no step; 2 and 3 (actor 1) end with their last observation.
    assert observations[:, 0].tolist() == [3, 103, 202, 302]
    assert rewards.tolist() == [3, 3, 0, 0]
    assert terminated.tolist() == [False, False, False, False]
    assert truncated.tolist() == [False, False, True, True]
    assert infos["_restarted"].tolist() == [False, False, True, True]
    assert envs.restarts == [0, 1]
    # The restarted sub-envs start new episodes (their new CounterEnv starts at 0).
    observations, rewards, _, _, infos = envs.step(zeros)
    reference.step(zeros)
    assert observations[:, 0].tolist() == [4, 104, 0, 0]
    assert infos["_reset"].tolist() == [False, False, True, True]
    for _ in range(6):
        observations, *_ = envs.step(zeros)
        expected = reference.step(zeros)
        assert observations[:2].tolist() == expected[0][:2].tolist()


def test_a_killed_actor_in_same_step_mode_returns_reset_and_final_observations(ray, closing):
    envs = closing(RayVectorEnv(_counters([5, 5]), envs_per_actor=1, autoreset_mode="SameStep"))
    envs.reset(seed=[1, 2])
    envs.step(np.zeros((2, 1)))
    _kill(ray, envs.actors[0])
    observations, rewards, terminated, truncated, infos = envs.step(np.zeros((2, 1)))
    assert observations[:, 0].tolist() == [0, 202]
    assert truncated.tolist() == [True, False]
    assert infos["_final_obs"].tolist() == [True, False]
    assert infos["final_obs"][0].tolist() == [101]
    assert infos["restarted"][0]


def test_a_masked_reset_after_an_actor_died_also_resets_its_other_sub_env(ray, closing):
    envs = closing(RayVectorEnv(_counters([5, 5, 5, 5]), envs_per_actor=2))
    zeros = np.zeros((4, 1))
    envs.reset(seed=0)
    envs.step(zeros)
    _kill(ray, envs.actors[1])
    # Sub-env 2 is reset with seed 1 + 2; sub-env 3, new and outside the mask, without one
    # (a new CounterEnv's first unseeded episode starts at 0).
    mask = np.array([False, False, True, False])
    observations, infos = envs.reset(seed=1, options={"reset_mask": mask})
    assert observations[:, 0].tolist() == [1, 101, 300, 0]
    assert infos["_restarted"].tolist() == [False, False, True, True]
    observations, *_ = envs.step(zeros)
    assert observations[:, 0].tolist() == [2, 102, 301, 1]


def test_an_actor_that_dies_more_than_max_restarts_times_raises(ray, closing):
    envs = closing(RayVectorEnv(_counters([5, 5]), envs_per_actor=2, max_restarts=0))
    envs.reset(seed=0)
    _kill(ray, envs.actors[0])
    with pytest.raises(RuntimeError, match="sub-environments 0 to 1 died 1 times; max_restarts"):
        envs.step(np.zeros((2, 1)))


def test_an_exception_inside_a_sub_env_names_its_index_and_reset_recovers(ray, closing):
    fns = _counters([5, 5, 5]) + _counters([5], fail_at_step=2)
    envs = closing(RayVectorEnv(fns, envs_per_actor=2))
    envs.reset(seed=0)
    envs.step(np.zeros((4, 1)))
    with pytest.raises(SubEnvironmentError, match="sub-environment 3 raised ValueError") as info:
        envs.step(np.zeros((4, 1)))
    assert info.value.index == 3
    assert isinstance(info.value.__cause__, ValueError)
    assert str(info.value.__cause__) == "failing at step 2"
    observations, _ = envs.reset(seed=0)
    assert observations[:, 0].tolist() == [0, 100, 200, 300]
    observations, *_ = envs.step(np.zeros((4, 1)))
    assert observations[:, 0].tolist() == [1, 101, 201, 301]
    assert envs.restarts == [0, 0]


def test_call_and_set_attr_carry_values_plain_pickle_cannot_such_as_a_lambda(ray, closing):
    envs = closing(RayVectorEnv(_counters([3, 3, 3]), envs_per_actor=2))
    envs.set_attr("scale", [lambda x: x * 2, lambda x: x * 3, lambda x: x * 4])
    assert envs.call("scale", 5) == (10, 15, 20)
    assert envs.get_attr("_length") == (3, 3, 3)


def test_a_factory_that_raises_names_its_sub_env(ray):
    def broken():
        raise OSError("no such model")

    with pytest.raises(SubEnvironmentError, match="sub-environment 2 raised OSError"):
        RayVectorEnv(_counters([3, 3]) + [broken], envs_per_actor=2)


def test_the_ray_rollouts_example_collects_episodes_and_prints_throughput(ray, capsys):
    spec = importlib.util.spec_from_file_location("ray_rollouts", _EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    example.main(["--environment", "reach_site_features", "--episodes", "2", "--num-envs", "2"])
    printed = capsys.readouterr().out
    assert "reach_site_features: 2 sub-environments in 2 Ray actors (1 each)" in printed
    assert re.search(r"^[23] episodes, \d+ steps in [\d.]+ s: \d+ steps/s", printed, re.M)


def test_the_readme_scale_out_with_ray_example_runs_as_written(ray):
    text = _README.read_text(encoding="utf-8")
    code = re.search(r"## Scale out with Ray\n[^#]*?```python\n(.*?)```", text, re.S).group(1)
    namespace = {}
    exec(compile(code, str(_README), "exec"), namespace)
    assert namespace["rewards"].shape == (8,)
    assert namespace["envs"].closed


def test_close_kills_every_actor_and_frees_their_cpus(ray, closing):
    envs = closing(RayVectorEnv(_counters([3, 3]), envs_per_actor=1))
    actors = envs.actors
    assert len(actors) == 2
    assert envs.num_cpus_per_actor == 1.0
    envs.close()
    for actor in actors:
        wait_until_dead(ray, actor)
    deadline = time.monotonic() + 30
    while ray.available_resources().get("CPU", 0) < 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    assert ray.available_resources().get("CPU", 0) == 2
    with pytest.raises(gymnasium.error.ClosedEnvironmentError, match="closed"):
        envs.actors  # noqa: B018
