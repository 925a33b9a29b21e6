"""Camera observables of a batch, rendered for every world by MuJoCo Warp's ray tracer.

`BatchCameras` renders the cameras that enabled camera observables (`MJCFCamera`) use, and
only those, once per observation: one `mujoco_warp` render context holds every such camera
at its observable's size. Each observable then reads its own image for every world, with
the CPU observable's dtype and shape behind a leading num_envs axis:

| observable | one world's image |
|---|---|
| RGB | (height, width, 3) uint8 |
| `depth=True` | (height, width, 1) float32: metres along the camera's axis |
| `segmentation=True` | (height, width, 2) int32: (geom id, `mjOBJ_GEOM`), -1 where empty |

The images are not the OpenGL renderer's bit for bit: a ray tracer shades each pixel's
centre where OpenGL rasterises, and lights without OpenGL's shadows and reflections. Where a
pixel sees nothing, depth is the far clipping distance (`vis.map.zfar` times the model's
extent), as OpenGL's depth buffer gives it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any

import mujoco
import numpy as np

from composer.batch import _warp
from composer.batch.kernels import kernels
from composer.observation.observable.mjcf import MJCFCamera

__all__ = ["BatchCameras"]

_DTYPES = {"rgb": np.uint8, "depth": np.float32, "segmentation": np.int32}


@dataclasses.dataclass(frozen=True)
class _CameraImage:
    """One camera observable's image in the render context."""

    name: str
    camera_index: int  # the camera's position in the render context, not its model id
    height: int
    width: int
    kind: str  # "rgb", "depth" or "segmentation"


def _visible_geom_groups() -> list[int]:
    """The geom groups MuJoCo's default visual options show (`mjvOption.geomgroup`), which
    the CPU camera observables render."""
    return [group for group, shown in enumerate(mujoco.MjvOption().geomgroup) if shown]


def _kind(observable: MJCFCamera) -> str:
    if observable.depth:
        return "depth"
    if observable.segmentation:
        return "segmentation"
    return "rgb"


def _check_renderable(name: str, observable: MJCFCamera) -> None:
    """Raises ValueError naming `name` for an option the ray tracer cannot follow."""
    for option in ("scene_option", "render_flag_overrides"):
        value = getattr(observable, option)
        if value is not None:
            raise ValueError(
                f"observable {name!r}: option {option}={value!r} is not supported in a batch "
                "(expected None); batched cameras render MuJoCo's default visual options"
            )


class BatchCameras:
    """The camera observables of a batch, rendered together once per observation.

    Args:
      observables: the enabled camera observables by key.
      physics: the `BatchPhysics` whose worlds they see.

    Raises:
      ValueError: for an observable with a scene option or render flag overrides, or for
        two observables of one camera with different image sizes (the render context
        renders each camera at one size).
    """

    def __init__(self, observables: Mapping[str, MJCFCamera], physics):
        modules = _warp.load()
        wp, mjw = modules.warp, modules.mujoco_warp
        self._wp, self._mjw, self._physics = wp, mjw, physics
        sizes: dict[int, tuple[str, int, int]] = {}
        images = []
        for name, observable in observables.items():
            _check_renderable(name, observable)
            camera_id = int(physics.host.bind(observable.mjcf_element).element_id)
            size = (observable.height, observable.width)
            first = sizes.setdefault(camera_id, (name, *size))
            if first[1:] != size:
                raise ValueError(
                    f"observable {name!r}: camera {observable.mjcf_element.full_identifier!r} "
                    f"is rendered at {size[0]}x{size[1]} here and at {first[1]}x{first[2]} "
                    f"by {first[0]!r}; a batch renders each camera at one size"
                )
            images.append((name, camera_id, size, _kind(observable)))
        cameras = list(sizes)
        self._camera_ids = tuple(cameras)
        kinds = {
            kind: [any(c == camera and k == kind for _, c, _, k in images) for camera in cameras]
            for kind in ("rgb", "depth", "segmentation")
        }
        self._images = [
            _CameraImage(name, cameras.index(camera), *size, kind)
            for name, camera, size, kind in images
        ]
        model = physics.mj_model
        self._far = float(model.vis.map.zfar * model.stat.extent)
        with wp.ScopedDevice(physics.device):
            self._context = mjw.create_render_context(
                model,
                nworld=physics.num_envs,
                cam_res=[(sizes[camera][2], sizes[camera][1]) for camera in cameras],
                render_rgb=kinds["rgb"],
                render_depth=kinds["depth"],
                render_seg=kinds["segmentation"],
                enabled_geom_groups=_visible_geom_groups(),
                cam_active=cameras,
            )
            self._outputs = {image.name: self._output(image) for image in self._images}

    def _output(self, image: _CameraImage) -> tuple[Any, Any]:
        channels = {"rgb": 3, "depth": 1, "segmentation": 2}[image.kind]
        shape = (self._physics.num_envs, image.height, image.width, channels)
        return self._physics.arrays.empty(shape, _DTYPES[image.kind])

    @property
    def camera_ids(self) -> tuple[int, ...]:
        """The model ids of the cameras rendered: those some observable uses, once each."""
        return self._camera_ids

    @property
    def names(self) -> list[str]:
        """The keys of the camera observables, in the order given."""
        return [image.name for image in self._images]

    def dtype(self, name: str) -> np.dtype:
        """The NumPy dtype of the observable `name`'s images."""
        kind = next(image.kind for image in self._images if image.name == name)
        return np.dtype(_DTYPES[kind])

    def render(self) -> None:
        """Renders every camera in every world, from the worlds' current poses."""
        wp, mjw, physics = self._wp, self._mjw, self._physics
        model, data, context = physics.warp_model, physics.warp_data, self._context
        k = kernels()
        with wp.ScopedDevice(physics.device):
            mjw.refit_bvh(model, data, context)
            mjw.render(model, data, context)
            for image in self._images:
                output = self._outputs[image.name][0]
                dim = (physics.num_envs, image.height * image.width)
                if image.kind == "rgb":
                    wp.launch(
                        k.unpack_rgb,
                        dim=dim,
                        inputs=[context.rgb_data, context.rgb_adr, image.camera_index],
                        outputs=[output],
                    )
                elif image.kind == "depth":
                    wp.launch(
                        k.planar_depth,
                        dim=dim,
                        inputs=[
                            context.depth_data,
                            context.depth_adr,
                            image.camera_index,
                            self._far,
                        ],
                        outputs=[output],
                    )
                else:
                    wp.launch(
                        k.segmentation,
                        dim=dim,
                        inputs=[context.seg_data, context.seg_adr, image.camera_index],
                        outputs=[output],
                    )

    def readers(self) -> dict[str, Callable[[], Any]]:
        """A reader per observable: the images of the last `render`, an `xp` view."""
        return {name: (lambda view=view: view) for name, (_, view) in self._outputs.items()}

    def close(self) -> None:
        """Does nothing: the render context's device memory goes with the object (kept so
        that both devices' cameras close alike, `composer.batch.gl_cameras`)."""
