"""Tests for composer.initializers.PropPlacer."""

import mujoco
import numpy as np
import pytest

import composer
import mjcf
from composer.initializers import PropPlacer
from composer.variation import deterministic, distributions, noises, rotations

HALF_SIZE = 0.05


class _Box(composer.Entity):
    def _build(self, name, half_size=HALF_SIZE):
        self._model = mjcf.RootElement(model=name)
        self._model.worldbody.add("geom", name="geom", type="box", size=[half_size] * 3, mass=0.1)

    @property
    def mjcf_model(self):
        return self._model


class _Counting(distributions.Uniform):
    """A Uniform that counts how often it is sampled."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.calls = 0

    def __call__(self, *args, **kwargs):
        self.calls += 1
        return super().__call__(*args, **kwargs)


def _scene(num_props, obstacle=False, pendulum=False):
    arena = composer.Arena()
    arena.mjcf_model.worldbody.add("geom", name="floor", type="plane", size=[2, 2, 0.1])
    if obstacle:
        arena.mjcf_model.worldbody.add(
            "geom", name="obstacle", type="box", size=[0.3, 0.3, 0.3], pos=[2.0, 0.0, 0.3]
        )
    if pendulum:
        body = arena.mjcf_model.worldbody.add("body", name="pendulum", pos=[-1.0, 0.0, 1.0])
        body.add("joint", name="swing", type="hinge", axis=[0, 1, 0])
        body.add("geom", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.02], mass=1)
    props = [_Box(f"box{i}") for i in range(num_props)]
    for prop in props:
        arena.add_free_entity(prop)
    return arena, props, mjcf.Physics.from_mjcf_model(arena.mjcf_model)


def _penetrating_contacts_with(physics, props):
    """Contacts with negative distance that involve a geom of one of `props`."""
    physics.forward()
    names = {f"{prop.mjcf_model.model}/geom" for prop in props}
    model, data = physics.model.ptr, physics.data.ptr
    found = []
    for i in range(data.ncon):
        contact = data.contact[i]
        pair = {model.geom(contact.geom1).name, model.geom(contact.geom2).name}
        if contact.dist < 0 and pair & names:
            found.append(pair)
    return found


CROWDED_REGION = distributions.Uniform([-0.25, -0.25, 0.1], [0.25, 0.25, 0.1])


def test_crowded_scene_is_placed_without_interpenetration():
    _, props, physics = _scene(10)
    position = _Counting([-0.25, -0.25, 0.1], [0.25, 0.25, 0.1])
    placer = PropPlacer(
        props,
        position=position,
        quaternion=rotations.UniformQuaternion(),
        max_attempts_per_prop=300,
    )
    for seed in range(3):
        placer.initialize_episode(physics, np.random.RandomState(seed))
        assert _penetrating_contacts_with(physics, props) == []
    assert position.calls > 3 * len(props)  # crowded: some samples were rejected


def test_props_are_placed_inside_the_sampled_region():
    _, props, physics = _scene(6)
    PropPlacer(props, position=CROWDED_REGION, max_attempts_per_prop=200).initialize_episode(
        physics, np.random.RandomState(0)
    )
    positions = np.array([prop.get_pose(physics)[0] for prop in props])
    assert np.all(np.abs(positions[:, :2]) <= 0.25)
    np.testing.assert_allclose(positions[:, 2], 0.1)


def test_placement_is_reproducible_from_the_seed():
    _, props, physics = _scene(5)
    placer = PropPlacer(props, position=CROWDED_REGION, max_attempts_per_prop=200)

    def poses(seed):
        placer.initialize_episode(physics, np.random.RandomState(seed))
        return np.array([np.concatenate(prop.get_pose(physics)) for prop in props])

    first = poses(7)
    np.testing.assert_array_equal(first, poses(7))
    assert not np.array_equal(first, poses(8))


def test_impossible_scene_raises_after_the_stated_attempts():
    _, props, physics = _scene(2)
    position = _Counting([0.0, 0.0, 0.1], [0.0, 0.0, 0.1])
    placer = PropPlacer(props, position=position, max_attempts_per_prop=7)
    with pytest.raises(composer.EpisodeInitializationError, match="'box1' in 7 attempts"):
        placer.initialize_episode(physics, np.random.RandomState(0))
    assert position.calls == 1 + 7  # box0 succeeds at once, box1 fails 7 times


def test_region_inside_a_static_obstacle_raises():
    _, props, physics = _scene(1, obstacle=True)
    placer = PropPlacer(props, position=distributions.Uniform([1.9, -0.1, 0.2], [2.1, 0.1, 0.4]))
    with pytest.raises(composer.EpisodeInitializationError, match="no non-penetrating pose"):
        placer.initialize_episode(physics, np.random.RandomState(0))


def test_no_props_raises_episode_initialization_error():
    _, _, physics = _scene(0)
    with pytest.raises(composer.EpisodeInitializationError, match="no props"):
        PropPlacer([], position=[0, 0, 0.1]).initialize_episode(physics, np.random.RandomState(0))


def test_contact_parameters_are_restored_after_success_and_failure():
    _, props, physics = _scene(3)
    model = physics.model.ptr
    contype, conaffinity = model.geom_contype.copy(), model.geom_conaffinity.copy()
    PropPlacer(props, position=CROWDED_REGION, max_attempts_per_prop=200).initialize_episode(
        physics, np.random.RandomState(0)
    )
    np.testing.assert_array_equal(model.geom_contype, contype)
    with pytest.raises(composer.EpisodeInitializationError):
        PropPlacer(props, position=[0.0, 0.0, 0.1]).initialize_episode(
            physics, np.random.RandomState(0)
        )
    np.testing.assert_array_equal(model.geom_contype, contype)
    np.testing.assert_array_equal(model.geom_conaffinity, conaffinity)


def test_ignore_collisions_accepts_overlapping_poses():
    _, props, physics = _scene(2)
    placer = PropPlacer(props, position=[0.0, 0.0, 0.1], ignore_collisions=True)
    placer.initialize_episode(physics, np.random.RandomState(0))
    assert len(_penetrating_contacts_with(physics, props)) > 0


def test_sequence_gives_each_prop_its_own_pose():
    _, props, physics = _scene(2)
    positions = [[0.5, 0.0, 0.1], [-0.5, 0.0, 0.1]]
    placer = PropPlacer(props, position=deterministic.Sequence(positions))
    placer.initialize_episode(physics, np.random.RandomState(0))
    np.testing.assert_allclose([prop.get_pose(physics)[0] for prop in props], positions)


def test_relative_variation_perturbs_the_pose_before_placement():
    _, props, physics = _scene(1)
    props[0].set_pose(physics, position=[0.3, 0.3, 0.2])
    noise = noises.Additive(distributions.Uniform(-0.01, 0.01))
    PropPlacer(props, position=noise).initialize_episode(physics, np.random.RandomState(0))
    position = props[0].get_pose(physics)[0]
    assert np.all(np.abs(position - [0.3, 0.3, 0.2]) <= 0.01)
    assert not np.array_equal(position, [0.3, 0.3, 0.2])


def test_settling_drops_props_to_rest_and_restores_time():
    _, props, physics = _scene(3)
    physics.data.time = 1.5
    placer = PropPlacer(
        props,
        position=distributions.Uniform([-0.5, -0.5, 0.3], [0.5, 0.5, 0.3]),
        settle_physics=True,
        max_attempts_per_prop=100,
    )
    placer.initialize_episode(physics, np.random.RandomState(0))
    heights = [prop.get_pose(physics)[0][2] for prop in props]
    np.testing.assert_allclose(heights, HALF_SIZE, atol=2e-3)
    assert physics.data.time == 1.5


def test_settling_holds_joints_that_are_not_props():
    _, props, physics = _scene(1, pendulum=True)
    swing = mujoco.mj_name2id(physics.model.ptr, mujoco.mjtObj.mjOBJ_JOINT, "swing")
    physics.data.qpos[swing] = 0.4
    placer = PropPlacer(props, position=[0.0, 0.0, 0.3], settle_physics=True)
    placer.initialize_episode(physics, np.random.RandomState(0))
    assert physics.data.qpos[swing] == 0.4
    assert props[0].get_pose(physics)[0][2] == pytest.approx(HALF_SIZE, abs=2e-3)


def test_settle_failure_raises_when_requested():
    _, props, physics = _scene(1)
    placer = PropPlacer(
        props,
        position=[0.0, 0.0, 1.0],
        settle_physics=True,
        max_settle_physics_time=0.01,
        raise_exception_on_settle_failure=True,
    )
    with pytest.raises(composer.EpisodeInitializationError, match="did not come to rest"):
        placer.initialize_episode(physics, np.random.RandomState(0))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"max_attempts_per_prop": 0}, "max_attempts_per_prop must be >= 1, got 0"),
        ({"max_settle_physics_attempts": 0}, "max_settle_physics_attempts must be >= 1"),
        ({"min_settle_physics_time": 3.0}, "min_settle_physics_time <= max_settle_physics_time"),
    ],
)
def test_bad_arguments_are_rejected_at_construction(kwargs, message):
    with pytest.raises(ValueError, match=message):
        PropPlacer([], position=[0, 0, 0], **kwargs)
