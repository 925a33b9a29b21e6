"""Inverse kinematics: joint positions that put a site at a target pose (damped least squares).

`qpos_from_site_pose` takes the same arguments and returns, bit for bit, the same results as
dm_control's `dm_control.utils.inverse_kinematics.qpos_from_site_pose`: every floating-point
operation of an iteration is the same NumPy/LAPACK/MuJoCo call on the same operands. It is
faster because an iteration updates only the quantities it reads (`mj_kinematics` and
`mj_comPos` instead of the whole `mj_fwdPosition`), reuses preallocated arrays and does not
log; with `inplace=True` one `mj_fwdPosition` on the final joint positions leaves
`physics.data` as dm_control leaves it.
"""

from __future__ import annotations

import collections
import copy
import math
from collections.abc import Sequence

import mujoco
import numpy as np
from absl import logging

IKResult = collections.namedtuple("IKResult", ["qpos", "err_norm", "steps", "success"])

#: Error for a `joint_names` of another type; `.format(type(joint_names))`.
_INVALID_JOINT_NAMES_TYPE = (
    "qpos_from_site_pose: joint_names: expected None or a list, tuple or numpy array of "
    "joint names, got {}"
)
#: Error when neither target is given.
_REQUIRE_TARGET_POS_OR_QUAT = (
    "qpos_from_site_pose: expected target_pos, target_quat or both, got neither"
)


def _raw(wrapper):
    """Returns the mujoco struct behind a Physics' `model`/`data` wrapper (or the struct itself)."""
    return getattr(wrapper, "ptr", wrapper)


def _dof_indices(model: mujoco.MjModel, joint_names) -> np.ndarray | None:
    """The dof indices of `joint_names` in the order given (all dofs of each joint), or None
    for every dof."""
    if joint_names is None:
        return None
    if not isinstance(joint_names, (list, tuple, np.ndarray)):
        raise ValueError(_INVALID_JOINT_NAMES_TYPE.format(type(joint_names)))
    indices = []
    for name in joint_names:
        joint_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, str(name))
        if joint_id < 0:
            raise ValueError(f"joint_names: the model has no joint named {name!r}")
        indices.append(np.flatnonzero(model.dof_jntid == joint_id))
    return np.concatenate(indices) if indices else np.zeros(0, dtype=np.intp)


def nullspace_method(
    jac_joints: np.ndarray, delta: np.ndarray, regularization_strength: float = 0.0
) -> np.ndarray:
    """Returns the joint step `dq` minimising |jac_joints @ dq - delta|^2 + r * |dq|^2.

    Solves the normal equations `(J^T J + r I) dq = J^T delta` with `np.linalg.solve` when
    `r > 0`, and by least squares (`np.linalg.lstsq`, singular values below machine precision
    times the largest treated as zero) when `r == 0`.

    Args:
      jac_joints: (nrows, njoints) Jacobian of the task coordinates w.r.t. the joints.
      delta: (nrows,) desired change of the task coordinates.
      regularization_strength: the damping `r`; 0 gives the least-squares solution.

    Returns:
      The (njoints,) joint step.
    """
    hessian = jac_joints.T.dot(jac_joints)
    gradient = jac_joints.T.dot(delta)
    if regularization_strength > 0:
        # The whole identity is added (not the diagonal alone) so that off-diagonal -0.0
        # entries become +0.0 exactly as in dm_control.
        hessian += np.eye(hessian.shape[0]) * regularization_strength
        return np.linalg.solve(hessian, gradient)
    return np.linalg.lstsq(hessian, gradient, rcond=-1)[0]


def _check_target(name: str, target, size: int) -> np.ndarray | None:
    if target is None:
        return None
    target = np.ascontiguousarray(target, dtype=np.float64)
    if target.shape != (size,):
        raise ValueError(f"{name}: expected shape ({size},), got {target.shape}")
    return target


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

    Each iteration takes a Gauss-Newton step (`nullspace_method`) on the site's pose error
    using MuJoCo's site Jacobian (`mj_jacSite`), damped by `regularization_strength` while
    the error exceeds `regularization_threshold`, scaled down to `max_update_norm`, and
    applied with `mj_integratePos`. Joint limits are not enforced.

    Args:
      physics: An `mjcf.Physics` (anything whose `model`/`data` are, or wrap with `.ptr`,
        a `mujoco.MjModel`/`mujoco.MjData`).
      site_name: Full name of the site in the compiled model.
      target_pos: Target (3,) position in the world frame, or None.
      target_quat: Target (4,) unit quaternion (w, x, y, z) in the world frame, or None.
      joint_names: Names of the joints the solver may move (a list, tuple or numpy array;
        a joint with several dofs moves all of them); None means every degree of freedom.
      tol: Convergence threshold on the error norm
        (`|pos error| + rot_weight * |rotation error in radians|`).
      rot_weight: Weight of the rotation error in the error norm.
      regularization_threshold: Error norm above which the step is damped.
      regularization_strength: Damping coefficient used above `regularization_threshold`.
      max_update_norm: Upper bound on the norm of one joint step.
      progress_thresh: The solver stops (unsuccessfully) when the error norm divided by the
        step norm exceeds this: it is no longer making progress.
      max_steps: Maximum number of iterations.
      inplace: If True, `physics.data` is modified: it ends with the solution's qpos and
        everything `mj_fwdPosition` computes from it. Otherwise a copy of the data is used
        and `physics` is left untouched.

    Returns:
      `IKResult(qpos, err_norm, steps, success)`: the full qpos vector (a view of
      `physics.data.qpos` when `inplace`, else a copy), the final error norm, the index of
      the last iteration, and whether the error norm fell below `tol`. A warning is logged
      when the last iteration is reached without success.

    Raises:
      ValueError: If neither target is given, a target has the wrong shape, `joint_names`
        has another type, or the site or a joint does not exist.
    """
    if target_pos is None and target_quat is None:
        raise ValueError(_REQUIRE_TARGET_POS_OR_QUAT)
    model = _raw(physics.model)
    site_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, site_name)
    if site_id < 0:
        raise ValueError(f"site_name: the model has no site named {site_name!r}")
    dof_indices = _dof_indices(model, joint_names)
    target_pos = _check_target("target_pos", target_pos, 3)
    target_quat = _check_target("target_quat", target_quat, 4)

    rows = 3 if target_pos is None or target_quat is None else 6
    jac = np.zeros((rows, model.nv))
    err = np.zeros(rows)
    # Views into `jac` and `err` for the translational and rotational parts.
    jac_pos = err_pos = jac_rot = err_rot = None
    if target_pos is not None:
        jac_pos, err_pos = jac[:3], err[:3]
    if target_quat is not None:
        jac_rot, err_rot = jac[rows - 3 :], err[rows - 3 :]
        site_quat = np.empty(4)
        site_quat_conj = np.empty(4)
        err_quat = np.empty(4)
    columns = model.nv if dof_indices is None else len(dof_indices)
    update_nv = None if dof_indices is None else np.zeros(model.nv)
    regularization = np.eye(columns) * regularization_strength
    hessian = np.empty((columns, columns))
    gradient = np.empty(columns)

    data = _raw(physics.data) if inplace else copy.copy(_raw(physics.data))
    qpos = data.qpos
    # mj_jacSite reads body poses (mj_kinematics) and com-based frames (mj_comPos): all the
    # loop needs of mj_fwdPosition.
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
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
            # np.linalg.norm of a 1-D float64 vector: sqrt(x.dot(x)).
            err_norm += math.sqrt(err_pos.dot(err_pos))
        if err_rot is not None:
            mujoco.mju_mat2Quat(site_quat, site_xmat)
            mujoco.mju_negQuat(site_quat_conj, site_quat)
            mujoco.mju_mulQuat(err_quat, target_quat, site_quat_conj)
            mujoco.mju_quat2Vel(err_rot, err_quat, 1.0)
            err_norm += math.sqrt(err_rot.dot(err_rot)) * rot_weight
        if err_norm < tol:
            success = True
            break
        mujoco.mj_jacSite(model, data, jac_pos, jac_rot, site_id)
        # nullspace_method's arithmetic into preallocated arrays. The fancy index gives the
        # memory layout (column-major) that selects the same BLAS routines as dm_control.
        jac_joints = jac if dof_indices is None else jac[:, dof_indices]
        jac_joints.T.dot(jac_joints, out=hessian)
        jac_joints.T.dot(err, out=gradient)
        if err_norm > regularization_threshold and regularization_strength > 0:
            hessian += regularization
            update = np.linalg.solve(hessian, gradient)
        else:
            update = np.linalg.lstsq(hessian, gradient, rcond=-1)[0]
        update_norm = math.sqrt(update.dot(update))
        # err_norm / update_norm, with the limits of a zero update: inf, or nan for 0 / 0.
        if update_norm:
            progress = err_norm / update_norm
        else:
            progress = math.inf if err_norm > 0 else math.nan
        if progress > progress_thresh:
            break
        if update_norm > max_update_norm:
            update *= max_update_norm / update_norm
        if dof_indices is not None:
            update_nv[dof_indices] = update
        mujoco.mj_integratePos(model, qpos, update if dof_indices is None else update_nv, 1.0)
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)

    if not success and steps == max_steps - 1:
        logging.warning("Failed to converge after %i steps: err_norm=%3g", steps, err_norm)
    if inplace:
        mujoco.mj_fwdPosition(model, data)
        return IKResult(qpos=qpos, err_norm=err_norm, steps=steps, success=success)
    return IKResult(qpos=qpos.copy(), err_norm=err_norm, steps=steps, success=success)
