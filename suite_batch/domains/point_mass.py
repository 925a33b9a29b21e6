"""Point mass's `PointMass` batched: its easy task and its hard one, whose episodes each
draw the actuators' directions (`wrap_prm`, a model field with a row per world)."""

import mujoco
import numpy as np

from suite_batch import rewards, tasks


class BatchPointMass(tasks.SuiteBatchTask):
    """`point_mass.PointMass` for every world: a gaussian reward for the mass's distance to
    the target (1 inside it, 0.1 at a target's radius outside), scaled by one for small
    controls (from 4/5 at full control to 1 at none)."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        geom = mujoco.mjtObj.mjOBJ_GEOM
        self._target = mujoco.mj_name2id(model, geom, "target")
        self._mass = mujoco.mj_name2id(model, geom, "pointmass")
        self._target_size = float(model.geom_size[self._target, 0])
        data = physics.data
        self._qpos, self._qvel = data.qpos, data.qvel
        self._geom_xpos, self._ctrl = data.geom_xpos, data.ctrl

    def get_observation(self) -> dict[str, np.ndarray]:
        return {"position": np.array(self._qpos), "velocity": np.array(self._qvel)}

    def get_reward(self) -> np.ndarray:
        xpos = self._geom_xpos
        mass_to_target = xpos[:, self._target] - xpos[:, self._mass]
        # The CPU's np.linalg.norm is the square root of np.dot (BLAS), which np.vecdot
        # matches row by row.
        distance = np.sqrt(np.vecdot(mass_to_target, mass_to_target))
        size = self._target_size
        near_target = rewards.tolerance(distance, (0, size), margin=size, scalar=True)
        control_reward = rewards.tolerance(
            self._ctrl, margin=1, value_at_margin=0, sigmoid="quadratic", scalar=False
        ).mean(axis=1)
        small_control = (control_reward + 4) / 5
        return near_target * small_control


tasks.register("dm_control.suite.point_mass.PointMass", BatchPointMass)
