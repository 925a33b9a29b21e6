"""A Gymnasium wrapper that records every k-th episode to a video file.

Needs gymnasium and the `video` extra (imageio, imageio-ffmpeg). Frames and frame rate
follow `composer.video`: a recorded episode of N steps has N + 1 frames, the one rendered
after `reset()` and one after each step.
"""

from __future__ import annotations

import os
import pathlib
from typing import Any

import gymnasium

from composer.episode_tally import EpisodeTally
from composer.utils import argument_checks
from composer.video import EXTENSIONS, EpisodeVideo, VideoWriter


class VideoRecorder(gymnasium.Wrapper):
    """Writes episodes 0, k, 2k, ... of `env` to `folder/{name_prefix}-{index:06d}{ext}`.

    Episodes are counted from 0 by `reset()`. A recorded episode's file is finished when
    the episode terminates or is truncated, when `reset()` starts the next episode first,
    or when `close()` is called; each finished file is appended to `videos` as a
    `composer.video.EpisodeVideo`.

    Args:
      env: a gymnasium environment created with `render_mode="rgb_array"`.
      folder: where the videos go; created if missing.
      every: record every `every`-th episode (k >= 1; 1 records all).
      name_prefix: file names start with this.
      extension: `".mp4"` or `".gif"`.
      fps: frames per second; defaults to `env.metadata["render_fps"]`.

    Raises:
      ValueError: naming the argument when `env` does not render RGB arrays, `every` is
        not a positive integer, `extension` is unknown, or there is no positive fps.
    """

    def __init__(
        self,
        env: gymnasium.Env,
        folder: str | os.PathLike,
        *,
        every: int = 1,
        name_prefix: str = "episode",
        extension: str = ".mp4",
        fps: float | None = None,
    ):
        super().__init__(env)
        if env.render_mode != "rgb_array":
            raise ValueError(
                f"env: expected an environment with render_mode 'rgb_array', "
                f"got render_mode {env.render_mode!r}"
            )
        every = argument_checks.integer(every=every)
        if not isinstance(extension, str) or extension.lower() not in EXTENSIONS:
            raise ValueError(f"extension: expected one of {list(EXTENSIONS)}, got {extension!r}")
        self._extension = extension.lower()
        if fps is None:
            fps = env.metadata.get("render_fps")
            if fps is None:
                raise ValueError(
                    "fps: not given and env.metadata has no 'render_fps'; pass fps=..."
                )
        fps = argument_checks.number(above=0, fps=fps)
        self.folder = pathlib.Path(folder)
        self.every = int(every)
        self.name_prefix = name_prefix
        self.fps = float(fps)
        self.videos: list[EpisodeVideo] = []
        self._episode = -1
        self._writer: VideoWriter | None = None
        self._tally = EpisodeTally()

    @property
    def episode_index(self) -> int:
        """The index of the current episode; -1 before the first reset."""
        return self._episode

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        self._finish()
        observation, info = self.env.reset(seed=seed, options=options)
        self._episode += 1
        if self._episode % self.every == 0:
            self.folder.mkdir(parents=True, exist_ok=True)
            path = self.folder / f"{self.name_prefix}-{self._episode:06d}{self._extension}"
            self._writer = VideoWriter(path, self.fps)
            self._tally.start_episode()
            self._writer.append(self.env.render())
        return observation, info

    def step(self, action):
        observation, reward, terminated, truncated, info = self.env.step(action)
        if self._writer is not None:
            self._tally.add_step(reward)
            self._writer.append(self.env.render())
            if terminated or truncated:
                self._finish()
        return observation, reward, terminated, truncated, info

    def close(self) -> None:
        self._finish()
        super().close()

    def _finish(self) -> None:
        if self._writer is None:
            return
        writer, self._writer = self._writer, None
        writer.close()
        self.videos.append(
            EpisodeVideo(
                writer.path,
                writer.frames,
                writer.fps,
                self._tally.episode_return,
                self._tally.episode_steps,
            )
        )
