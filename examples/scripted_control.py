"""Scripted policies that solve reach_site_features and lift_brick_features.

Both drive the pinch site (the hand's tool-centre point) with `CartesianController`, a
proportional controller in Cartesian space: the pose error of the pinch site, times a gain,
is the twist it should move with; damped least squares on the site's Jacobian turns that
twist into the six arm joint velocities the actuators take. State is read only through the
public API (`physics.bind`, `env.task`); the Jacobian comes from `mujoco.mj_jacSite`.

- `ReachPolicy`: hold the hand pointing down and move the pinch site onto the target.
- `LiftPolicy`: open the fingers above the brick, turned to its yaw, go down around it,
  close, lift, then hold the arm still (zero velocity) with the fingers closed.

Usage: python examples/scripted_control.py [--environment NAME] [--seeds 0 1 2 3 4]
"""

import argparse

import mujoco
import numpy as np

import manipulation

# The pinch site pointing straight down with its grip axis (+y) along world x, as the
# episodes start; columns are the site's axes in the world frame.
_DOWN = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


class CartesianController:
    """Arm joint velocities that move the pinch site towards a target pose.

    Args:
      env: a manipulation environment (its task has `arm` and `hand`), after `reset`.
      gain: twist per unit of pose error (1/s): position error in m, rotation error in rad.
      damping: damped-least-squares regulariser, keeps joint speeds finite near
        singularities.
    """

    def __init__(self, env, gain: float = 8.0, damping: float = 1e-4):
        physics = env.physics
        self._model, self._data = physics.model.ptr, physics.data.ptr
        self._site = physics.bind(env.task.hand.tool_center_point)
        self._site_id = int(self._site.element_id)
        self._dofs = np.asarray(physics.bind(env.task.arm.joints).dofadr)
        self._limit = np.asarray(physics.bind(env.task.arm.actuators).ctrlrange)[:, 1]
        self._gain, self._damping = gain, damping
        self._jacp = np.zeros((3, self._model.nv))
        self._jacr = np.zeros((3, self._model.nv))

    @property
    def position(self) -> np.ndarray:
        """The pinch site's current world position."""
        return self._site.xpos.copy()

    def joint_velocities(self, position, rotation=_DOWN) -> np.ndarray:
        """Returns the 6 arm joint velocities toward `position` (3,) and `rotation` (3, 3).

        The velocities are scaled down together, if needed, to fit the actuators' ranges,
        so the pinch site keeps its direction of travel.
        """
        current = self._site.xmat.reshape(3, 3)
        rotation_error = 0.5 * np.cross(current, rotation, axis=0).sum(axis=1)
        twist = self._gain * np.concatenate([position - self._site.xpos, rotation_error])
        mujoco.mj_jacSite(self._model, self._data, self._jacp, self._jacr, self._site_id)
        jacobian = np.vstack([self._jacp[:, self._dofs], self._jacr[:, self._dofs]])
        gram = jacobian @ jacobian.T + self._damping * np.eye(6)
        velocities = jacobian.T @ np.linalg.solve(gram, twist)
        return velocities / max(1.0, np.max(np.abs(velocities) / self._limit))


class ReachPolicy:
    """Moves the pinch site onto the reach_site target, fingers still.

    Build one per episode, after `env.reset()`; call it with each TimeStep for an action.
    """

    def __init__(self, env):
        self._controller = CartesianController(env)
        self._target = env.physics.bind(env.task.target)

    def __call__(self, timestep) -> np.ndarray:
        del timestep  # The policy reads the state from the physics.
        arm = self._controller.joint_velocities(self._target.xpos)
        return np.concatenate([arm, np.zeros(3)])


def _yaw_rotation(quaternion) -> np.ndarray:
    """The down-pointing pinch orientation turned to a half-turn-symmetric prop's yaw."""
    w, x, y, z = quaternion
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    yaw = (yaw + np.pi / 2) % np.pi - np.pi / 2
    turn = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    return turn @ _DOWN


class LiftPolicy:
    """Grasps the lift task's brick across its width and lifts it 0.25 m above the table.

    Phases (s): approach 0.12 m above the brick with the fingers opening, go down until the
    finger pads straddle it, close, lift, then hold with the arm still: corrections of a
    controller acting on a held brick would shake it out of the grip. Build one per
    episode, after `env.reset()` (it plans from where the brick starts).
    """

    _APPROACH, _DESCEND, _CLOSE, _LIFT = 1.5, 1.2, 0.6, 1.5
    _ABOVE, _GRASP, _LIFTED = 0.12, 0.016, 0.25
    _OPEN, _SHUT = -2.0, 3.0

    def __init__(self, env):
        self._physics = env.physics
        self._controller = CartesianController(env)
        prop = self._physics.bind(env.task.prop.root_body)
        self._brick = prop.xpos[:2].copy()
        self._rotation = _yaw_rotation(prop.xquat)
        self._start = self._controller.position

    def _setpoint(self, time: float):
        """Returns (pinch-site position or None to hold still, finger velocity) at `time`."""
        above = np.array([*self._brick, self._ABOVE])
        grasp = np.array([*self._brick, self._GRASP])
        lifted = np.array([*self._brick, self._LIFTED])
        for duration, start, end, fingers in (
            (self._APPROACH, self._start, above, self._OPEN),
            (self._DESCEND, above, grasp, self._OPEN),
            (self._CLOSE, grasp, grasp, self._SHUT),
            (self._LIFT, grasp, lifted, self._SHUT),
        ):
            if time < duration:
                fraction = min(1.0, time / (0.8 * duration))
                return start + fraction * (end - start), fingers
            time -= duration
        return None, self._SHUT

    def __call__(self, timestep) -> np.ndarray:
        del timestep  # The policy reads the state from the physics.
        position, fingers = self._setpoint(self._physics.data.time)
        if position is None:
            arm = np.zeros(6)
        else:
            arm = self._controller.joint_velocities(position, self._rotation)
        return np.concatenate([arm, np.full(3, fingers)])


POLICIES = {"reach_site_features": ReachPolicy, "lift_brick_features": LiftPolicy}


def run_episode(environment_name: str, seed: int) -> list[float]:
    """Runs one scripted episode of `environment_name` and returns its rewards."""
    env = manipulation.load(environment_name, seed=seed)
    timestep = env.reset()
    policy = POLICIES[environment_name](env)
    rewards = []
    while not timestep.last():
        timestep = env.step(policy(timestep))
        rewards.append(timestep.reward)
    return rewards


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--environment", choices=sorted(POLICIES), default=None)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    args = parser.parse_args()
    names = [args.environment] if args.environment else sorted(POLICIES, reverse=True)
    for name in names:
        for seed in args.seeds:
            rewards = run_episode(name, seed)
            print(
                f"{name} seed {seed}: return {sum(rewards):7.2f}, max reward {max(rewards):.3f}, "
                f"mean reward over the last second {np.mean(rewards[-25:]):.3f}"
            )


if __name__ == "__main__":
    main()
