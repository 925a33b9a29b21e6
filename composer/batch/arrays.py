"""The array namespace batched task code runs in, and what a batch hands its caller.

Everything a batch computes lives on its Warp device. Task code (rewards, discounts,
terminations, observables, controls) reads MuJoCo Warp's arrays through views that share
their memory, in one array namespace of the Python array API standard (`array_api_compat`):

| device     | array_type          | namespace of task code                              |
|------------|---------------------|-----------------------------------------------------|
| Warp's CPU | anything but torch  | NumPy: views of the Warp arrays (`Array.numpy()`)   |
| Warp's CPU | "torch"             | torch CPU tensors (`warp.to_torch`)                 |
| CUDA       | any                 | torch CUDA tensors (`warp.to_torch`)                |

`namespace="torch"` picks torch on the CPU device too (the code path CUDA runs). On CUDA,
torch runs on Warp's stream of the device, so that torch's and Warp's work on the same
memory runs in order. torch's current stream is per thread: the bridge sets it for the
thread that builds the batch, and `reset` and `step` set it again for the thread that calls
them (another thread may step the batch).

What `reset` and `step` hand out is converted from that namespace without a copy, except
for `array_type="numpy"` on CUDA, which copies to the host:

| array_type | the caller gets                                  |
|------------|--------------------------------------------------|
| "numpy"    | NumPy arrays                                     |
| "warp"     | `warp.array`s on the batch's device              |
| "torch"    | `torch.Tensor`s on the batch's device            |
| "jax"      | `jax.Array`s on the batch's device (DLPack)      |

Each step's results are new arrays: a result the caller keeps is never overwritten by a
later step. torch and JAX are imported only when used, and are not dependencies of `[warp]`.
"""

from types import ModuleType
from typing import Any

import numpy as np

__all__ = ["ARRAY_TYPES", "ArrayBridge", "array_library", "check_array_type", "numpy_namespace"]

#: The values of `BatchEnvironment(array_type=...)`.
ARRAY_TYPES = ("numpy", "warp", "torch", "jax")

# The top-level module of an array's type -> the library `array_library` names.
_LIBRARIES = {"warp": "warp", "torch": "torch", "jax": "jax", "jaxlib": "jax"}


def array_library(values) -> str:
    """'warp', 'torch' or 'jax' for an array of that library (none is imported), else ''."""
    return _LIBRARIES.get(type(values).__module__.split(".", 1)[0], "")


def row_items(rows: np.ndarray) -> np.ndarray:
    """`rows` (n, w), each row contiguous, as a NumPy (n,) view with one item per row: a
    row then copies as one block rather than entry by entry (about half the time for a
    world's few floats, and a fraction for its kilobytes of MuJoCo Warp data)."""
    return rows.view(np.dtype((np.void, rows.itemsize * rows.shape[-1])))[:, 0]


def check_array_type(array_type: str) -> str:
    """Returns `array_type` if it is one of `ARRAY_TYPES`; raises ValueError naming it."""
    if array_type not in ARRAY_TYPES:
        raise ValueError(f"array_type: expected one of {list(ARRAY_TYPES)}, got {array_type!r}")
    return array_type


def _import(name: str, purpose: str) -> ModuleType:
    try:
        return __import__(name)
    except ImportError as error:
        raise ImportError(f"{purpose} needs {name} installed ({error})") from error


#: The first NumPy whose own namespace follows the array API standard as task code uses it
#: (`astype` with `copy` and `device`, `isdtype`, creation functions taking `device`).
NUMPY_ARRAY_API = (2, 1)


def numpy_namespace():
    """The array-API namespace of NumPy task code: `array_api_compat`'s NumPy where that is
    installed (the extras `[warp]` and `[test]` have it), else NumPy itself from 2.1 on, so
    that the CPU batch needs nothing beyond the runtime dependencies.

    Raises:
      ImportError: for an older NumPy without `array-api-compat`, saying what to install.
    """
    try:
        import array_api_compat
    except ImportError:
        version = tuple(int(part) for part in np.__version__.split(".")[:2])
        if version >= NUMPY_ARRAY_API:
            return np
        raise ImportError(
            f"batched task code runs in NumPy's array-API namespace, which NumPy "
            f"{np.__version__} has only through array-api-compat: pip install "
            f"'numpy>={NUMPY_ARRAY_API[0]}.{NUMPY_ARRAY_API[1]}' or array-api-compat"
        ) from None
    return array_api_compat.array_namespace(np.zeros(0))


class ArrayBridge:
    """Views of Warp arrays in the task namespace `xp`, and conversions out of it.

    Args:
      warp: the `warp` module.
      device: the Warp device of the batch.
      array_type: one of `ARRAY_TYPES`: what `hand_out` converts to.
      namespace: "numpy" or "torch" for task code, or None for the table above (NumPy
        cannot be chosen on CUDA).

    Attributes:
      xp: the array-API namespace of task code (`numpy_namespace()` or `array_api_compat`'s
        torch).
      library: "numpy" or "torch", the library behind `xp`.
      xp_device: the batch's device as `xp` names it (for `xp.zeros(..., device=)`).

    Raises:
      ImportError: when torch (needed on CUDA or for array_type "torch") or JAX (for
        array_type "jax") is missing; the message names it.
    """

    def __init__(self, warp, device, array_type: str, namespace: str | None = None):
        self._wp = warp
        self.device = device
        self._torch_stream = None
        self.array_type = check_array_type(array_type)
        if warp is None:  # `host`: NumPy memory, no Warp
            if array_type == "warp" or namespace not in (None, "numpy"):
                raise ValueError(
                    f"array_type={array_type!r}, namespace={namespace!r}: the CPU batch "
                    "(mujoco.batch) computes in NumPy and hands out 'numpy', 'torch' or "
                    "'jax'; Warp arrays and torch task code need a Warp device "
                    "(device='warp-cpu' or 'cuda:0')"
                )
            self.library = "numpy"
            self.xp = numpy_namespace()
            self.xp_device = "cpu"
            if array_type == "jax":
                _import("jax", "array_type='jax'")
            return
        if namespace not in (None, "numpy", "torch") or (namespace == "numpy" and device.is_cuda):
            raise ValueError(
                f"namespace: expected None, 'torch' or (on Warp's CPU device) 'numpy', got "
                f"{namespace!r} on {device}"
            )
        if namespace is None:
            namespace = "torch" if device.is_cuda or array_type == "torch" else "numpy"
        self.library = namespace
        if self.library == "torch":
            purpose = "batched task code on CUDA" if device.is_cuda else "array_type='torch'"
            self._torch = _import("torch", purpose)
            import array_api_compat

            self.xp = array_api_compat.array_namespace(self._torch.zeros(0))
            self.xp_device = self._torch.device(str(device))
            if device.is_cuda:
                # torch's work on the batch's arrays and Warp's must be ordered: torch runs on
                # Warp's stream of the device (Warp cannot record CUDA graphs on torch's
                # legacy default stream).
                self._torch_stream = warp.stream_to_torch(warp.get_stream(device))
                self.use_stream()
        else:
            self.xp = numpy_namespace()
            self.xp_device = "cpu"
        if array_type == "jax":
            _import("jax", "array_type='jax'")

    @classmethod
    def host(cls, array_type: str, namespace: str | None = None) -> "ArrayBridge":
        """The bridge of a batch whose memory is NumPy's (`mujoco.batch`): task code runs in
        NumPy, and `hand_out` gives NumPy arrays, or torch or JAX ones made from them.

        Raises:
          ValueError: for array_type "warp" or namespace "torch", which need Warp.
        """
        return cls(None, "cpu", array_type, namespace)

    def use_stream(self) -> None:
        """Makes Warp's stream of the device the calling thread's current torch stream (on
        CUDA; nothing elsewhere). torch keeps one current stream per thread."""
        stream = self._torch_stream
        if stream is not None and self._torch.cuda.current_stream(stream.device) != stream:
            self._torch.cuda.set_stream(stream)

    # Warp -> namespace.

    def view(self, array, shape: tuple[int, ...]) -> Any:
        """The contiguous Warp `array` as an `xp` array of `shape`, sharing its memory."""
        if self._wp is None:
            return np.reshape(array, shape)
        if self.library == "torch":
            return self._wp.to_torch(array).reshape(shape)
        return array.numpy().reshape(shape)

    def empty(self, shape: tuple[int, ...], dtype) -> tuple[Any, Any]:
        """A new Warp array on the device and its `xp` view: `(warp_array, view)` (on the
        host: one NumPy array, twice)."""
        if self._wp is None:
            array = np.zeros(shape, dtype)
            return array, array
        array = self._wp.zeros(
            shape, dtype=self._wp.dtype_from_numpy(np.dtype(dtype)), device=self.device
        )
        return array, self.view(array, shape)

    def asarray(self, values, dtype=None) -> Any:
        """Host or device `values` as an `xp` array on the device (host values: one copy)."""
        if self.library == "torch":
            torch = self._torch
            if array_library(values) == "warp":
                values = self._wp.to_torch(values)
            elif isinstance(values, np.ndarray) and not values.flags.writeable:
                values = values.copy()  # torch takes only writeable NumPy memory
            tensor = torch.as_tensor(values, device=str(self.device))
            return tensor if dtype is None else tensor.to(_torch_dtype(torch, dtype))
        if array_library(values) == "warp":
            values = values.numpy()
        return np.asarray(values, dtype=dtype)

    # Namespace -> Warp.

    def to_warp(self, values, dtype=None) -> Any:
        """An `xp` array as a Warp array sharing its memory (contiguous arrays only)."""
        wp = self._wp
        if self.library == "torch":
            return wp.from_torch(values.contiguous(), dtype=dtype)
        values = np.ascontiguousarray(values)
        if dtype is None:
            dtype = wp.dtype_from_numpy(values.dtype)
        return wp.array(values, dtype=dtype, device=self.device, copy=False)

    # Namespace -> the caller.

    def hand_out(self, values) -> Any:
        """An `xp` array as `array_type` (see the module docstring)."""
        kind = self.array_type
        if kind == "numpy":
            if self.library == "torch":
                return values.cpu().numpy()
            return np.asarray(values)
        if kind == "torch":
            if self.library == "torch":
                return values
            return _import("torch", "array_type='torch'").from_numpy(np.asarray(values))
        if self._wp is None:  # "jax", from host memory
            return _import("jax", "array_type='jax'").numpy.asarray(values)
        array = self.to_warp(values)
        return self._wp.to_jax(array) if kind == "jax" else array

    def to_host(self, values) -> np.ndarray:
        """An array of any namespace (torch, JAX, Warp, NumPy, or anything NumPy reads) as a
        NumPy array: a device-to-host copy for one on CUDA."""
        if hasattr(values, "detach") and hasattr(values, "cpu"):  # torch
            return values.detach().cpu().numpy()
        if hasattr(values, "numpy"):  # Warp
            return values.numpy()
        return np.asarray(values)


def _torch_dtype(torch, dtype):
    return getattr(torch, np.dtype(dtype).name) if np.dtype(dtype) != bool else torch.bool
