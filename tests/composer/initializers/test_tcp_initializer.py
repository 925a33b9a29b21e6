"""Tests for composer.initializers.ToolCenterPointInitializer on a 6-DOF arm with a hand."""

import mujoco
import numpy as np
import pytest

import composer
import mjcf
from composer.initializers import ToolCenterPointInitializer
from composer.variation import deterministic

# (joint axis, link length); the first joint sits at the base, each later one at the end of
# the previous link.
_LINKS = [
    ("0 0 1", 0.2),
    ("0 1 0", 0.4),
    ("0 1 0", 0.35),
    ("0 0 1", 0.05),
    ("0 1 0", 0.05),
    ("0 0 1", 0.03),
]
_LIMITED = {"joint_2": (-2.5, 2.5), "joint_3": (-2.8, 2.8), "joint_5": (-2.5, 2.5)}


class _Arm(composer.Entity):
    def _build(self):
        self._model = mjcf.RootElement(model="arm")
        parent, offset = self._model.worldbody, [0, 0, 0]
        self._joints = []
        for i, (axis, length) in enumerate(_LINKS, start=1):
            body = parent.add("body", name=f"link_{i}", pos=offset)
            joint = body.add("joint", name=f"joint_{i}", type="hinge", axis=axis)
            if joint.name in _LIMITED:
                joint.set_attributes(limited="true", range=_LIMITED[joint.name])
            self._joints.append(joint)
            body.add("geom", type="capsule", fromto=[0, 0, 0, 0, 0, length], size=[0.02])
            parent, offset = body, [0, 0, length]
        self._wrist_site = parent.add("site", name="wrist", pos=offset)

    @property
    def mjcf_model(self):
        return self._model

    @property
    def joints(self):
        return self._joints

    @property
    def wrist_site(self):
        return self._wrist_site


class _Hand(composer.Entity):
    def _build(self):
        self._model = mjcf.RootElement(model="hand")
        self._model.worldbody.add("geom", type="box", size=[0.03, 0.03, 0.02], pos=[0, 0, 0.02])
        self._tcp = self._model.worldbody.add("site", name="tcp", pos=[0, 0, 0.08])

    @property
    def mjcf_model(self):
        return self._model

    @property
    def tool_center_point(self):
        return self._tcp


class _Ball(composer.Entity):
    def _build(self):
        self._model = mjcf.RootElement(model="ball")
        self._model.worldbody.add("geom", type="sphere", size=[0.1])

    @property
    def mjcf_model(self):
        return self._model


OBSTACLE_CENTRE = np.array([0.5, 0.0, 0.3])
FREE_TARGET = np.array([-0.3, 0.3, 0.6])


def _scene(obstacle=False, free_ball_at=None):
    arena = composer.Arena()
    if obstacle:
        arena.mjcf_model.worldbody.add(
            "geom", name="obstacle", type="box", size=[0.1, 0.1, 0.1], pos=OBSTACLE_CENTRE
        )
    arm, hand = _Arm(), _Hand()
    arm.attach(hand, attach_site=arm.wrist_site)
    arena.attach(arm)
    if free_ball_at is not None:
        ball = _Ball()
        arena.add_free_entity(ball)
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    if free_ball_at is not None:
        ball.set_pose(physics, position=free_ball_at)
    physics.forward()
    return arm, hand, physics


def _tcp_pose(physics, hand):
    site = physics.bind(hand.tool_center_point)
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.asarray(site.xmat, dtype=np.float64).ravel())
    return np.array(site.xpos), quat


def _qpos(physics, arm):
    return np.array(physics.bind(arm.joints).qpos)


def test_places_the_tool_centre_point_at_the_target_pose():
    arm, hand, physics = _scene()
    down = np.array([0.0, np.sqrt(0.5), np.sqrt(0.5), 0.0])
    initializer = ToolCenterPointInitializer(hand, arm, position=FREE_TARGET, quaternion=down)
    initializer.initialize_episode(physics, np.random.RandomState(0))
    position, quat = _tcp_pose(physics, hand)
    np.testing.assert_allclose(position, FREE_TARGET, atol=1e-4)
    assert abs(quat @ down) == pytest.approx(1.0, abs=1e-6)


def test_solution_respects_joint_ranges():
    # Unlimited hinges end in [0, 2*pi), the range dm_control's arms sample them from.
    arm, hand, physics = _scene()
    initializer = ToolCenterPointInitializer(hand, arm, position=[0.4, -0.2, 0.4])
    for seed in range(3):
        initializer.initialize_episode(physics, np.random.RandomState(seed))
        qpos = _qpos(physics, arm)
        for joint, value in zip(arm.joints, qpos):
            low, high = _LIMITED.get(joint.name, (0.0, 2 * np.pi))
            assert low <= value < high


def test_unreachable_target_raises_and_restores_the_arm():
    arm, hand, physics = _scene()
    physics.bind(arm.joints).qpos = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6]
    initializer = ToolCenterPointInitializer(
        hand, arm, position=[3.0, 0.0, 0.5], max_ik_attempts=2, max_rejection_samples=2
    )
    with pytest.raises(composer.EpisodeInitializationError, match="after 2 sampled poses"):
        initializer.initialize_episode(physics, np.random.RandomState(0))
    np.testing.assert_allclose(_qpos(physics, arm), [0.1, 0.2, 0.3, 0.4, 0.5, 0.6])


def test_pose_that_puts_the_hand_into_a_static_obstacle_is_rejected():
    arm, hand, physics = _scene(obstacle=True)
    positions = deterministic.Sequence([OBSTACLE_CENTRE, FREE_TARGET])
    initializer = ToolCenterPointInitializer(hand, arm, position=positions)
    initializer.initialize_episode(physics, np.random.RandomState(0))
    np.testing.assert_allclose(_tcp_pose(physics, hand)[0], FREE_TARGET, atol=1e-4)


def test_ignore_collisions_accepts_a_pose_inside_an_obstacle():
    arm, hand, physics = _scene(obstacle=True)
    positions = deterministic.Sequence([OBSTACLE_CENTRE, FREE_TARGET])
    initializer = ToolCenterPointInitializer(hand, arm, position=positions, ignore_collisions=True)
    initializer.initialize_episode(physics, np.random.RandomState(0))
    np.testing.assert_allclose(_tcp_pose(physics, hand)[0], OBSTACLE_CENTRE, atol=1e-4)


def test_touching_a_free_prop_is_allowed():
    target = np.array([0.3, 0.3, 0.5])
    arm, hand, physics = _scene(free_ball_at=target)
    initializer = ToolCenterPointInitializer(hand, arm, position=target, max_rejection_samples=1)
    initializer.initialize_episode(physics, np.random.RandomState(0))
    np.testing.assert_allclose(_tcp_pose(physics, hand)[0], target, atol=1e-4)


def test_without_a_hand_the_wrist_site_is_placed():
    arm, _, physics = _scene()
    ToolCenterPointInitializer(None, arm, position=FREE_TARGET).initialize_episode(
        physics, np.random.RandomState(0)
    )
    np.testing.assert_allclose(physics.bind(arm.wrist_site).xpos, FREE_TARGET, atol=1e-4)


def test_zero_attempts_are_rejected_at_construction():
    with pytest.raises(ValueError, match="max_ik_attempts and max_rejection_samples must be >= 1"):
        ToolCenterPointInitializer(None, None, position=[0, 0, 0], max_ik_attempts=0)


def test_a_recompiled_model_with_a_new_obstacle_is_seen_by_an_initializer_used_before():
    # The initializer works out the arm's geoms once per compiled model; adding a geom in
    # front of the arm's shifts every geom id, and the obstacle must count from then on.
    arena = composer.Arena()
    arm, hand = _Arm(), _Hand()
    arm.attach(hand, attach_site=arm.wrist_site)
    arena.attach(arm)
    positions = deterministic.Sequence([OBSTACLE_CENTRE, OBSTACLE_CENTRE, FREE_TARGET])
    initializer = ToolCenterPointInitializer(hand, arm, position=positions)
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    initializer.initialize_episode(physics, np.random.RandomState(0))
    np.testing.assert_allclose(_tcp_pose(physics, hand)[0], OBSTACLE_CENTRE, atol=1e-4)
    arena.mjcf_model.worldbody.insert(
        "geom", 0, name="obstacle", type="box", size=[0.1, 0.1, 0.1], pos=OBSTACLE_CENTRE
    )
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    initializer.initialize_episode(physics, np.random.RandomState(0))
    np.testing.assert_allclose(_tcp_pose(physics, hand)[0], FREE_TARGET, atol=1e-4)
