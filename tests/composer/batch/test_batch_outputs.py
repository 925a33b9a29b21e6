"""Device outputs: with array_type 'warp' a batch hands out Warp arrays on its device,
equal to its NumPy results, sharing memory with NumPy on the CPU device; actions may be
device arrays."""

import gymnasium
import numpy as np
import pytest

from composer.batch import BatchTimeStep
from manipulation import batch as manipulation_batch

pytestmark = pytest.mark.warp
wp = pytest.importorskip("warp", reason="needs MuJoCo Warp: pip install -e '.[warp]'")

NUM_ENVS = 3
STEPS = 4


def _actions(env, seed=0):
    spec = env.action_spec()
    rng = np.random.RandomState(seed)
    return [rng.uniform(spec.minimum, spec.maximum, (NUM_ENVS, *spec.shape)) for _ in range(STEPS)]


def _host(time_step: BatchTimeStep) -> BatchTimeStep:
    return BatchTimeStep(
        time_step.step_type.numpy(),
        time_step.reward.numpy(),
        time_step.discount.numpy(),
        {name: value.numpy() for name, value in time_step.observation.items()},
    )


def _assert_same(actual: BatchTimeStep, expected: BatchTimeStep):
    np.testing.assert_array_equal(actual.step_type, expected.step_type)
    np.testing.assert_array_equal(actual.reward, expected.reward)
    np.testing.assert_array_equal(actual.discount, expected.discount)
    assert actual.observation.keys() == expected.observation.keys()
    for name, value in expected.observation.items():
        assert actual.observation[name].dtype == value.dtype, name
        np.testing.assert_array_equal(actual.observation[name], value, err_msg=name)


@pytest.fixture(scope="module", params=["reach_site_features", "lift_brick_features"])
def name(request):
    return request.param


@pytest.fixture(scope="module")
def numpy_run(name):
    env = manipulation_batch.load(name, NUM_ENVS, seed=3, device="warp-cpu")
    actions = _actions(env)
    return actions, [env.reset()] + [env.step(action) for action in actions]


def test_warp_outputs_equal_the_numpy_outputs_every_step(name, numpy_run):
    actions, expected = numpy_run
    env = manipulation_batch.load(name, NUM_ENVS, seed=3, array_type="warp", device="warp-cpu")
    steps = [env.reset()] + [env.step(action) for action in actions]
    for time_step, reference in zip(steps, expected):
        for value in (time_step.reward, *time_step.observation.values()):
            assert isinstance(value, wp.array) and value.device.is_cpu
        _assert_same(_host(time_step), reference)


def test_device_actions_step_the_worlds_as_the_same_numpy_actions(name, numpy_run):
    actions, expected = numpy_run
    env = manipulation_batch.load(name, NUM_ENVS, seed=3, array_type="warp", device="warp-cpu")
    steps = [env.reset()]
    for dtype, action in zip([wp.float32, wp.float64] * STEPS, actions):
        steps.append(env.step(wp.array(action, dtype=dtype, device="cpu")))
    for time_step, reference in zip(steps, expected):
        host = _host(time_step)
        np.testing.assert_array_equal(host.reward, reference.reward)
        for key, value in reference.observation.items():
            # float32 actions are what the worlds' float32 controls hold either way.
            np.testing.assert_array_equal(host.observation[key], value, err_msg=key)


def _zeros(env):
    return np.zeros((NUM_ENVS, *env.action_spec().shape))


@pytest.fixture(scope="module")
def warp_env():
    env = manipulation_batch.load(
        "reach_site_features", NUM_ENVS, seed=1, array_type="warp", device="warp-cpu"
    )
    env.reset()
    return env


def test_cpu_warp_outputs_are_numpy_arrays_without_a_copy(warp_env):
    observation = warp_env.step(_zeros(warp_env)).observation
    for value in observation.values():
        view = np.asarray(value)
        assert view.__array_interface__["data"][0] == value.ptr
        view[...] = 7.0
        assert (value.numpy() == 7.0).all()


def test_a_later_step_leaves_earlier_results_as_they_were(warp_env):
    first = warp_env.step(_zeros(warp_env) + 0.5)
    kept = {name: value.numpy().copy() for name, value in first.observation.items()}
    warp_env.step(_zeros(warp_env) - 0.5)
    for name, value in first.observation.items():
        np.testing.assert_array_equal(value.numpy(), kept[name], err_msg=name)


def test_step_types_of_warp_outputs_compare_elementwise(warp_env):
    time_step = warp_env.reset()
    np.testing.assert_array_equal(time_step.first(), [True] * NUM_ENVS)
    np.testing.assert_array_equal(time_step.last(), [False] * NUM_ENVS)


def test_device_action_with_nan_names_the_world_and_steps_nothing(warp_env):
    warp_env.step(_zeros(warp_env))
    qpos = warp_env.physics.data.qpos.copy()
    action = _zeros(warp_env).astype(np.float32)
    action[2, 4] = np.nan
    with pytest.raises(ValueError, match=r"action: NaN or infinity in the actions of worlds \[2\]"):
        warp_env.step(wp.array(action, device="cpu"))
    np.testing.assert_array_equal(warp_env.physics.data.qpos, qpos)


def test_float64_device_action_beyond_float32_names_the_world(warp_env):
    warp_env.step(_zeros(warp_env))
    action = _zeros(warp_env).astype(np.float64)
    action[1, 3] = 1e39
    with pytest.raises(ValueError, match=r"beyond float32's range .* worlds \[1\]"):
        warp_env.step(wp.array(action, dtype=wp.float64, device="cpu"))


def test_device_action_of_the_wrong_shape_is_refused(warp_env):
    with pytest.raises(ValueError, match=r"action: expected shape \(3, 9\).*got \(3, 5\)"):
        warp_env.step(wp.zeros((NUM_ENVS, 5), dtype=wp.float32, device="cpu"))


def test_device_action_of_an_integer_type_is_refused(warp_env):
    with pytest.raises(ValueError, match="action: expected a contiguous float32 or float64"):
        warp_env.step(wp.zeros((NUM_ENVS, 9), dtype=wp.int32, device="cpu"))


def test_unknown_array_type_is_refused_before_compiling():
    with pytest.raises(ValueError, match=r"array_type: expected one of .*'jax'\], got 'cupy'"):
        manipulation_batch.load("reach_site_features", 2, array_type="cupy")


def test_gymnasium_vector_env_returns_warp_arrays():
    env = gymnasium.make_vec(
        "composer/reach_site_features-v0",
        num_envs=2,
        vectorization_mode="vector_entry_point",
        backend="batch",
        array_type="warp",
        device="warp-cpu",
    )
    observation, _ = env.reset(seed=0)
    observation, reward, terminated, truncated, info = env.step(np.zeros((2, 9)))
    for value in (*observation.values(), reward, terminated, truncated, info["discount"]):
        assert isinstance(value, wp.array)
    assert terminated.numpy().dtype == bool and not terminated.numpy().any()
    env.close()


@pytest.fixture
def jax_x64():
    jax = pytest.importorskip("jax", reason="JAX is optional and not installed (out of CI)")
    # Rewards and discounts are float64; without x64 JAX would hold them as float32.
    enabled = jax.config.jax_enable_x64
    jax.config.update("jax_enable_x64", True)
    yield jax.numpy
    jax.config.update("jax_enable_x64", enabled)


def test_jax_outputs_equal_the_numpy_outputs_and_take_jax_actions(numpy_run, name, jax_x64):
    jnp = jax_x64
    actions, expected = numpy_run
    env = manipulation_batch.load(name, NUM_ENVS, seed=3, array_type="jax")
    steps = [env.reset()] + [env.step(jnp.asarray(action)) for action in actions]
    for time_step, reference in zip(steps, expected):
        assert all(isinstance(v, type(jnp.zeros(1))) for v in time_step.observation.values())
        _assert_same(
            BatchTimeStep(
                np.asarray(time_step.step_type),
                np.asarray(time_step.reward),
                np.asarray(time_step.discount),
                {key: np.asarray(value) for key, value in time_step.observation.items()},
            ),
            reference,
        )


def test_torch_task_code_gives_the_numpy_results_as_torch_tensors(numpy_run, name):
    torch = pytest.importorskip("torch", reason="torch is optional: pip install torch==2.13.0")
    actions, expected = numpy_run
    env = manipulation_batch.load(name, NUM_ENVS, seed=3, device="warp-cpu", array_type="torch")
    assert env.physics.xp.__name__.endswith("torch")  # the hooks ran on torch tensors
    steps = [env.reset()] + [env.step(torch.as_tensor(action)) for action in actions]
    # The same float32 physics; torch's and NumPy's float32 sin, cos, exp and norms may
    # round differently, by an ulp or two of each operation (4 ulps allowed).
    tolerance = 4 * np.finfo(np.float32).eps
    for time_step, reference in zip(steps, expected):
        assert all(isinstance(v, torch.Tensor) for v in time_step.observation.values())
        np.testing.assert_array_equal(time_step.step_type.numpy(), reference.step_type)
        np.testing.assert_allclose(
            time_step.reward.numpy(), reference.reward, rtol=tolerance, atol=tolerance
        )
        for key, value in reference.observation.items():
            got = time_step.observation[key].numpy()
            np.testing.assert_allclose(got, value, rtol=tolerance, atol=tolerance, err_msg=key)
