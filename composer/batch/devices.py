"""Which physics runs a batch's worlds: a `BatchEnvironment(device=...)` name, resolved.

| device        | physics                                         | floats  |
|---------------|-------------------------------------------------|---------|
| "cpu"         | `mujoco.batch` on C threads (MuJoCo >= 4.0)     | float64 |
| "warp-cpu"    | MuJoCo Warp on Warp's CPU device (extra [warp]) | float32 |
| "cuda", "cuda:N" | MuJoCo Warp on that GPU (extra [warp])       | float32 |

None picks "cuda:0" when MuJoCo Warp is installed and Warp sees a GPU, else "cpu". The CPU
batch needs nothing beyond MuJoCo; its worlds compute what `composer.Environment` computes,
bit for bit. Warp's CPU device computes what its CUDA device computes, and serves tests of
the CUDA code paths on machines without a GPU.
"""

from typing import NamedTuple

from composer.batch import _warp

__all__ = ["CPU", "WARP_CPU", "Device", "resolve"]

#: The CPU batch, on `mujoco.batch`.
CPU = "cpu"
#: MuJoCo Warp's CPU device.
WARP_CPU = "warp-cpu"


class Device(NamedTuple):
    """A resolved batch device.

    Attributes:
      name: the name a user passes (`CPU`, `WARP_CPU`, "cuda:0", ...).
      warp_name: the Warp device name ("cpu", "cuda:0"), or None for the CPU batch.
    """

    name: str
    warp_name: str | None

    @property
    def on_warp(self) -> bool:
        """Whether MuJoCo Warp runs the worlds."""
        return self.warp_name is not None


def resolve(device: str | None) -> Device:
    """The `Device` a `BatchEnvironment(device=...)` names.

    Raises:
      ValueError: for a name that is none of the table's, naming the choices.
    """
    if device is None:
        if _warp.is_available() and _warp.load().warp.get_cuda_device_count() > 0:
            return Device("cuda:0", "cuda:0")
        return Device(CPU, None)
    if device == CPU:
        return Device(CPU, None)
    if device == WARP_CPU:
        return Device(WARP_CPU, "cpu")
    if isinstance(device, str) and (device == "cuda" or device.startswith("cuda:")):
        return Device(device, device)
    raise ValueError(
        f"device: expected {CPU!r} (mujoco.batch), {WARP_CPU!r} (MuJoCo Warp's CPU device) "
        f"or a CUDA device such as 'cuda:0', got {device!r}"
    )
