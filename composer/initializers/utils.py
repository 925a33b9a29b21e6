"""Helpers for writing initializers: `JointStaticIsolator` keeps the other joints still."""

from __future__ import annotations

from collections.abc import Iterable

_JOINT_TAGS = ("joint", "freejoint")


class JointStaticIsolator:
    """Context manager that lets code change some joints and puts every other joint back.

    On construction it records the `qpos` and `qvel` of every joint of the joints' model
    (attached models included) that is not in `joints`; when the `with` block ends, normally
    or by an exception, it writes those values back. Inside the block anything may change
    the physics (set the given joints, run inverse kinematics, step it): afterwards the
    other joints are where they were when the isolator was made, not when the block began.

    Args:
      physics: The `mjcf.Physics` of the joints' model.
      joints: A joint element, or an iterable of joint elements, that may change.

    Raises:
      ValueError: If `joints` is empty, holds an element that is not a joint, or holds
        joints of different models.
    """

    def __init__(self, physics, joints):
        if not isinstance(joints, Iterable):
            joints = [joints]
        joints = list(joints)
        if not joints:
            raise ValueError("JointStaticIsolator: expected at least one joint, got none")
        for joint in joints:
            if getattr(joint, "tag", None) not in _JOINT_TAGS:
                raise ValueError(
                    f"JointStaticIsolator: expected joint elements, got {joint!r} "
                    f"in joints {joints!r}"
                )
        root_model = joints[0].root.root_model
        for joint in joints[1:]:
            if joint.root.root_model is not root_model:
                raise ValueError(
                    f"JointStaticIsolator: joints of different models: {joints[0]!r} and "
                    f"{joint!r} belong to {root_model.model!r} and "
                    f"{joint.root.root_model.model!r}"
                )
        isolated = set(map(id, joints))
        others = [j for j in root_model.find_all("joint") if id(j) not in isolated]
        self._others = physics.bind(others) if others else None
        if self._others is not None:
            self._qpos = self._others.qpos.copy()
            self._qvel = self._others.qvel.copy()

    def __enter__(self) -> JointStaticIsolator:
        return self

    def __exit__(self, exc_type, exc_value, traceback) -> None:
        if self._others is not None:
            self._others.qpos = self._qpos
            self._others.qvel = self._qvel
