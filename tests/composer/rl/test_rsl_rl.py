"""composer.rl.rsl_rl: rsl_rl's VecEnv over a batched environment, with real rsl_rl."""

import numpy as np
import pytest

pytestmark = pytest.mark.warp

torch = pytest.importorskip("torch", reason="torch is not installed: pip install torch==2.13.0")
pytest.importorskip("rsl_rl", reason="rsl_rl is not installed: pip install -e '.[rsl_rl]'")
pytest.importorskip("mujoco_warp", reason="MuJoCo Warp is not installed: pip install -e '.[warp]'")

import manipulation.batch  # noqa: E402
from composer.rl.rsl_rl import RslRlVecEnv  # noqa: E402

WORLDS = 4
# reach_site_features: 0.04 s per control step, so 0.2 s is 5 control steps.
TIME_LIMIT = 0.2
STEPS = 5


_OPTIONS = dict(
    seed=3,
    device="warp-cpu",
    array_type="torch",
    autoreset_mode="same_step",
    time_limit=TIME_LIMIT,
)


def _batch(**kwargs):
    return manipulation.batch.load("reach_site_features", WORLDS, **{**_OPTIONS, **kwargs})


@pytest.fixture(scope="module")
def env():
    adapter = RslRlVecEnv(_batch())
    yield adapter
    adapter.close()


@pytest.mark.parametrize(
    "options, named",
    [
        ({"array_type": "numpy"}, "array_type"),
        ({"autoreset_mode": "next_step"}, "autoreset_mode"),
        ({"time_limit": float("inf")}, "time_limit"),
    ],
)
def test_refuses_a_batch_rsl_rl_cannot_train_on(options, named):
    batch = _batch(**options)
    try:
        with pytest.raises(ValueError, match=named):
            RslRlVecEnv(batch)
    finally:
        batch.close()


def test_describes_the_batch_as_rsl_rl_expects(env):
    spec = env.unwrapped.action_spec()
    observations = env.get_observations()["policy"]
    sizes = [int(np.prod(s.shape)) for s in env.unwrapped.observation_spec().values()]
    assert env.num_envs == WORLDS
    assert env.num_actions == spec.shape[0]
    assert env.max_episode_length == STEPS
    assert observations.shape == (WORLDS, sum(sizes))
    assert observations.dtype == torch.float32


def test_unit_actions_reach_the_action_spec_bounds(env):
    spec = env.unwrapped.action_spec()
    ctrl = env.unwrapped.physics.field("data", "ctrl")
    env.reset()
    env.step(torch.ones(WORLDS, env.num_actions))
    np.testing.assert_allclose(np.asarray(ctrl.read())[0], spec.maximum, rtol=1e-6)
    env.step(-4 * torch.ones(WORLDS, env.num_actions))  # clipped to -1 first
    np.testing.assert_allclose(np.asarray(ctrl.read())[0], spec.minimum, rtol=1e-6)


def test_time_limit_ends_every_world_as_a_time_out_and_restarts_it(env):
    env.reset()
    zeros = torch.zeros(WORLDS, env.num_actions)
    for _ in range(STEPS - 1):
        _, _, dones, extras = env.step(zeros)
        assert not dones.any() and not extras["time_outs"].any()
    observations, rewards, dones, extras = env.step(zeros)
    assert dones.dtype == torch.long and dones.tolist() == [1] * WORLDS
    assert extras["time_outs"].tolist() == [True] * WORLDS
    assert rewards.shape == (WORLDS,)
    assert env.episode_length_buf.tolist() == [0] * WORLDS
    # The observation handed out is the next episode's first, not the ended one's last.
    final = env.unwrapped.final_observation["jaco_arm/joints_vel"].reshape(WORLDS, -1)
    assert not torch.equal(final, torch.zeros_like(final))
    first = env.get_observations()["policy"]
    assert torch.equal(observations["policy"], first)


def test_setting_episode_lengths_moves_each_worlds_time_out(env):
    env.reset()
    env.episode_length_buf = torch.tensor([STEPS - 1, 0, STEPS - 1, 2])
    _, _, dones, extras = env.step(torch.zeros(WORLDS, env.num_actions))
    assert dones.tolist() == [1, 0, 1, 0]
    assert extras["time_outs"].tolist() == [True, False, True, False]
    with pytest.raises(ValueError, match="episode_steps"):
        env.episode_length_buf = torch.tensor([1.5] * WORLDS)


def test_rsl_rl_ppo_trains_an_iteration_on_it():
    from rsl_rl.runners import OnPolicyRunner

    adapter = RslRlVecEnv(_batch())
    model = {"class_name": "MLPModel", "hidden_dims": [32], "activation": "elu"}
    config = {
        "num_steps_per_env": 4,
        "save_interval": 100,
        "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "actor": {**model, "distribution_cfg": {"class_name": "GaussianDistribution"}},
        "critic": model,
        "algorithm": {"class_name": "PPO", "num_mini_batches": 2},
    }
    runner = OnPolicyRunner(adapter, config, log_dir=None, device="cpu")
    before = [p.clone() for p in runner.alg.actor.parameters()]
    runner.learn(1, init_at_random_ep_len=True)
    after = list(runner.alg.actor.parameters())
    assert any(not torch.equal(a, b) for a, b in zip(before, after))
    adapter.close()


def test_images_apart_are_groups_of_their_own_holding_what_flattening_concatenates():
    # One world of a vision task, seeded alike: "flattened" (the default) concatenates every
    # observation in the spec's order; "apart" leaves the camera out of "policy".
    adapters = {
        images: RslRlVecEnv(
            manipulation.batch.load("lift_brick_vision", 1, **{**_OPTIONS, "seed": 5}),
            images=images,
        )
        for images in ("flattened", "apart")
    }
    try:
        flat = adapters["flattened"].get_observations()
        apart = adapters["apart"].get_observations()
        spec = adapters["apart"].unwrapped.observation_spec()
    finally:
        for adapter in adapters.values():
            adapter.close()
    assert list(flat.keys()) == ["policy"]
    assert list(apart.keys()) == ["policy", "front_close"]
    assert apart["front_close"].shape == (1, *spec["front_close"].shape)
    assert apart["front_close"].dtype == torch.float32
    pieces, features = [], iter(apart["policy"][0])
    for name, value in spec.items():
        size = int(np.prod(value.shape))
        if name == "front_close":
            pieces.append(apart["front_close"][0].reshape(-1))
        else:
            pieces.append(torch.stack([next(features) for _ in range(size)]))
    assert torch.equal(torch.cat(pieces), flat["policy"][0])
    assert flat["policy"].shape[1] - apart["policy"].shape[1] == 84 * 84 * 3


def test_an_unknown_images_choice_is_refused_naming_the_argument():
    batch = _batch()
    try:
        with pytest.raises(ValueError, match="images: expected 'apart' or 'flattened'"):
            RslRlVecEnv(batch, images="mixed")
    finally:
        batch.close()
