"""ToolCenterPointInitializer: puts a hand's tool-centre point at a sampled pose by IK."""

from __future__ import annotations

import functools
import weakref

import mujoco
import numpy as np

from composer import initializer
from composer.environment import EpisodeInitializationError
from composer.initializers import _kinematic_tree
from composer.utils import inverse_kinematics
from composer.variation import base

# Orientation of a tool-centre point pointing straight down (its z axis along world -z).
DOWN_QUATERNION = np.array([0.0, np.sqrt(0.5), np.sqrt(0.5), 0.0])

# Weight of the orientation error (radians) relative to the position error (metres) in IK.
_IK_ROT_WEIGHT = 2.0

#: The message when no pose works (dm_control's tests format it with these keys).
_REJECTION_SAMPLING_FAILED = (
    "ToolCenterPointInitializer: no collision-free IK solution after "
    "{max_rejection_samples} sampled poses with up to {max_ik_attempts} IK attempts each"
)

_HINGE = int(mujoco.mjtJoint.mjJNT_HINGE)
_SCALAR_JOINTS = (_HINGE, int(mujoco.mjtJoint.mjJNT_SLIDE))

# Geom groups, and which pairs of them make a contact count as a collision: the arm with the
# arm, the hand or static geometry; the hand with the arm or static geometry (not with
# itself). Free-floating bodies (props) are in no group, so touching them is allowed.
_ARM, _HAND, _STATIC = 0, 1, 2
_RELEVANT = np.array(
    [
        [True, True, True],
        [True, False, True],
        [True, True, False],
    ]
)


class ToolCenterPointInitializer(initializer.Initializer):
    """Moves an arm's joints so that the hand's tool-centre point reaches a sampled pose.

    For each sampled target pose, inverse kinematics is tried up to `max_ik_attempts` times,
    from the current joint configuration first and then from random ones within the joint
    ranges (unlimited hinges in [0, 2*pi)), as dm_control's `RobotArm.set_site_to_xpos`
    does; an arm that has that method does it itself. A solution is rejected if a joint
    cannot be brought within its range or, unless `ignore_collisions`, if it creates a
    relevant collision: between two arm geoms, between the arm and the hand, or between the
    arm or hand and anything that is not free-floating (so touching a free prop is allowed).
    """

    def __init__(
        self,
        hand,
        arm,
        position,
        quaternion=DOWN_QUATERNION,
        ignore_collisions: bool = False,
        max_ik_attempts: int = 10,
        max_rejection_samples: int = 10,
    ):
        """Initializes this ToolCenterPointInitializer.

        Args:
          hand: The hand entity whose `tool_center_point` site is placed, or None to place the
            arm's `wrist_site`.
          arm: The arm entity; its `joints` (a sequence of MJCF joints) are moved.
          position: A Cartesian position (3,) or a variation producing one.
          quaternion: A unit quaternion (w, x, y, z) or a variation producing one.
          ignore_collisions: If True, any IK solution is accepted.
          max_ik_attempts: IK attempts per sampled pose.
          max_rejection_samples: Target poses sampled before giving up.
        """
        if max_ik_attempts < 1 or max_rejection_samples < 1:
            raise ValueError(
                "ToolCenterPointInitializer: max_ik_attempts and max_rejection_samples must be "
                f">= 1, got {max_ik_attempts} and {max_rejection_samples}"
            )
        self._hand = hand
        self._arm = arm
        self._position = position
        self._quaternion = quaternion
        self._ignore_collisions = ignore_collisions
        self._max_ik_attempts = max_ik_attempts
        self._max_rejection_samples = max_rejection_samples
        # (weak reference to the model, joint names, geom groups) of the last model seen
        # (see `_structure`).
        self._cached_structure: tuple[weakref.ref, list[str], np.ndarray] | None = None

    def initialize_episode(self, physics, random_state) -> None:
        """Sets the arm's joints (see the class docstring)."""
        self(physics, random_state)

    def __call__(self, physics, random_state) -> None:
        """Sets the arm's joints so that the tool-centre point is at a sampled pose.

        Each sampled pose takes the draws of `position`, then of `quaternion`, then those
        of the arm's IK attempts (`set_site_to_xpos`), in dm_control's order, so that a
        seed gives dm_control's episode.

        Raises:
          EpisodeInitializationError: If no sampled pose had an acceptable IK solution.
        """
        site = self._hand.tool_center_point if self._hand is not None else self._arm.wrist_site
        data = physics.data.ptr
        model = physics.model.ptr
        joint_names, geom_groups = self._structure(model)
        joints = _ArmJoints(model, joint_names)
        initial_qpos = data.qpos[joints.qpos].copy()
        # A dm_control arm (`RobotArm`) places the site itself; others get the same method.
        set_site_to_xpos = getattr(self._arm, "set_site_to_xpos", None)
        if set_site_to_xpos is None:
            set_site_to_xpos = functools.partial(_set_site_to_xpos, joints, joint_names)

        for _ in range(self._max_rejection_samples):
            target_pos = base.evaluate(self._position, random_state=random_state)
            target_quat = base.evaluate(self._quaternion, random_state=random_state)
            success = set_site_to_xpos(
                physics=physics,
                random_state=random_state,
                site=site,
                target_pos=target_pos,
                target_quat=target_quat,
                max_ik_attempts=self._max_ik_attempts,
            )
            if success:
                physics.forward()
                if self._ignore_collisions or not _has_relevant_collision(data, geom_groups):
                    return
            data.qpos[joints.qpos] = initial_qpos
        physics.forward()
        raise EpisodeInitializationError(
            _REJECTION_SAMPLING_FAILED.format(
                max_rejection_samples=self._max_rejection_samples,
                max_ik_attempts=self._max_ik_attempts,
            )
            + f" (tool center point {site.full_identifier!r})"
        )

    def _structure(self, model: mujoco.MjModel) -> tuple[list[str], np.ndarray]:
        """The arm's joint names and each geom's group in `model`, worked out once per
        compiled model: both follow from the model's tree, which only a recompile (a new
        `MjModel`) changes. Joint ranges, which change in place, are read at every call."""
        cached = self._cached_structure
        if cached is None or cached[0]() is not model:
            joint_names = [joint.full_identifier for joint in self._arm.joints]
            cached = (weakref.ref(model), joint_names, self._geom_groups(model))
            self._cached_structure = cached
        return cached[1], cached[2]

    def __getstate__(self) -> dict:
        # A copy (copy.deepcopy) starts without the cache, which refers to a compiled model.
        return {**self.__dict__, "_cached_structure": None}

    def _geom_groups(self, model: mujoco.MjModel) -> np.ndarray:
        """Returns each geom's group: _ARM, _HAND, _STATIC, or -1 for free-floating bodies."""
        arm_bodies = _kinematic_tree.entity_body_mask(model, self._arm)
        hand_bodies = np.zeros(model.nbody, dtype=bool)
        if self._hand is not None:
            hand_bodies = _kinematic_tree.entity_body_mask(model, self._hand)
        free_roots = model.jnt_bodyid[model.jnt_type == int(mujoco.mjtJoint.mjJNT_FREE)]
        free_bodies = np.isin(model.body_rootid, free_roots)
        geom_bodies = model.geom_bodyid
        groups = np.full(model.ngeom, -1)
        groups[~free_bodies[geom_bodies]] = _STATIC
        groups[arm_bodies[geom_bodies]] = _ARM
        groups[hand_bodies[geom_bodies]] = _HAND
        return groups


def _has_relevant_collision(data: mujoco.MjData, geom_groups: np.ndarray) -> bool:
    geom1, geom2 = _kinematic_tree.penetrating_geom_pairs(data)
    group1, group2 = geom_groups[geom1], geom_groups[geom2]
    known = (group1 >= 0) & (group2 >= 0)
    return bool(np.any(_RELEVANT[group1[known], group2[known]]))


class _ArmJoints:
    """The arm's scalar (hinge or slide) joints: their qpos indices, types and ranges."""

    def __init__(self, model: mujoco.MjModel, names: list[str]):
        ids = []
        for name in names:
            joint_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
            if joint_id < 0:
                raise ValueError(
                    f"ToolCenterPointInitializer: arm joint {name!r} is not in the model"
                )
            if model.jnt_type[joint_id] not in _SCALAR_JOINTS:
                raise ValueError(
                    f"ToolCenterPointInitializer: arm joint {name!r} must be a hinge or slide joint"
                )
            if model.jnt_type[joint_id] != _HINGE and not model.jnt_limited[joint_id]:
                raise ValueError(
                    f"ToolCenterPointInitializer: arm joint {name!r} is an unlimited slide "
                    "joint, which has no range to sample positions from; give it a range"
                )
            ids.append(joint_id)
        self.qpos = model.jnt_qposadr[ids]
        self.limited = model.jnt_limited[ids].astype(bool)
        self.low, self.high = model.jnt_range[ids].T

    def sampling_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """The range each joint is sampled in: its own, or [0, 2*pi) for unlimited hinges."""
        low = np.where(self.limited, self.low, 0.0)
        high = np.where(self.limited, self.high, 2.0 * np.pi)
        return low, high

    def randomize(self, qpos: np.ndarray, random_state) -> None:
        """Sets each joint to a position drawn uniformly within `sampling_bounds`, in one
        draw for all joints."""
        qpos[self.qpos] = random_state.uniform(*self.sampling_bounds())

    def bring_into_range(self, qpos: np.ndarray) -> bool:
        """Shifts each joint, in order, by whole turns until it is within its sampling
        bounds; returns False at the first joint that no whole turn brings within them
        (that joint and those after it are left as they are)."""
        two_pi = 2.0 * np.pi
        for address, low, high in zip(self.qpos, *self.sampling_bounds()):
            # Whole turns one at a time, as dm_control shifts them, for the same rounding.
            while qpos[address] >= high:
                qpos[address] -= two_pi
            while qpos[address] < low:
                qpos[address] += two_pi
                if qpos[address] > high:
                    return False
        return True


def _set_site_to_xpos(
    joints: _ArmJoints,
    joint_names: list[str],
    *,
    physics,
    random_state,
    site,
    target_pos,
    target_quat,
    max_ik_attempts: int,
) -> bool:
    """dm_control's `RobotArm.set_site_to_xpos` for arms that lack it: IK from the current
    joints, then, after each failed attempt while more than one is allowed, from joints
    drawn within their sampling bounds; returns whether an attempt succeeded."""
    qpos = physics.data.ptr.qpos
    success = False
    for _ in range(max_ik_attempts):
        result = inverse_kinematics.qpos_from_site_pose(
            physics,
            site.full_identifier,
            target_pos=target_pos,
            target_quat=target_quat,
            joint_names=joint_names,
            rot_weight=_IK_ROT_WEIGHT,
            inplace=True,
        )
        success = result.success and joints.bring_into_range(qpos)
        if success or max_ik_attempts <= 1:
            break
        joints.randomize(qpos, random_state)
    return success
