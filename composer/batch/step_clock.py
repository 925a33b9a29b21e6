"""Where a batch's control step spends its time, and how often it copies to the host.

`StepClock` times the parts of `BatchEnvironment.step` on the wall clock. Each part ends
with a synchronisation of the batch's device (`warp.synchronize_device`), so the device
work a part launched is counted in that part, on CUDA as on Warp's CPU device; the parts
are laps of one clock, so together they cover the step from its first line to its last.
Timing synchronises, and so slows a CUDA step down: a benchmark measures the throughput
in a run without a clock and the split in another.

`HostCopies` counts the calls that copy a device array to the host while it is active
(Warp's `numpy`/`list`, torch's `cpu`/`numpy`/`item`/`tolist`/`__bool__`): each one
synchronises a CUDA device. On Warp's CPU device those calls cost no copy, but they are
the ones that would.
"""

import time
from typing import Any

__all__ = ["PARTS", "HostCopies", "StepClock"]

#: The parts of a control step, in the order `BatchEnvironment.step` runs them.
#: action: the action's checks and its copy to the device; task: the `BatchTask` hooks
#: (`before_step`, reward, discount, termination); physics: the physics sub-steps;
#: start_episodes: the start of the worlds whose episode ended; counters: step counts,
#: time limits, step types; observations: the observation reads; refill: the
#: initial-state slots' bookkeeping and uploads, the producer wait included; hand_out:
#: the conversion of the results to `array_type`.
PARTS = (
    "action",
    "task",
    "physics",
    "start_episodes",
    "counters",
    "observations",
    "refill",
    "hand_out",
)


class StepClock:
    """Wall seconds per part of the control steps timed since the clock was made.

    Args:
      synchronize: a function that waits until the batch's device is idle.

    Attributes:
      seconds: part name (`PARTS`) -> seconds spent, all steps together.
      steps: the number of steps timed.
    """

    def __init__(self, synchronize):
        self._synchronize = synchronize
        self.seconds: dict[str, float] = dict.fromkeys(PARTS, 0.0)
        self.steps = 0
        self._last = 0.0

    def start(self) -> None:
        """Starts a step: waits for the device, then reads the clock."""
        self._synchronize()
        self.steps += 1
        self._last = time.perf_counter()

    def lap(self, part: str) -> None:
        """Ends `part` (one of `PARTS`): waits for the device and adds the time since the
        last lap (or `start`)."""
        self._synchronize()
        now = time.perf_counter()
        self.seconds[part] += now - self._last
        self._last = now

    def milliseconds_per_step(self) -> dict[str, float]:
        """Each part's mean milliseconds per timed step."""
        steps = max(self.steps, 1)
        return {part: 1e3 * seconds / steps for part, seconds in self.seconds.items()}


class _Stopped:
    """The clock of an untimed environment: every call does nothing."""

    def start(self) -> None:
        pass

    def lap(self, part: str) -> None:
        pass


STOPPED = _Stopped()


class HostCopies:
    """Counts device-to-host copies while active, as a context manager.

    Patches the copying methods of `warp.array` (and of `torch.Tensor` when torch is
    installed) for the duration of the `with` block; not thread-safe, for tests and
    benchmarks only.

    Attributes:
      count: the copies counted so far.
    """

    def __init__(self):
        self.count = 0
        self._originals: dict[tuple[Any, str], Any] = {}

    def __enter__(self) -> "HostCopies":
        import warp

        self._originals = {
            (warp.array, name): getattr(warp.array, name) for name in ("numpy", "list")
        }
        try:
            import torch
        except ImportError:
            torch = None
        if torch is not None:
            for name in ("cpu", "numpy", "item", "tolist", "__bool__"):
                self._originals[(torch.Tensor, name)] = getattr(torch.Tensor, name)
        for (owner, name), original in self._originals.items():
            setattr(owner, name, self._counted(original))
        return self

    def _counted(self, original):
        def counted(*args, **kwargs):
            self.count += 1
            return original(*args, **kwargs)

        return counted

    def __exit__(self, *exc_info) -> None:
        for (owner, name), original in self._originals.items():
            setattr(owner, name, original)
        self._originals = {}
