"""The Warp kernels of `composer.batch`, defined on first use (importing this needs no Warp).

Every kernel works on arrays whose first axis is the world, most of them on two-dimensional
views of MuJoCo Warp's per-world arrays made by `rows`. The same kernels run on Warp's CPU
device (compiled C loops, one call per thread) and on CUDA. Each owner's kernels are
defined by a function of their own below, named for the owner:

| definer            | kernels                                   | launched by                |
|--------------------|-------------------------------------------|----------------------------|
| `_state_copies`    | save_columns, restore_columns, copy_worlds| `composer.batch.physics`   |
| `_action_checks`   | count_nonfinite                           | `composer.batch.actions`   |
| `_contacts`        | contact_worlds                            | `physics.ContactWatch`     |
| `_episode_starts`  | take_slots, count_episodes                | `composer.batch.state_slots` |
| `_static_poses`    | static_geom_poses                         | `composer.batch.physics`   |
| `_gather`          | gather_columns                            | `composer.batch.gather`    |
| `_images`          | unpack_rgb, planar_depth, segmentation    | `composer.batch.cameras`   |
"""

from types import SimpleNamespace
from typing import Any

import numpy as np

from composer.batch import _warp

__all__ = ["kernels", "rows"]

_kernels: SimpleNamespace | None = None


def kernels() -> SimpleNamespace:
    """The kernels, compiled by Warp at their first launch.

    Returns:
      A namespace of every kernel of the module docstring's table (documented on each).
    """
    global _kernels
    if _kernels is None:
        wp = _warp.load().warp
        definers = (
            _state_copies,
            _action_checks,
            _contacts,
            _episode_starts,
            _static_poses,
            _gather,
            _images,
        )
        _kernels = SimpleNamespace(**{k: v for define in definers for k, v in define(wp).items()})
    return _kernels


def rows(array, dtype, nrows: int):
    """A (nrows, entries per row) alias of the contiguous Warp `array`, read as `dtype`.

    `nrows` is the number of worlds the array holds (1 for a model field shared by every
    world); the memory is the array's own.
    """
    wp = _warp.load().warp
    per_row = array.capacity // nrows // wp.types.type_size_in_bytes(dtype)
    return wp.array(
        ptr=array.ptr, dtype=dtype, shape=(nrows, per_row), device=array.device, copy=False
    )


# Each definer returns its kernels by name.


def _state_copies(wp) -> dict[str, Any]:
    """Copies of per-world state: columns saved and restored, worlds' rows copied."""

    @wp.kernel(module="unique")
    def save_columns(
        columns: wp.array(dtype=wp.int32),
        source: wp.array2d(dtype=wp.float32),
        saved: wp.array2d(dtype=wp.float32),
    ):
        """saved[world, k] = source[world, columns[k]]."""
        world, k = wp.tid()
        saved[world, k] = source[world, columns[k]]

    @wp.kernel(module="unique")
    def restore_columns(
        columns: wp.array(dtype=wp.int32),
        saved: wp.array2d(dtype=wp.float32),
        target: wp.array2d(dtype=wp.float32),
    ):
        """target[world, columns[k]] = saved[world, k]: what `save_columns` saved."""
        world, k = wp.tid()
        target[world, columns[k]] = saved[world, k]

    @wp.kernel(module="unique")
    def copy_worlds(
        keep: wp.array(dtype=wp.bool),
        source: wp.array2d(dtype=Any),
        target: wp.array2d(dtype=Any),
    ):
        """Copies the rows of the worlds where `keep` is true from `source` to `target`; a
        world that is not kept costs one read of `keep`."""
        world = wp.tid()
        if keep[world]:
            for k in range(source.shape[1]):
                target[world, k] = source[world, k]

    return {
        "save_columns": save_columns,
        "restore_columns": restore_columns,
        "copy_worlds": copy_worlds,
    }


def _action_checks(wp) -> dict[str, Any]:
    """The check of device actions' values."""
    float32_max = wp.constant(wp.float64(np.finfo(np.float32).max))

    @wp.kernel(module="unique")
    def count_nonfinite(values: wp.array2d(dtype=Any), count: wp.array(dtype=wp.int32)):
        """Adds the number of entries of `values` that are NaN, infinite, or beyond float32's
        range (which becomes infinity in float32) to count[0]."""
        i, j = wp.tid()
        value = wp.float64(values[i, j])
        if not wp.isfinite(value) or wp.abs(value) > float32_max:
            wp.atomic_add(count, 0, 1)

    return {"count_nonfinite": count_nonfinite}


def _contacts(wp) -> dict[str, Any]:
    """Which worlds have a contact between two sets of geoms."""

    @wp.kernel(module="unique")
    def contact_worlds(
        nacon: wp.array(dtype=wp.int32),
        geom: wp.array(dtype=wp.vec2i),
        worldid: wp.array(dtype=wp.int32),
        codes: wp.array(dtype=wp.int32),
        stride: int,
        out: wp.array(dtype=wp.bool),
    ):
        """out[world] = True where an active contact pairs a code-1 geom with a code-2 one.

        A geom's code has bit 1 for the first set and bit 2 for the second. Thread t reads
        the active contacts t, t + stride, ...: launched with `stride` threads, one per
        contact slot on CUDA, or one thread for them all on the CPU device, where a thread
        per slot of the (mostly empty) contact capacity would cost a call each.
        """
        for k in range(wp.tid(), nacon[0], stride):
            pair = geom[k]
            a = codes[pair[0]]
            b = codes[pair[1]]
            if ((a & 1) != 0 and (b & 2) != 0) or ((a & 2) != 0 and (b & 1) != 0):
                out[worldid[k]] = True

    return {"contact_worlds": contact_worlds}


def _episode_starts(wp) -> dict[str, Any]:
    """The prepared initial states taken into the worlds that start an episode."""

    @wp.kernel(module="unique")
    def take_slots(
        mask: wp.array(dtype=wp.bool),
        counters: wp.array2d(dtype=wp.int32),
        slots_per_world: int,
        slots: wp.array2d(dtype=wp.float32),
        target: wp.array2d(dtype=wp.float32),
    ):
        """target[world] = the slot of world's next episode, for the worlds of `mask`.

        counters[0, world] is the number of episodes the world has started (the index of its
        next one); `slots` holds `slots_per_world` rows per world, episode e in row
        e % slots_per_world.
        """
        world, k = wp.tid()
        if mask[world]:
            row = world * slots_per_world + counters[0, world] % slots_per_world
            target[world, k] = slots[row, k]

    @wp.kernel(module="unique")
    def count_episodes(
        mask: wp.array(dtype=wp.bool),
        uploaded: wp.array(dtype=wp.int32),
        counters: wp.array2d(dtype=wp.int32),
    ):
        """Counts a started episode for the worlds of `mask`: counters[0] += 1, and
        counters[1] += 1 where the episode's state was not uploaded (a reused state)."""
        world = wp.tid()
        if mask[world]:
            if counters[0, world] >= uploaded[world]:
                counters[1, world] = counters[1, world] + 1
            counters[0, world] = counters[0, world] + 1

    return {"take_slots": take_slots, "count_episodes": count_episodes}


def _static_poses(wp) -> dict[str, Any]:
    """The world poses of geoms welded to the world, which MuJoCo Warp does not update."""

    @wp.func
    def mul_quat(a: wp.quat, b: wp.quat):
        # MuJoCo's order: w, x, y, z.
        return wp.quat(
            a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
        )

    @wp.func
    def rotate(v: wp.vec3, q: wp.quat):
        # v rotated by the unit quaternion q (w, x, y, z).
        u = wp.vec3(q[1], q[2], q[3])
        t = 2.0 * wp.cross(u, v)
        return v + q[0] * t + wp.cross(u, t)

    @wp.func
    def quat_to_mat(q: wp.quat):
        w, x, y, z = q[0], q[1], q[2], q[3]
        return wp.mat33(
            1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y),
            2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x),
            2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y),
        )  # fmt: skip

    @wp.kernel(module="unique")
    def static_geom_poses(
        geoms: wp.array(dtype=wp.int32),
        geom_bodyid: wp.array(dtype=wp.int32),
        geom_pos: wp.array2d(dtype=wp.vec3),
        geom_quat: wp.array2d(dtype=wp.quat),
        xpos: wp.array2d(dtype=wp.vec3),
        xquat: wp.array2d(dtype=wp.quat),
        geom_xpos: wp.array2d(dtype=wp.vec3),
        geom_xmat: wp.array2d(dtype=wp.mat33),
    ):
        """The world poses of `geoms`, geoms of bodies welded to the world, from their
        bodies' poses (MuJoCo Warp computes them once, when the data is made)."""
        world, k = wp.tid()
        geom = geoms[k]
        body = geom_bodyid[geom]
        xq = xquat[world, body]
        position = geom_pos[world % geom_pos.shape[0], geom]
        geom_xpos[world, geom] = xpos[world, body] + rotate(position, xq)
        rotation = mul_quat(xq, geom_quat[world % geom_quat.shape[0], geom])
        geom_xmat[world, geom] = quat_to_mat(rotation)

    return {"static_geom_poses": static_geom_poses}


def _gather(wp) -> dict[str, Any]:
    """The observation gather of `composer.batch.gather`."""

    @wp.kernel(module="unique")
    def gather_columns(
        sources: wp.array(dtype=wp.uint64),
        source_rows: wp.array(dtype=wp.int32),
        source_sizes: wp.array(dtype=wp.int32),
        column_source: wp.array(dtype=wp.int32),
        column_out: wp.array2d(dtype=wp.int32),
        column_terms: wp.array(dtype=wp.int32),
        column_entries: wp.array2d(dtype=wp.int32),
        column_weights: wp.array2d(dtype=wp.float32),
        column_op: wp.array(dtype=wp.int32),
        slot: int,
        out: wp.array2d(dtype=wp.float32),
    ):
        """Every observation entry (a column) of one world, into row `slot` of `out`.

        Column c reads the float32 device array at address sources[column_source[c]]
        (source_sizes entries, source_rows per world, 0 for a row shared by every world):
        the sum of column_terms[c] entries column_entries[c, t] of the world's row, each
        times column_weights[c, t], then sin (op 1), cos (op 2) or nothing (op 0). It goes
        to out[slot, column_out[c, 0] + world * column_out[c, 1]].
        """
        world = wp.tid()
        for c in range(column_source.shape[0]):
            s = column_source[c]
            source = wp.array(ptr=sources[s], shape=(source_sizes[s],), dtype=wp.float32)
            base = world * source_rows[s]
            value = wp.float32(0.0)
            for t in range(column_terms[c]):
                value += column_weights[c, t] * source[base + column_entries[c, t]]
            op = column_op[c]
            if op == 1:
                value = wp.sin(value)
            elif op == 2:
                value = wp.cos(value)
            out[slot, column_out[c, 0] + world * column_out[c, 1]] = value

    return {"gather_columns": gather_columns}


def _images(wp) -> dict[str, Any]:
    """MuJoCo Warp's rendered pixels unpacked into camera images."""

    @wp.kernel(module="unique")
    def unpack_rgb(
        packed: wp.array2d(dtype=wp.uint32),
        address: wp.array(dtype=int),
        camera: int,
        image: wp.array4d(dtype=wp.uint8),
    ):
        """image[world, y, x] = the RGB bytes of MuJoCo Warp's packed pixel (0xAARRGGBB)."""
        world, pixel = wp.tid()
        width = image.shape[2]
        value = packed[world, address[camera] + pixel]
        y, x = pixel // width, pixel % width
        image[world, y, x, 0] = wp.uint8((value >> wp.uint32(16)) & wp.uint32(255))
        image[world, y, x, 1] = wp.uint8((value >> wp.uint32(8)) & wp.uint32(255))
        image[world, y, x, 2] = wp.uint8(value & wp.uint32(255))

    @wp.kernel(module="unique")
    def planar_depth(
        depth: wp.array2d(dtype=wp.float32),
        address: wp.array(dtype=int),
        camera: int,
        far: float,
        image: wp.array4d(dtype=wp.float32),
    ):
        """image[world, y, x, 0] = the pixel's depth along the camera axis, `far` where the
        ray hit nothing (MuJoCo Warp writes 0 there)."""
        world, pixel = wp.tid()
        width = image.shape[2]
        value = depth[world, address[camera] + pixel]
        if value <= 0.0:
            value = far
        image[world, pixel // width, pixel % width, 0] = value

    @wp.kernel(module="unique")
    def segmentation(
        ids: wp.array2d(dtype=wp.vec2i),
        address: wp.array(dtype=int),
        camera: int,
        image: wp.array4d(dtype=wp.int32),
    ):
        """image[world, y, x] = (object id, object type) of the pixel, (-1, -1) if none."""
        world, pixel = wp.tid()
        width = image.shape[2]
        value = ids[world, address[camera] + pixel]
        y, x = pixel // width, pixel % width
        image[world, y, x, 0] = value[0]
        image[world, y, x, 1] = value[1]

    return {"unpack_rgb": unpack_rgb, "planar_depth": planar_depth, "segmentation": segmentation}
