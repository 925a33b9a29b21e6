"""Inverse kinematics: joint positions that put a site at a target pose (damped least squares)."""

from __future__ import annotations

import collections
import copy
from collections.abc import Sequence

import mujoco
import numpy as np
from absl import logging

IKResult = collections.namedtuple("IKResult", ["qpos", "err_norm", "steps", "success"])


def _raw(wrapper):
    """Returns the mujoco struct behind a Physics' `model`/`data` wrapper (or the struct itself)."""
    return getattr(wrapper, "ptr", wrapper)


def _dof_indices(model: mujoco.MjModel, joint_names) -> np.ndarray | slice:
    if joint_names is None:
        return slice(None)
    if not isinstance(joint_names, (list, tuple, np.ndarray)):
        raise ValueError(
            f"joint_names: expected None or a list, tuple or array of joint names, "
            f"got {type(joint_names).__name__}"
        )
    indices = []
    for name in joint_names:
        joint_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, str(name))
        if joint_id < 0:
            raise ValueError(f"joint_names: the model has no joint named {name!r}")
        indices.append(np.flatnonzero(model.dof_jntid == joint_id))
    return np.concatenate(indices) if indices else np.zeros(0, dtype=int)


def nullspace_method(
    jac_joints: np.ndarray, delta: np.ndarray, regularization_strength: float = 0.0
) -> np.ndarray:
    """Returns the joint step `dq` minimising |jac_joints @ dq - delta|^2 + r * |dq|^2.

    Args:
      jac_joints: (nrows, njoints) Jacobian of the task coordinates w.r.t. the joints.
      delta: (nrows,) desired change of the task coordinates.
      regularization_strength: the damping `r`; 0 gives the least-squares solution.

    Returns:
      The (njoints,) joint step.
    """
    hessian = jac_joints.T @ jac_joints
    gradient = jac_joints.T @ delta
    if regularization_strength > 0:
        # The diagonal through a strided flat view: np.diag_indices_from costs ~40x more.
        hessian.flat[:: hessian.shape[0] + 1] += regularization_strength
        return np.linalg.solve(hessian, gradient)
    return np.linalg.lstsq(hessian, gradient, rcond=None)[0]


def qpos_from_site_pose(
    physics,
    site_name: str,
    target_pos=None,
    target_quat=None,
    joint_names: Sequence[str] | None = None,
    tol: float = 1e-14,
    rot_weight: float = 1.0,
    regularization_threshold: float = 0.1,
    regularization_strength: float = 3e-2,
    max_update_norm: float = 2.0,
    progress_thresh: float = 20.0,
    max_steps: int = 100,
    inplace: bool = False,
) -> IKResult:
    """Finds joint positions that place a site at a target position and/or orientation.

    Each iteration takes a Gauss-Newton step on the site's pose error using MuJoCo's site
    Jacobian (`mj_jacSite`), damped by `regularization_strength` while the error exceeds
    `regularization_threshold`. Joint limits are not enforced.

    Args:
      physics: An `mjcf.Physics` (anything whose `model`/`data` are, or wrap with `.ptr`,
        a `mujoco.MjModel`/`mujoco.MjData`).
      site_name: Full name of the site in the compiled model.
      target_pos: Target (3,) position in the world frame, or None.
      target_quat: Target (4,) unit quaternion (w, x, y, z) in the world frame, or None.
      joint_names: Names of the joints the solver may move; None means every degree of freedom.
      tol: Convergence threshold on the error norm
        (`|pos error| + rot_weight * |rotation error in radians|`).
      rot_weight: Weight of the rotation error in the error norm.
      regularization_threshold: Error norm above which the step is damped.
      regularization_strength: Damping coefficient used above `regularization_threshold`.
      max_update_norm: Upper bound on the norm of one joint step.
      progress_thresh: The solver stops (unsuccessfully) when the error norm divided by the
        step norm exceeds this: it is no longer making progress.
      max_steps: Maximum number of iterations.
      inplace: If True, `physics.data` is modified (qpos and the kinematic quantities that
        depend on it); otherwise a copy of the data is used and `physics` is left untouched.

    Returns:
      `IKResult(qpos, err_norm, steps, success)`: the full qpos vector (a view of
      `physics.data.qpos` when `inplace`, else a copy), the final error norm, the index of
      the last iteration, and whether the error norm fell below `tol`.

    Raises:
      ValueError: If neither target is given, a target has the wrong shape, or the site or a
        joint does not exist.
    """
    if target_pos is None and target_quat is None:
        raise ValueError(
            "qpos_from_site_pose: at least one of target_pos and target_quat is required"
        )
    model = _raw(physics.model)
    site_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site_name)
    if site_id < 0:
        raise ValueError(f"site_name: the model has no site named {site_name!r}")
    dof_indices = _dof_indices(model, joint_names)

    rows = 0
    if target_pos is not None:
        target_pos = np.asarray(target_pos, dtype=np.float64)
        if target_pos.shape != (3,):
            raise ValueError(f"target_pos: expected shape (3,), got {target_pos.shape}")
        rows += 3
    if target_quat is not None:
        target_quat = np.asarray(target_quat, dtype=np.float64)
        if target_quat.shape != (4,):
            raise ValueError(f"target_quat: expected shape (4,), got {target_quat.shape}")
        rows += 3

    jac = np.zeros((rows, model.nv))
    err = np.zeros(rows)
    # Views into `jac` and `err` for the translational and rotational parts.
    jac_pos = jac[:3] if target_pos is not None else None
    err_pos = err[:3] if target_pos is not None else None
    jac_rot = jac[rows - 3 :] if target_quat is not None else None
    err_rot = err[rows - 3 :] if target_quat is not None else None
    data = _raw(physics.data) if inplace else copy.copy(_raw(physics.data))
    site_quat = np.empty(4)
    site_quat_conj = np.empty(4)
    err_quat = np.empty(4)
    update_nv = np.zeros(model.nv)

    def update_kinematics():
        # mj_jacSite needs body poses (mj_kinematics) and com-based frames (mj_comPos).
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)

    update_kinematics()
    site_xpos = data.site_xpos[site_id]
    site_xmat = data.site_xmat[site_id]

    success = False
    err_norm = 0.0
    steps = 0
    for step in range(max_steps):
        steps = step
        err_norm = 0.0
        if err_pos is not None:
            np.subtract(target_pos, site_xpos, out=err_pos)
            err_norm += np.linalg.norm(err_pos)
        if err_rot is not None:
            mujoco.mju_mat2Quat(site_quat, site_xmat)
            mujoco.mju_negQuat(site_quat_conj, site_quat)
            mujoco.mju_mulQuat(err_quat, target_quat, site_quat_conj)
            mujoco.mju_quat2Vel(err_rot, err_quat, 1.0)
            err_norm += np.linalg.norm(err_rot) * rot_weight
        if err_norm < tol:
            success = True
            break
        mujoco.mj_jacSite(model, data, jac_pos, jac_rot, site_id)
        regularization = regularization_strength if err_norm > regularization_threshold else 0.0
        update = nullspace_method(jac[:, dof_indices], err, regularization)
        update_norm = np.linalg.norm(update)
        if update_norm == 0.0 or err_norm > progress_thresh * update_norm:
            break
        if update_norm > max_update_norm:
            update *= max_update_norm / update_norm
        update_nv[dof_indices] = update
        mujoco.mj_integratePos(model, data.qpos, update_nv, 1.0)
        update_kinematics()

    if not success and steps == max_steps - 1:
        logging.warning("Failed to converge after %i steps: err_norm=%3g", steps, err_norm)
    qpos = data.qpos if inplace else data.qpos.copy()
    return IKResult(qpos=qpos, err_norm=err_norm, steps=steps, success=success)
