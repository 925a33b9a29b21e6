"""Episode videos: run a policy (or replay actions) on an environment and write an mp4 or gif.

Needs the `video` extra (`pip install 'mujoco-composer[video]'`: imageio and
imageio-ffmpeg); imageio is imported on first use, never by `import composer`.

Frames and timing, the rule both `record_video` and `composer.gym.video_recorder` follow:
a video holds one frame for the state after `reset()` and one after every step, so an
episode of N steps gives N + 1 frames. It plays in real time: the frame rate is
`1 / control_timestep` rounded to two decimals (50 for 0.02 s, 33.33 for 0.03 s). An mp4
stores that rate exactly as a fraction; a gif stores each frame's duration in whole
hundredths of a second, so 50 fps (20 ms) is exact and 33.33 fps plays as 30 ms frames, and
Pillow's gif writer merges consecutive identical frames into one longer frame.
"""

from __future__ import annotations

import math
import numbers
import os
import pathlib
from collections.abc import Iterable
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from composer.episode_tally import EpisodeTally, Policy
from composer.utils import argument_checks

if TYPE_CHECKING:
    import composer


EXTENSIONS = (".mp4", ".gif")
_NO_ACTION = object()
_INSTALL_HINT = "pip install 'mujoco-composer[video]' (imageio and imageio-ffmpeg)"


class EpisodeVideo(NamedTuple):
    """A written episode video.

    Attributes:
      path: the video file.
      frames: frames handed to the writer, `steps + 1` (a gif decodes to fewer when
        consecutive frames are identical; see the module docstring).
      fps: frames per second.
      episode_return: the sum of the episode's rewards.
      steps: environment steps taken.
    """

    path: pathlib.Path
    frames: int
    fps: float
    episode_return: float
    steps: int


def fps_for(control_timestep: float) -> float:
    """Frames per second that play one frame per control step in real time (two decimals).

    Raises:
      ValueError: if `control_timestep` is not a positive number of seconds.
    """
    seconds = argument_checks.number(above=0, unit="seconds", control_timestep=control_timestep)
    return round(1.0 / seconds, 2)


def _has_no_time_limit(environment) -> bool:
    """Whether `environment` says it has no time limit (one that does not say is assumed to)."""
    time_limit = getattr(environment, "time_limit", None)
    return isinstance(time_limit, numbers.Real) and math.isinf(time_limit)


def video_extension(path: str | os.PathLike) -> str:
    """The lower-case extension of `path`, checked against `EXTENSIONS`.

    Raises:
      ValueError: naming `path` when its extension is not .mp4 or .gif.
    """
    suffix = pathlib.Path(path).suffix.lower()
    if suffix not in EXTENSIONS:
        raise ValueError(
            f"path {os.fspath(path)!r}: unknown video extension {suffix or '(none)'!r}; "
            f"expected one of {list(EXTENSIONS)}"
        )
    return suffix


def check_frame_size(extension: str, *, width: int, height: int) -> None:
    """Raises ValueError naming `width` or `height` if an `extension` video cannot hold it.

    An mp4 (H.264 with yuv420p colour) needs an even width and height; a gif takes any.
    """
    if extension == ".mp4" and (width % 2 or height % 2):
        odd = "width" if width % 2 else "height"
        raise ValueError(
            f"{odd}: an mp4 needs an even frame size (H.264, yuv420p), got {width}x{height}"
        )


class VideoWriter:
    """Writes RGB frames to an mp4 (H.264, through imageio-ffmpeg) or a gif (through Pillow).

    Args:
      path: the file to write; its extension (.mp4 or .gif) picks the format. An
        existing file is replaced.
      fps: frames per second, > 0.

    Every frame must be a (height, width, 3) uint8 array of the first frame's size; an mp4
    needs an even width and height (H.264 with yuv420p colour). The file is complete once
    `close()` returns; the writer is also a context manager.

    Raises:
      ValueError: for an unknown extension or a non-positive fps.
      ImportError: when imageio or imageio-ffmpeg is not installed.
    """

    def __init__(self, path: str | os.PathLike, fps: float):
        self._extension = video_extension(path)
        self.path = pathlib.Path(path)
        self.fps = argument_checks.number(above=0, fps=fps)
        self.frames = 0
        self._shape = None
        self._writer = self._open()

    def _open(self):
        try:
            if self._extension == ".gif":
                import imageio.v3 as iio

                return iio.imopen(self.path, "w", plugin="pillow")
            import imageio.v2 as iio
            import imageio_ffmpeg  # noqa: F401  (a clear error here rather than inside imageio)
        except ImportError as error:
            raise ImportError(f"writing {self.path.name} needs {_INSTALL_HINT}") from error
        return iio.get_writer(
            self.path,
            format="FFMPEG",
            mode="I",
            fps=self.fps,
            codec="libx264",
            pixelformat="yuv420p",
            macro_block_size=1,
            ffmpeg_log_level="error",
        )

    def append(self, frame: np.ndarray) -> None:
        """Adds one frame.

        Raises:
          ValueError: if `frame` is not (height, width, 3) uint8, differs in size from the
            first frame, or (mp4) has an odd width or height.
        """
        frame = np.asarray(frame)
        if frame.ndim != 3 or frame.shape[2] != 3 or frame.dtype != np.uint8:
            raise ValueError(
                f"frame {self.frames}: expected a (height, width, 3) uint8 RGB image, "
                f"got shape {frame.shape} dtype {frame.dtype}"
            )
        if self._shape is None:
            check_frame_size(self._extension, width=frame.shape[1], height=frame.shape[0])
            self._shape = frame.shape
        elif frame.shape != self._shape:
            raise ValueError(
                f"frame {self.frames}: expected shape {self._shape} like the first frame, "
                f"got {frame.shape}"
            )
        if self._extension == ".gif":
            # Pillow takes frame durations in milliseconds.
            self._writer.write(frame, duration=1000.0 / self.fps, loop=0, is_batch=False)
        else:
            self._writer.append_data(frame)
        self.frames += 1

    def close(self) -> None:
        """Finishes the file. Further calls do nothing."""
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def __enter__(self) -> VideoWriter:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()


def record_video(
    environment: composer.Environment,
    path: str | os.PathLike,
    policy: Policy | None = None,
    *,
    actions: Iterable | None = None,
    camera_id: int | str = -1,
    width: int = 320,
    height: int = 240,
    max_steps: int | None = None,
) -> EpisodeVideo:
    """Resets `environment`, runs one episode and writes it to `path` as a video.

    Exactly one of `policy` and `actions` drives the episode. A `policy` is called with
    each TimeStep (the FIRST one included) and returns the next action; the episode runs
    until a LAST TimeStep or `max_steps` steps, so an environment without a time limit
    (`environment.time_limit` is inf) needs `max_steps`, or the recording might never end.
    `actions` are applied in order until they run out, the episode ends (the rest are not
    used; `steps` says how many were), or `max_steps`.

    The video has `steps + 1` frames (the reset frame, then one per step) at
    `fps_for(environment.control_timestep())` frames per second; see the module docstring.

    Args:
      environment: a `composer.Environment` (anything with `reset`, `step`,
        `control_timestep()` and `physics.render` works).
      path: the file to write; `.mp4` or `.gif` picks the format.
      policy: a callable TimeStep -> action.
      actions: an iterable of actions to replay instead of a policy.
      camera_id: a camera name or index in the model; -1 (default) is the free camera.
      width, height: frame size in pixels, at most the model's offscreen buffer
        (`<visual><global offwidth offheight>`, 640x480 unless set); even for mp4.
      max_steps: stop after this many steps even if the episode goes on.

    Returns:
      An `EpisodeVideo`: the path, frames written, fps, the sum of rewards and the number
      of steps taken.

    Raises:
      ValueError: naming the argument for an unknown extension, a non-positive or (mp4)
        odd width or height, a non-positive `max_steps`, no `max_steps` for a policy on an
        environment without a time limit, an unknown camera, or when neither or both of
        `policy` and `actions` are given. Nothing is written then.
      ImportError: when imageio or imageio-ffmpeg is not installed.
    """
    width = argument_checks.integer(width=width)
    height = argument_checks.integer(height=height)
    if max_steps is not None:
        max_steps = argument_checks.integer(max_steps=max_steps)
    if (policy is None) == (actions is None):
        raise ValueError(
            "policy, actions: expected exactly one of a policy (TimeStep -> action) or a "
            f"list of actions to replay, got {'both' if policy is not None else 'neither'}"
        )
    if policy is not None and not callable(policy):
        raise ValueError(f"policy: expected a callable TimeStep -> action, got {policy!r}")
    check_frame_size(video_extension(path), width=width, height=height)
    if policy is not None and max_steps is None and _has_no_time_limit(environment):
        raise ValueError(
            "max_steps: expected a number of steps for a policy on an environment without a "
            "time limit (time_limit=inf), got None: the recording would go on until the task "
            "ends the episode, perhaps never; pass max_steps, or give the environment a "
            "time_limit"
        )
    fps = fps_for(environment.control_timestep())

    timestep = environment.reset()
    # Rendering the reset frame first checks the camera and size before a file is created.
    first_frame = environment.physics.render(height=height, width=width, camera_id=camera_id)
    remaining = None if actions is None else iter(actions)
    tally = EpisodeTally()
    tally.start_episode()
    with VideoWriter(path, fps) as writer:
        writer.append(first_frame)
        while not timestep.last() and (max_steps is None or tally.steps < max_steps):
            action = policy(timestep) if remaining is None else next(remaining, _NO_ACTION)
            if action is _NO_ACTION:
                break
            timestep = environment.step(action)
            tally.add_step(timestep.reward)
            writer.append(
                environment.physics.render(height=height, width=width, camera_id=camera_id)
            )
    return EpisodeVideo(writer.path, writer.frames, fps, tally.episode_return, tally.steps)
