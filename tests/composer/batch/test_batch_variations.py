"""Composer's variators in a batch: each world draws its own values at its resets, exactly as
a CPU environment seeded alike draws them, and a variation that needs a recompile is refused
naming the element, the attribute and why.

The refusals come before Warp is loaded, so they run without it; the tests marked `warp`
build batches on Warp's CPU device.
"""

import functools
import json
import warnings

import mujoco
import numpy as np
import pytest
from test_batch_equivalence import _assert_world_matches, _max_servo_gain

import composer
import manipulation
import mjcf
from composer import batch, variation
from composer.variation import distributions
from manipulation import batch as manipulation_batch
from manipulation.props import Duplo2x4
from manipulation.tasks import observation_settings
from manipulation.tasks.lift import Lift
from manipulation.tasks.reach import Reach
from mjcf.patching import patchable_attributes

NAME = "lift_brick_randomised_features"
SEEDS = (11, 12, 13)
RESETS = 3
CONTROL_STEPS = 5


class _VariedReach(Reach):
    """reach_site whose `initialize_episode_mjcf` sets `attributes` of the element that
    `find(task)` returns, each to a draw of `attributes[name](random_state)`."""

    def __init__(self, find, **attributes):
        super().__init__(observation_settings.FEATURES)
        self.element = find(self)
        self.attributes = attributes

    def initialize_episode_mjcf(self, random_state) -> None:
        values = {name: draw(random_state) for name, draw in self.attributes.items()}
        self.element.set_attributes(**values)


def _floor(task):
    return task.arena.mjcf_model.find("geom", "floor")


def _target(task):
    return task.target


def _rgba(random_state):
    return random_state.uniform(size=4)


def _tinted_reach() -> _VariedReach:
    return _VariedReach(_target, rgba=_rgba)


def test_a_variation_of_an_unproven_attribute_is_refused_with_the_proofs_reason():
    task = _VariedReach(_floor, pos=lambda random_state: random_state.uniform(size=3))
    with pytest.raises(
        NotImplementedError,
        match=r"<geom name='floor'> attribute 'pos', changed by initialize_episode_mjcf: needs "
        r"a recompile, .*the proof refuses it: .*(bvh_aabb|body_i)",
    ):
        batch.BatchEnvironment(task, 2)


def test_a_refused_variation_says_how_to_draw_it_per_world_instead():
    task = _VariedReach(_floor, pos=lambda random_state: random_state.uniform(size=3))
    with pytest.raises(NotImplementedError) as refused:
        batch.BatchEnvironment(task, 2)
    message = str(refused.value)
    assert "write its compiled value in initialize_episode instead" in message
    assert "`physics.bind(element).pos = random_state.uniform(low, high)`" in message
    assert "docs/concepts/batch.md#what-to-do-about-a-refused-variation" in message


def test_a_variation_the_proof_does_not_cover_is_refused_saying_so():
    task = _VariedReach(_floor, mass=lambda random_state: random_state.uniform(1.0, 2.0))
    with pytest.raises(
        NotImplementedError,
        match=r"<geom name='floor'> attribute 'mass'.*needs a recompile.*does not cover it",
    ):
        batch.BatchEnvironment(task, 2)


class _GrowingReach(Reach):
    def initialize_episode_mjcf(self, random_state) -> None:
        self.arena.mjcf_model.worldbody.add("geom", size=[random_state.uniform(0.01, 0.02)])


def test_a_change_of_the_models_structure_is_refused():
    with pytest.raises(NotImplementedError, match=r"changed the MJCF model's structure.*recompile"):
        batch.BatchEnvironment(_GrowingReach(observation_settings.FEATURES), 2)


@pytest.mark.warp
def test_a_variation_on_a_release_the_table_is_not_proven_on_is_proven_at_construction(
    monkeypatch, tmp_path
):
    monkeypatch.setattr(patchable_attributes, "MUJOCO_VERSION", "3.0.0")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))  # no cached proof either
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        # The CPU batch: no Warp start-up, whose own warnings (a stale kernel cache) are
        # not this test's.
        env = batch.BatchEnvironment(_tinted_reach(), 2, device="cpu")
    env.close()
    cached = tmp_path / "mujoco-composer" / "patch_proof" / f"mujoco-{mujoco.__version__}.json"
    proofs = json.loads(cached.read_text(encoding="utf-8"))["contexts"]
    assert [(proof["tag"], proof["attribute"]) for proof in proofs] == [("site", "rgba")]


class _AlternatingReach(Reach):
    """Sets the floor's colour in one episode, its friction in the next, and so on."""

    def __init__(self):
        super().__init__(observation_settings.FEATURES)
        self.episodes = 0

    def initialize_episode_mjcf(self, random_state) -> None:
        floor = _floor(self)
        if self.episodes % 2 == 0:
            floor.rgba = random_state.uniform(size=4)
        else:
            floor.friction = random_state.uniform(0.5, 1.0, size=3)
        self.episodes += 1


def test_a_variation_that_leaves_an_attribute_of_an_earlier_episode_unset_is_refused():
    # The worlds of a producer share its MJCF tree: an attribute left as it is keeps
    # another world's value.
    with pytest.raises(
        NotImplementedError,
        match=r"<geom name='floor'> attribute 'rgba': set by initialize_episode_mjcf in an "
        r"earlier episode but not in this one",
    ):
        batch.BatchEnvironment(_AlternatingReach(), 2)


class _ArrayCodeReach(manipulation_batch.BatchReach):
    def initialize_episode(self, physics, mask) -> None:
        pass


def test_an_mjcf_variation_is_refused_where_array_code_sets_the_initial_states():
    with pytest.raises(
        NotImplementedError,
        match=r"_VariedReach.initialize_episode_mjcf varies the MJCF model per episode, but "
        r"_ArrayCodeReach sets initial states with array code",
    ):
        batch.BatchEnvironment(_ArrayCodeReach(_tinted_reach()), 2)


@pytest.mark.warp
def test_a_variation_of_a_field_that_mujoco_warp_shares_between_worlds_is_refused():
    task = _VariedReach(_target, size=lambda random_state: random_state.uniform(0.02, 0.05, 3))
    with pytest.raises(
        NotImplementedError,
        match=r"model field 'site_size' \(from <site name='target'> attribute 'size'\) varies "
        r"per world, but MuJoCo Warp shares it",
    ):
        batch.BatchEnvironment(task, 2, device="warp-cpu")


@pytest.mark.warp
def test_a_variation_of_a_field_the_device_lacks_keeps_the_cpu_draws_with_process_producers():
    # A site's colour is not on MuJoCo Warp's model; its draw still precedes the target's.
    factory = functools.partial(_VariedReach, _target, rgba=_rgba)
    batch_env = batch.BatchEnvironment(
        factory(),
        len(SEEDS),
        random_states=SEEDS,
        device="warp-cpu",
        task_factory=factory,
        state_workers=2,
        state_processes=True,
    )
    targets = batch_env.reset().observation["target_position"]
    batch_env.close()
    assert "site_rgba" not in batch_env.physics.batched_model_fields
    for world, seed in enumerate(SEEDS):
        cpu = composer.Environment(factory(), random_state=seed)
        expected = cpu.reset().observation["target_position"]
        # Within float32 rounding; a target drawn from the wrong place is centimetres off.
        np.testing.assert_allclose(targets[world], expected, rtol=0.0, atol=1e-6)


def _varied_values(physics, task) -> dict:
    """The varied values of `task`'s brick in `physics` (CPU or batched)."""
    prop = task.prop
    body = physics.bind(mjcf.get_attachment_frame(prop.mjcf_model))
    geoms = physics.bind(prop.mjcf_model.find_all("geom"))
    return {
        "mass": body.mass,
        "inertia": body.inertia,
        "friction": geoms.friction,
        "rgba": geoms.rgba,
    }


@pytest.mark.warp
def test_each_world_draws_the_cpu_environments_values_at_every_reset():
    batch_env = manipulation_batch.load(NAME, len(SEEDS), random_states=SEEDS, device="warp-cpu")
    cpu_envs = [manipulation.load(NAME, seed=seed) for seed in SEEDS]
    plain = manipulation.load("lift_brick_features", seed=0)
    plain.reset()
    built = _varied_values(plain.physics, plain.task)  # the brick as built: 25 g
    masses = []
    for _ in range(RESETS):
        batch_env.reset()
        drawn = _varied_values(batch_env.physics, batch_env.task.task)
        for world, env in enumerate(cpu_envs):
            env.reset()
            for key, expected in _varied_values(env.physics, env.task).items():
                # The device holds float32: the CPU's values rounded, bit for bit.
                np.testing.assert_array_equal(
                    drawn[key][world], np.float32(expected), err_msg=f"world {world}, {key}"
                )
        # One mass factor for mass and inertia, one friction factor and one colour per brick.
        mass_factors = drawn["mass"] / built["mass"]
        np.testing.assert_allclose(
            drawn["inertia"] / built["inertia"], mass_factors[:, None] * np.ones(3), rtol=1e-5
        )
        assert np.all((0.5 <= mass_factors) & (mass_factors <= 2.0))
        factors = drawn["friction"] / built["friction"]
        same = np.broadcast_to(factors[:, :1, :1], factors.shape)
        np.testing.assert_allclose(factors, same, rtol=1e-5)
        assert np.all((0.5 <= factors) & (factors <= 1.5))
        rgba = drawn["rgba"]
        np.testing.assert_array_equal(rgba, np.broadcast_to(rgba[:, :1], rgba.shape))
        masses.append(drawn["mass"].copy())
    masses = np.array(masses)  # (resets, worlds)
    assert len(np.unique(masses)) == masses.size  # every world and episode its own
    batch_env.close()


@pytest.mark.warp
def test_worlds_match_their_cpu_environments_over_several_randomised_episodes():
    batch_env = manipulation_batch.load(NAME, len(SEEDS), random_states=SEEDS, device="warp-cpu")
    cpu_envs = [manipulation.load(NAME, seed=seed) for seed in SEEDS]
    kv = _max_servo_gain(cpu_envs[0])
    n_sub_steps = cpu_envs[0].task.physics_steps_per_control_step
    spec = cpu_envs[0].action_spec()
    rng = np.random.default_rng(5)
    for _ in range(RESETS):
        cpu_steps = [env.reset() for env in cpu_envs]
        _assert_world_matches(batch_env.reset(), cpu_steps, 1, NAME, kv)
        for step in range(1, CONTROL_STEPS + 1):
            action = rng.uniform(spec.minimum, spec.maximum, (len(SEEDS), spec.shape[0]))
            cpu_steps = [env.step(a) for env, a in zip(cpu_envs, action)]
            physics_steps = step * n_sub_steps + 1
            _assert_world_matches(batch_env.step(action), cpu_steps, physics_steps, NAME, kv)
    batch_env.close()


class _GearedLift(Lift):
    """lift_brick whose first arm actuator's gear is drawn at every episode: an attribute
    after whose change `mj_setConst` recomputes `actuator_acc0`."""

    def __init__(self):
        super().__init__(observation_settings.FEATURES, Duplo2x4(), rest_height=0.0)
        self.actuator = self.root_entity.mjcf_model.find_all("actuator")[0]
        self._variator = variation.MJCFVariator()
        self._variator.bind_attributes(
            self.actuator, gear=distributions.Uniform([0.5, 0, 0, 0, 0, 0], [2.0, 0, 0, 0, 0, 0])
        )

    def initialize_episode_mjcf(self, random_state) -> None:
        self._variator.apply_variations(random_state)


@pytest.mark.warp
def test_derived_constants_follow_each_worlds_draw_and_change_only_in_the_reset_worlds():
    batch_env = batch.BatchEnvironment(
        _GearedLift(), len(SEEDS), random_states=SEEDS, device="warp-cpu", time_limit=1.0
    )
    cpu_envs = [composer.Environment(_GearedLift(), random_state=seed) for seed in SEEDS]
    compiled_acc0 = mjcf.Physics.from_mjcf_model(
        _GearedLift().root_entity.mjcf_model
    ).model.ptr.actuator_acc0[0]
    model = batch_env.physics.model
    batch_env.reset()
    for world, env in enumerate(cpu_envs):
        env.reset()
        cpu_model = env.physics.model.ptr
        for field in ("actuator_gear", "actuator_acc0"):
            expected = np.float32(getattr(cpu_model, field))
            np.testing.assert_array_equal(getattr(model, field)[world], expected, err_msg=field)
    # The actuator drives one hinge: its acceleration per unit force scales with the gear
    # (compiled as 1).
    np.testing.assert_allclose(
        model.actuator_acc0[:, 0] / compiled_acc0, model.actuator_gear[:, 0, 0], rtol=1e-5
    )
    before = model.actuator_acc0.copy()
    # World 0 ends its episode at the next step and starts the next one at the step after.
    steps = batch_env.episode_steps
    steps[0] = batch_env.max_episode_steps - 1
    batch_env.episode_steps = steps
    rest = np.zeros((len(SEEDS), *batch_env.action_spec().shape))
    batch_env.step(rest)
    step_types = batch_env.step(rest).step_type
    assert step_types.tolist() == [0, 1, 1]  # FIRST, MID, MID
    after = model.actuator_acc0
    np.testing.assert_array_equal(after[1:], before[1:])
    cpu_envs[0].reset()
    np.testing.assert_array_equal(after[0], np.float32(cpu_envs[0].physics.model.ptr.actuator_acc0))
    assert not np.array_equal(after[0], before[0])
    batch_env.close()
