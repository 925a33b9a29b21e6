"""What an agent observes in a manipulation task: ground-truth features or camera images."""

import dataclasses


@dataclasses.dataclass(frozen=True)
class ObservationSettings:
    """Which observables a task enables besides the arm's and hand's proprioception.

    Attributes:
      features: the props' poses and velocities and the task's own features (the target
        position, the desired order of the bricks).
      camera: images from the arena's `front_close` camera, under the key 'front_close'.
      camera_height: image height in pixels.
      camera_width: image width in pixels.
    """

    features: bool
    camera: bool
    camera_height: int = 84
    camera_width: int = 84


FEATURES = ObservationSettings(features=True, camera=False)
VISION = ObservationSettings(features=False, camera=True)
