"""composer.gym.video_recorder: every k-th episode of a gymnasium env, written to disk."""

import gymnasium
import numpy as np
import pytest

import composer
import mjcf

iio = pytest.importorskip("imageio.v3", reason="the [video] extra (imageio) is not installed")
pytest.importorskip("imageio_ffmpeg", reason="the [video] extra (imageio-ffmpeg) is not installed")
from composer.gym.video_recorder import VideoRecorder  # noqa: E402

_HEIGHT, _WIDTH = 48, 64


class _Ball(composer.Entity):
    def _build(self):
        self._model = mjcf.RootElement(model="ball")
        self._model.worldbody.add("geom", type="sphere", size=[0.1], rgba=[1, 0, 0, 1])

    @property
    def mjcf_model(self):
        return self._model


class _DropBall(composer.Task):
    """A ball falls from 1 m onto a plane; reward 1 per step."""

    def __init__(self):
        self._arena = composer.Arena()
        self._arena.mjcf_model.worldbody.add("light", pos=[0, 0, 3])
        self._arena.mjcf_model.worldbody.add("geom", type="plane", size=[1, 1, 0.1])
        self._ball = _Ball()
        self._arena.add_free_entity(self._ball)
        self.set_timesteps(control_timestep=0.04, physics_timestep=0.004)

    @property
    def root_entity(self):
        return self._arena

    def initialize_episode(self, physics, random_state):
        self._ball.set_pose(physics, position=[0, 0, 1.0])

    def get_reward(self, physics):
        return 1.0


class _DropBallEnv(gymnasium.Env):
    """The composer task as a minimal gymnasium env: episodes of `steps` steps."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(self, render_mode="rgb_array", steps=4):
        self.render_mode = render_mode
        self._env = composer.Environment(_DropBall(), time_limit=0.04 * steps)
        self.observation_space = gymnasium.spaces.Box(-np.inf, np.inf, (1,), np.float64)
        self.action_space = gymnasium.spaces.Box(-1, 1, (0,), np.float64)

    def _height(self):
        return self._env.physics.data.qpos[2:3].copy()

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self._env.reset()
        return self._height(), {}

    def step(self, action):
        timestep = self._env.step(action)
        return self._height(), timestep.reward, False, timestep.last(), {}

    def render(self):
        return self._env.physics.render(height=_HEIGHT, width=_WIDTH)


def _run_episodes(env, episodes):
    for _ in range(episodes):
        env.reset()
        truncated = False
        while not truncated:
            _, _, _, truncated, _ = env.step(np.zeros(0))


def test_every_kth_episode_is_written_with_its_index_in_the_name(tmp_path):
    env = VideoRecorder(_DropBallEnv(), tmp_path / "videos", every=2)
    _run_episodes(env, 5)
    env.close()
    names = sorted(path.name for path in (tmp_path / "videos").iterdir())
    assert names == ["episode-000000.mp4", "episode-000002.mp4", "episode-000004.mp4"]


def test_recorded_file_has_reset_frame_plus_one_per_step_of_the_rendered_size(tmp_path):
    env = VideoRecorder(_DropBallEnv(steps=4), tmp_path)
    _run_episodes(env, 1)
    frames = iio.imread(tmp_path / "episode-000000.mp4", index=None)
    assert frames.shape == (5, _HEIGHT, _WIDTH, 3)
    assert frames.max() > 50
    # The ball falls: the last frame differs from the first.
    assert np.abs(frames[-1].astype(int) - frames[0].astype(int)).mean() > 0.5


def test_finished_videos_are_listed_with_frames_fps_and_return(tmp_path):
    env = VideoRecorder(_DropBallEnv(steps=3), tmp_path, every=1)
    _run_episodes(env, 2)
    assert [video.path.name for video in env.videos] == [
        "episode-000000.mp4",
        "episode-000001.mp4",
    ]
    assert [(video.frames, video.steps, video.episode_return) for video in env.videos] == [
        (4, 3, 3.0),
        (4, 3, 3.0),
    ]
    assert env.videos[0].fps == 25.0
    assert iio.immeta(env.videos[0].path, plugin="FFMPEG")["fps"] == 25.0


def test_gif_extension_prefix_and_explicit_fps(tmp_path):
    env = VideoRecorder(
        _DropBallEnv(steps=3), tmp_path, name_prefix="drop", extension=".gif", fps=10
    )
    _run_episodes(env, 1)
    path = tmp_path / "drop-000000.gif"
    assert iio.imread(path, index=None).shape[:3] == (4, _HEIGHT, _WIDTH)
    assert iio.immeta(path, index=0)["duration"] == 100


def test_episode_cut_short_by_reset_or_close_is_still_written(tmp_path):
    env = VideoRecorder(_DropBallEnv(steps=10), tmp_path)
    env.reset()
    env.step(np.zeros(0))
    env.reset()
    env.step(np.zeros(0))
    env.step(np.zeros(0))
    env.close()
    assert [(video.path.name, video.frames) for video in env.videos] == [
        ("episode-000000.mp4", 2),
        ("episode-000001.mp4", 3),
    ]
    assert iio.imread(tmp_path / "episode-000001.mp4", index=None).shape[0] == 3


def test_env_without_rgb_array_rendering_is_rejected(tmp_path):
    with pytest.raises(ValueError, match="env: expected .*render_mode 'rgb_array', got .*None"):
        VideoRecorder(_DropBallEnv(render_mode=None), tmp_path)


@pytest.mark.parametrize("every", [0, -1, 1.5])
def test_non_positive_every_is_rejected(tmp_path, every):
    with pytest.raises(ValueError, match=f"every: expected an integer >= 1, got {every}"):
        VideoRecorder(_DropBallEnv(), tmp_path, every=every)


def test_unknown_extension_is_rejected(tmp_path):
    with pytest.raises(ValueError, match=r"extension: expected one of .*got '\.avi'"):
        VideoRecorder(_DropBallEnv(), tmp_path, extension=".avi")


def test_missing_fps_is_rejected(tmp_path):
    inner = _DropBallEnv()
    inner.metadata = {"render_modes": ["rgb_array"]}
    with pytest.raises(ValueError, match="fps: not given"):
        VideoRecorder(inner, tmp_path)
    with pytest.raises(ValueError, match="fps: expected a positive number, got 0"):
        VideoRecorder(_DropBallEnv(), tmp_path, fps=0)
