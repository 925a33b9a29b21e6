"""Which compiled bodies, geoms and joints belong to an entity, found from its root body."""

from __future__ import annotations

import mujoco
import numpy as np

import mjcf


def body_id(model: mujoco.MjModel, body) -> int:
    """Returns the compiled id of an MJCF body element."""
    identifier = body.full_identifier
    found = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, identifier)
    if found < 0:
        raise ValueError(f"body {identifier!r} is not part of the compiled model")
    return found


def subtree_mask(model: mujoco.MjModel, root: int) -> np.ndarray:
    """Returns a boolean mask over bodies: True for `root` and all its descendants."""
    mask = np.zeros(model.nbody, dtype=bool)
    mask[root] = True
    parents = model.body_parentid
    # MuJoCo numbers bodies depth-first, so every parent precedes its children.
    for body in range(root + 1, model.nbody):
        mask[body] = mask[parents[body]]
    return mask


def entity_body_mask(model: mujoco.MjModel, entity) -> np.ndarray:
    """Returns the body mask of an entity's subtree (including entities attached to it).

    The subtree starts at the attachment frame of the entity's model (the whole world for a
    model that is not attached).
    """
    frame = mjcf.get_attachment_frame(entity.mjcf_model)
    return subtree_mask(model, 0 if frame is None else body_id(model, frame))


def joint_address_ranges(model: mujoco.MjModel, joint_ids) -> tuple[np.ndarray, np.ndarray]:
    """Returns the qpos and qvel indices of the given joints."""
    qpos_end = np.append(model.jnt_qposadr[1:], model.nq)
    dof_end = np.append(model.jnt_dofadr[1:], model.nv)
    qpos = [np.arange(model.jnt_qposadr[j], qpos_end[j]) for j in joint_ids]
    dofs = [np.arange(model.jnt_dofadr[j], dof_end[j]) for j in joint_ids]
    empty = np.zeros(0, dtype=int)
    return (
        np.concatenate(qpos) if qpos else empty,
        np.concatenate(dofs) if dofs else empty,
    )


def penetrating_geom_pairs(data: mujoco.MjData) -> tuple[np.ndarray, np.ndarray]:
    """Returns the geom ids of both sides of every contact with negative distance."""
    contact = data.contact
    penetrating = contact.dist < 0
    return contact.geom1[penetrating], contact.geom2[penetrating]
