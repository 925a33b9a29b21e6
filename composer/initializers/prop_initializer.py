"""PropPlacer: rejection-samples prop poses until no prop penetrates anything."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from absl import logging

import mjcf
from composer import initializer
from composer.environment import EpisodeInitializationError
from composer.initializers import _kinematic_tree
from composer.variation import base, rotations

#: The message of a failed placement (dm_control's tests format it with these keys).
_REJECTION_SAMPLING_FAILED = (
    "PropPlacer: no non-penetrating pose found for prop {model_name!r} in {max_attempts} "
    "attempts; sample from a wider region, raise max_attempts_per_prop or set "
    "ignore_collisions=True"
)


class PropPlacer(initializer.Initializer):
    """Places props at sampled poses such that no prop penetrates anything.

    Props are placed one at a time, in order. Props not yet placed do not collide while
    earlier ones are placed; each sampled pose is accepted when no contact with negative
    distance involves the prop being placed. `position` and `quaternion` are constants or
    variations, evaluated with the prop's pose before placement as `initial_value` and the
    last sampled pose as `current_value` (use `variation.deterministic.Sequence` to give each
    prop its own fixed pose).

    Optionally the physics is then stepped until the props come to rest, with every joint
    that does not belong to a prop held still, and the simulation time restored afterwards.
    """

    def __init__(
        self,
        props: Sequence,
        position,
        quaternion=rotations.IDENTITY_QUATERNION,
        ignore_collisions: bool = False,
        max_attempts_per_prop: int = 20,
        settle_physics: bool = False,
        min_settle_physics_time: float = 0.0,
        max_settle_physics_time: float = 2.0,
        max_qvel_tol: float = 1e-3,
        max_qacc_tol: float = 1e-2,
        *,
        max_settle_physics_attempts: int = 1,
        raise_exception_on_settle_failure: bool = False,
    ):
        """Initializes this PropPlacer.

        Args:
          props: The `composer.Entity` props to place, in placement order.
          position: A Cartesian position (3,) or a variation producing one.
          quaternion: A unit quaternion (w, x, y, z) or a variation producing one.
          ignore_collisions: If True, the first sampled pose of each prop is accepted.
          max_attempts_per_prop: Poses sampled per prop before giving up.
          settle_physics: Whether to step the physics until the props are at rest.
          min_settle_physics_time: Simulated seconds to step at least when settling.
          max_settle_physics_time: Simulated seconds to step at most per settling attempt.
          max_qvel_tol: Props are at rest when every prop joint velocity is below this...
          max_qacc_tol: ...and every prop joint acceleration is below this.
          max_settle_physics_attempts: Times to re-place and settle when settling fails.
          raise_exception_on_settle_failure: Raise `EpisodeInitializationError` (instead of
            logging a warning) when the props have not settled.

        Raises:
          ValueError: For a non-positive attempt count or inconsistent settling times.
        """
        if max_attempts_per_prop < 1:
            raise ValueError(
                f"PropPlacer: max_attempts_per_prop must be >= 1, got {max_attempts_per_prop}"
            )
        if max_settle_physics_attempts < 1:
            raise ValueError(
                "PropPlacer: max_settle_physics_attempts must be >= 1, "
                f"got {max_settle_physics_attempts}"
            )
        if not 0 <= min_settle_physics_time <= max_settle_physics_time:
            raise ValueError(
                "PropPlacer: expected 0 <= min_settle_physics_time <= max_settle_physics_time, "
                f"got {min_settle_physics_time} and {max_settle_physics_time}"
            )
        self._props = list(props)
        self._position = position
        self._quaternion = quaternion
        self._ignore_collisions = ignore_collisions
        self._max_attempts_per_prop = max_attempts_per_prop
        self._settle_physics = settle_physics
        self._min_settle_physics_time = min_settle_physics_time
        self._max_settle_physics_time = max_settle_physics_time
        self._max_qvel_tol = max_qvel_tol
        self._max_qacc_tol = max_qacc_tol
        self._max_settle_physics_attempts = max_settle_physics_attempts
        self._raise_exception_on_settle_failure = raise_exception_on_settle_failure

    def __call__(self, physics, random_state, ignore_contacts_with_entities=None) -> None:
        """Places the props, then settles them if requested.

        Args:
          physics: An `mjcf.Physics`.
          random_state: A `np.random.RandomState`.
          ignore_contacts_with_entities: Entities whose contacts are disabled while placing,
            e.g. props that another initializer will place afterwards.

        Raises:
          EpisodeInitializationError: If there are no props, or a prop has no non-penetrating
            pose among `max_attempts_per_prop` samples, or (when requested) the props do not
            settle.
        """
        if not self._props:
            raise EpisodeInitializationError("PropPlacer: there are no props to place")
        model = physics.model.ptr
        prop_geoms = []
        for prop in self._props:
            bodies = _kinematic_tree.entity_body_mask(model, prop)
            prop_geoms.append(np.flatnonzero(bodies[model.geom_bodyid]))
        ignored_geoms = [
            np.flatnonzero(_kinematic_tree.entity_body_mask(model, entity)[model.geom_bodyid])
            for entity in (ignore_contacts_with_entities or ())
        ]
        for attempt in range(self._max_settle_physics_attempts):
            self._place_all(physics, random_state, prop_geoms, ignored_geoms)
            if not self._settle_physics or self._settle(physics):
                return
            logging.info("PropPlacer: props did not settle (attempt %d)", attempt + 1)
        message = (
            f"PropPlacer: props did not come to rest within {self._max_settle_physics_time} s "
            f"of simulated time in {self._max_settle_physics_attempts} attempt(s)"
        )
        if self._raise_exception_on_settle_failure:
            raise EpisodeInitializationError(message)
        logging.warning(message)

    def _place_all(self, physics, random_state, prop_geoms, ignored_geoms) -> None:
        # The physics is brought forward exactly where dm_control's placer does it (once
        # with every placed geom out of collision detection, then after each sampled pose,
        # and not after the ignored entities collide again), since the step that settles the
        # props continues from the last forward's results.
        model = physics.model.ptr
        # The sorted distinct geom ids, through a mask: np.unique would import numpy.ma on
        # first use (tens of milliseconds on an episode's first reset).
        is_disabled = np.zeros(model.ngeom, dtype=bool)
        is_disabled[np.concatenate(prop_geoms + ignored_geoms)] = True
        disabled = np.flatnonzero(is_disabled)
        saved_contype = model.geom_contype[disabled].copy()
        saved_conaffinity = model.geom_conaffinity[disabled].copy()
        # Props not placed yet (and ignored entities) take no part in collision detection.
        model.geom_contype[disabled] = 0
        model.geom_conaffinity[disabled] = 0
        try:
            try:
                physics.forward()
            except mjcf.PhysicsError as error:
                raise mjcf.PhysicsError(
                    "PropPlacer: physics.forward() failed with every prop out of collision "
                    f"detection: {error}"
                ) from error
            for prop, geoms in zip(self._props, prop_geoms):
                restore = np.isin(disabled, geoms)
                model.geom_contype[disabled[restore]] = saved_contype[restore]
                model.geom_conaffinity[disabled[restore]] = saved_conaffinity[restore]
                self._place(physics, random_state, prop, geoms)
        finally:
            model.geom_contype[disabled] = saved_contype
            model.geom_conaffinity[disabled] = saved_conaffinity

    def _place(self, physics, random_state, prop, geoms) -> None:
        model = physics.model.ptr
        data = physics.data.ptr
        is_prop_geom = np.zeros(model.ngeom, dtype=bool)
        is_prop_geom[geoms] = True
        # Copies: get_pose may return views of qpos, which set_pose overwrites.
        initial_position, initial_quaternion = (np.array(v) for v in prop.get_pose(physics))
        position, quaternion = initial_position, initial_quaternion
        for _ in range(self._max_attempts_per_prop):
            position = base.evaluate(self._position, initial_position, position, random_state)
            quaternion = base.evaluate(
                self._quaternion, initial_quaternion, quaternion, random_state
            )
            prop.set_pose(physics, position=position, quaternion=quaternion)
            try:
                physics.forward()
            except mjcf.PhysicsError:
                # A pose that overflows the contact buffer is a colliding pose.
                continue
            if self._ignore_collisions:
                return
            geom1, geom2 = _kinematic_tree.penetrating_geom_pairs(data)
            if not np.any(is_prop_geom[geom1] | is_prop_geom[geom2]):
                return
        raise EpisodeInitializationError(
            _REJECTION_SAMPLING_FAILED.format(
                model_name=prop.mjcf_model.model, max_attempts=self._max_attempts_per_prop
            )
        )

    def _settle(self, physics) -> bool:
        """Steps until the props rest; returns whether they did. Restores the time."""
        model = physics.model.ptr
        data = physics.data.ptr
        prop_bodies = np.zeros(model.nbody, dtype=bool)
        for prop in self._props:
            prop_bodies |= _kinematic_tree.entity_body_mask(model, prop)
        is_prop_joint = prop_bodies[model.jnt_bodyid]
        _, prop_dofs = _kinematic_tree.joint_address_ranges(model, np.flatnonzero(is_prop_joint))
        other_qpos, other_dofs = _kinematic_tree.joint_address_ranges(
            model, np.flatnonzero(~is_prop_joint)
        )
        held_qpos = data.qpos[other_qpos].copy()
        held_qvel = data.qvel[other_dofs].copy()
        start_time = data.time
        settled = False
        while data.time - start_time < self._max_settle_physics_time:
            physics.step()
            if other_qpos.size:
                data.qpos[other_qpos] = held_qpos
                data.qvel[other_dofs] = held_qvel
                # The held joints moved back, so accelerations are recomputed before they
                # are read (dm_control's bindings do the same, and the next step goes on
                # from this forward's results).
                physics.forward()
            # np.abs(...).max(): np.max's dispatch costs more than the few numbers it reads.
            max_qvel = np.abs(data.qvel[prop_dofs]).max() if prop_dofs.size else 0.0
            max_qacc = np.abs(data.qacc[prop_dofs]).max() if prop_dofs.size else 0.0
            if (
                max_qvel < self._max_qvel_tol
                and max_qacc < self._max_qacc_tol
                and data.time - start_time > self._min_settle_physics_time
            ):
                settled = True
                break
        data.time = start_time
        return settled
