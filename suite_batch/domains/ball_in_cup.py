"""Ball-in-Cup's `BallInCup` batched: the catch task's sparse in-the-cup reward."""

import mujoco
import numpy as np

from suite_batch import tasks

# The world's x and z axes: the plane the ball and the cup move in.
_X, _Z = 0, 2


class BatchBallInCup(tasks.SuiteBatchTask):
    """`ball_in_cup.BallInCup` for every world: 1 while the ball lies inside the cup's
    target box (its centre's offset from the box's, in x and in z, short of the box's
    half-size less the ball's radius), 0 elsewhere."""

    def __init__(self, task, host, physics):
        super().__init__(task, host, physics)
        model = host.model.ptr
        self._target = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "target")
        self._ball = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "ball")
        ball_geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "ball")
        # The box's x and z half-sizes less the ball's radius, as the task subtracts them.
        self._room = model.site_size[self._target, [_X, _Z]] - model.geom_size[ball_geom, 0]
        data = physics.data
        self._qpos, self._qvel = data.qpos, data.qvel
        self._site_xpos, self._xpos = data.site_xpos, data.xpos

    def get_observation(self) -> dict[str, np.ndarray]:
        return {"position": np.array(self._qpos), "velocity": np.array(self._qvel)}

    def get_reward(self) -> np.ndarray:
        target = self._site_xpos[:, self._target][:, [_X, _Z]]
        ball = self._xpos[:, self._ball][:, [_X, _Z]]
        inside = abs(target - ball) < self._room
        return inside.all(axis=1).astype(np.float64)


tasks.register("dm_control.suite.ball_in_cup.BallInCup", BatchBallInCup)
