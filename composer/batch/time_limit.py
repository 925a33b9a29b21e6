"""The control step at which a batch's time limit ends an episode, as C MuJoCo's clock has it.

C MuJoCo's `time` is a float64 to which every physics step adds the timestep, so after s
steps it is the rounded running sum, not s * timestep. A CPU environment ends an episode at
the first control step whose time reaches the limit; the batch counts control steps on the
device and ends it at the same one, whatever float32's `time` there.

The running sum is not summed step by step (a long time limit is billions of steps): within
one binade of float64 (the numbers from 2**e up to 2**(e+1)) every number is a multiple of
the same spacing u, so adding the timestep moves by u * (timestep / u rounded to an
integer). Only where timestep / u ends in exactly one half does the rounding (to even)
depend on the sum itself; it then alternates for at most one step and settles. Two equal
increments in a row therefore mean the same increment until the binade ends, which is
jumped over in one multiplication (exact: the result is a multiple of u in the binade).
"""

import math

__all__ = ["NO_LIMIT", "control_step_limit"]

#: A step count no episode reaches: the limit of an infinite time limit (int32 counters).
NO_LIMIT = 2**31 - 1


def control_step_limit(time_limit: float, physics_timestep: float, n_sub_steps: int) -> int:
    """The number of control steps after which C MuJoCo's float64 `time` reaches `time_limit`.

    Args:
      time_limit: seconds, >= 0, or infinity (no limit).
      physics_timestep: the model's timestep in seconds, > 0.
      n_sub_steps: physics steps per control step, >= 1.

    Returns:
      The smallest number of control steps c with time(c * n_sub_steps) >= time_limit, or
      `NO_LIMIT` for an infinite limit.

    Raises:
      ValueError: naming `time_limit`, when it needs `NO_LIMIT` control steps or more (the
        device counts in int32). Below that bound the sum always reaches the limit: adding
        the timestep stops moving it only past 2**52 timesteps.
    """
    if math.isinf(time_limit):
        return NO_LIMIT
    if time_limit / (physics_timestep * n_sub_steps) >= NO_LIMIT - 1:
        raise ValueError(
            f"time_limit: {time_limit!r} s is {NO_LIMIT - 1} control steps of "
            f"{physics_timestep * n_sub_steps!r} s or more, beyond the device's int32 step "
            "counters; pass float('inf') for no time limit"
        )
    sub_steps = _physics_steps_to_reach(time_limit, physics_timestep)
    return -(-sub_steps // n_sub_steps)


def _physics_steps_to_reach(limit: float, dt: float) -> int:
    """The smallest s such that the float64 running sum of s timesteps is >= `limit`."""
    time, steps = 0.0, 0
    while time < limit:
        once = time + dt
        twice = once + dt
        steps += 1
        # Differences of floats within a factor of two of each other are exact.
        increment = twice - once
        binade = math.frexp(once)[1]
        if (
            once - time == increment
            and math.frexp(time)[1] == binade == math.frexp(twice)[1]
            and once < limit
        ):
            end = min(limit, math.ldexp(1.0, binade))
            # Every sum jumped over stays below the limit and in the binade.
            jumps = max(0, math.floor((end - once) / increment) - 1)
            once += jumps * increment
            steps += jumps
        time = once
    return steps
