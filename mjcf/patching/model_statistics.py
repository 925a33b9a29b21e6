"""The model statistics (`MjModel.stat`) as MuJoCo's compiler computes them.

`mj_setConst` brings the constants derived from masses and geometry up to date, but not
`stat` (center, extent, mean size, mass and inertia), which the compiler computes once, at
`qpos0`, after the constants: a bounding box of the bodies, joint anchors, sites and
geoms (a geom counts with its bounding radius, a plane or height field with a tenth of
its size), a size per body (its largest distance from its centre of mass to a joint anchor
of it or of a child, or to the far side of one of its geoms), and the mean body mass and
mass-matrix diagonal. A value the model's `<statistic>` sets replaces the computed one.

The arithmetic follows the compiler's order (sequential sums, the same distance formula),
so that the numbers are bit-identical to a recompile's on the installed MuJoCo; that is
checked by `mjcf/patching/patch_proof.py` wherever a patch relies on it.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

__all__ = ["Statistics", "compiled_statistics", "write_statistics"]

# Bounds the compiler starts its bounding box from, and the smallest size and extent.
_FAR = 1e10
_MIN_SIZE = 1e-5
# The fraction of a plane's or height field's size that counts as its bounding radius,
# and the radius of a plane infinite in both directions.
_UNBOUNDED_FRACTION = 0.1
_INFINITE_PLANE_RADIUS = 0.01
# Fills the mass matrix `data.qM`: `mj_makeM` where it exists (it came with tendon armature,
# which it adds); before it (mujoco 3.3.0), `mj_crb` wrote the whole matrix.
_make_mass_matrix = getattr(mujoco, "mj_makeM", None) or mujoco.mj_crb


class Statistics(NamedTuple):
    """The fields of `MjModel.stat` that the compiler computes."""

    center: np.ndarray
    extent: float
    meansize: float
    meanmass: float
    meaninertia: float


def compiled_statistics(model: mujoco.MjModel, data: mujoco.MjData) -> Statistics:
    """The statistics a compile of `model` would give, before `<statistic>` overrides.

    Args:
      model: the model, its constants up to date (`mj_setConst`).
      data: an MjData of `model`, used as scratch space: it is reset to `qpos0` and left
        with the positions and the mass matrix there.

    Returns:
      `Statistics`; a field the compiler leaves alone (the extent of a model with no
      spread, the means of a model without bodies or degrees of freedom) keeps `model`'s
      current value.
    """
    # What the statistics read of a forward at qpos0: the positions and the mass matrix.
    mujoco.mj_resetData(model, data)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_comPos(model, data)
    _make_mass_matrix(model, data)

    # Bounding box of body frames, centres of mass, joint anchors, sites and geoms.
    points = np.concatenate([data.xpos[1:], data.xipos[1:], data.xanchor, data.site_xpos])
    radii = _bounding_radii(model)
    low = np.minimum.reduce(
        [np.full(3, _FAR), *_min_rows(points), *_min_rows(data.geom_xpos - radii[:, None])]
    )
    high = np.maximum.reduce(
        [np.full(3, -_FAR), *_max_rows(points), *_max_rows(data.geom_xpos + radii[:, None])]
    )
    center = (low + high) * 0.5
    extent = float(model.stat.extent)
    if high[0] > low[0]:
        spread = high - low
        extent = max(_MIN_SIZE, max(spread[0], max(spread[1], spread[2])))

    meansize = float(model.stat.meansize)
    meanmass = float(model.stat.meanmass)
    if model.nbody > 1:
        sizes = np.maximum(_body_sizes(model, data)[1:], _MIN_SIZE)
        meansize = float(np.cumsum(sizes / (model.nbody - 1))[-1])
        meanmass = float(np.cumsum(model.body_mass[1:])[-1] / (model.nbody - 1))
    extent = max(extent, 2 * meansize)

    meaninertia = float(model.stat.meaninertia)
    if model.nv:
        meaninertia = float(np.cumsum(_mass_matrix_diagonal(model, data))[-1] / model.nv)
    return Statistics(center, float(extent), meansize, meanmass, meaninertia)


def write_statistics(model: mujoco.MjModel, statistics: Statistics, *, keep=()) -> None:
    """Writes `statistics` into `model.stat`, except the fields named in `keep` (those
    the model's `<statistic>` sets)."""
    for name, value in statistics._asdict().items():
        if name in keep:
            continue
        if name == "center":
            model.stat.center[:] = value
        else:
            setattr(model.stat, name, value)


def _mass_matrix_diagonal(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """The mass matrix's diagonal, one entry per degree of freedom: from its compressed rows
    `data.M` where they exist, else (mujoco 3.3.0) from `data.qM` at `dof_Madr`."""
    if hasattr(data, "M"):
        return data.M[model.M_rowadr + model.M_rownnz - 1]
    return data.qM[model.dof_Madr]


def _min_rows(points: np.ndarray) -> list[np.ndarray]:
    return [points.min(axis=0)] if len(points) else []


def _max_rows(points: np.ndarray) -> list[np.ndarray]:
    return [points.max(axis=0)] if len(points) else []


def _bounding_radii(model: mujoco.MjModel) -> np.ndarray:
    """Each geom's radius in the bounding box: its bounding radius, or a fraction of the
    size of a plane or height field (which have none)."""
    radii = np.where(model.geom_rbound > 0, model.geom_rbound, 0.0)
    for i in np.flatnonzero(model.geom_rbound <= 0):
        if model.geom_type[i] == mujoco.mjtGeom.mjGEOM_PLANE:
            width, length = model.geom_size[i, 0], model.geom_size[i, 1]
            if width or length:
                radii[i] = max(width, length) * _UNBOUNDED_FRACTION
            else:
                radii[i] = _INFINITE_PLANE_RADIUS
        elif model.geom_type[i] == mujoco.mjtGeom.mjGEOM_HFIELD:
            size = model.hfield_size[model.geom_dataid[i]]
            radii[i] = max(size[0], max(size[1], max(size[2], size[3]))) * _UNBOUNDED_FRACTION
    return radii


def _distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise Euclidean distances, summed in MuJoCo's order."""
    d = a - b
    return np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1] + d[:, 2] * d[:, 2])


def _body_sizes(model: mujoco.MjModel, data: mujoco.MjData) -> np.ndarray:
    """Each body's size: the largest distance from its centre of mass to a joint anchor of
    it or of a child, or to the far side of one of its geoms (bounding radius)."""
    sizes = np.zeros(model.nbody)
    bodies = model.jnt_bodyid
    np.maximum.at(sizes, bodies, _distances(data.xipos[bodies], data.xanchor))
    parents = model.body_parentid[bodies]
    np.maximum.at(sizes, parents, _distances(data.xipos[parents], data.xanchor))
    sizes[0] = 0
    geoms = np.flatnonzero((model.geom_rbound > 0) & (model.geom_bodyid > 0))
    owners = model.geom_bodyid[geoms]
    reach = model.geom_rbound[geoms] + _distances(data.xipos[owners], data.geom_xpos[geoms])
    np.maximum.at(sizes, owners, reach)
    return sizes
