"""Cartpole's `Balance` batched: its four benchmark tasks and the two- and three-pole ones."""

import mujoco
import numpy as np

from suite_batch import rewards, tasks

# Entries of a row-major 3x3 orientation matrix, as dm_control names its xmat columns.
_ZZ, _XZ = 8, 2


class BatchBalance(tasks.SuiteBatchTask):
    """`cartpole.Balance` for every world: a smooth or sparse reward for keeping the poles
    up (and, smooth, the cart centred, the control small and the poles slow)."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        slider = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, "slider")
        self._cart = int(model.jnt_qposadr[slider])
        self._sparse = bool(task._sparse)
        self._cart_range = type(task)._CART_RANGE
        self._angle_cosine_range = type(task)._ANGLE_COSINE_RANGE
        data = physics.data
        self._qpos, self._qvel = data.qpos, data.qvel
        self._xmat, self._ctrl = data.xmat, data.ctrl

    def _cart_position(self) -> np.ndarray:
        return self._qpos[:, self._cart]

    def _pole_angle_cosines(self) -> np.ndarray:
        # Every body after the world and the cart is a pole.
        return self._xmat[:, 2:, _ZZ]

    def get_observation(self) -> dict[str, np.ndarray]:
        n = self.physics.num_envs
        poles = self._xmat[:, 2:][:, :, [_ZZ, _XZ]].reshape(n, -1)
        return {
            "position": np.concatenate([self._cart_position()[:, None], poles], axis=1),
            "velocity": np.array(self._qvel),
        }

    def get_reward(self) -> np.ndarray:
        cart, cosines = self._cart_position(), self._pole_angle_cosines()
        if self._sparse:
            cart_in_bounds = rewards.tolerance(cart, self._cart_range, scalar=True)
            angle_in_bounds = rewards.tolerance(
                cosines, self._angle_cosine_range, scalar=False
            ).prod(axis=1)
            return cart_in_bounds * angle_in_bounds
        upright = (cosines + 1) / 2
        # The cart's position is one number on the CPU, the rest arrays.
        centered = (1 + rewards.tolerance(cart, margin=2, scalar=True)) / 2
        small_control = rewards.tolerance(
            self._ctrl, margin=1, value_at_margin=0, sigmoid="quadratic", scalar=False
        )[:, 0]
        small_control = (4 + small_control) / 5
        small_velocity = rewards.tolerance(self._qvel[:, 1:], margin=5, scalar=False).min(axis=1)
        small_velocity = (1 + small_velocity) / 2
        return upright.mean(axis=1) * small_control * small_velocity * centered


tasks.register("dm_control.suite.cartpole.Balance", BatchBalance)
