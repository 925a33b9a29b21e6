"""The Warp kernels of the manipulation tasks' rewards, defined on first use.

A reward written as one kernel reads MuJoCo Warp's arrays and writes every world's reward
in one pass, on Warp's CPU device and on CUDA alike, where the same formula in array code
would make an array per operation. Each kernel computes in float32 what the task's array
code computes, operation for operation, so its rewards equal the CPU task's to float32.
Importing this module needs no Warp: `kernels()` imports it once an environment is built.
"""

from types import SimpleNamespace

__all__ = ["kernels"]

_kernels: SimpleNamespace | None = None


def kernels() -> SimpleNamespace:
    """The reward kernels, compiled by Warp at their first launch.

    Returns:
      A namespace with `lift_reward` (documented on it).
    """
    global _kernels
    if _kernels is None:
        import warp

        _kernels = SimpleNamespace(lift_reward=_lift_reward(warp))
    return _kernels


def _lift_reward(wp):
    @wp.kernel(module="unique")
    def lift_reward(
        vertex_sites: wp.array(dtype=wp.int32),
        site_xpos: wp.array2d(dtype=wp.vec3),
        touches: wp.array(dtype=wp.bool),
        lift_height: wp.float32,
        reward: wp.array(dtype=wp.float32),
    ):
        """reward[world] = `Lift`'s reward: the height of the prop's lowest vertex site as a
        linear ramp, 0 at the table (height 0) and 1 from `lift_height` up, while the hand
        touches the prop (touches[world]); 0 otherwise."""
        world = wp.tid()
        height = site_xpos[world, vertex_sites[0]][2]
        for k in range(1, vertex_sites.shape[0]):
            height = wp.min(height, site_xpos[world, vertex_sites[k]][2])
        value = wp.float32(0.0)
        if height >= lift_height:
            value = wp.float32(1.0)
        else:
            # `rewards.tolerance`'s linear sigmoid with margin lift_height, value 0 there.
            distance = (lift_height - height) / lift_height
            if wp.abs(distance) < wp.float32(1.0):
                value = wp.float32(1.0) - distance
        if not (height > wp.float32(0.0) and touches[world]):
            value = wp.float32(0.0)
        reward[world] = value

    return lift_reward
