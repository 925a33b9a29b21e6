"""composer.video: episode videos written through imageio and read back from disk."""

import subprocess
import sys

import numpy as np
import pytest
from composer_scene import ReachTask

import composer
from composer import video

iio = pytest.importorskip("imageio.v3", reason="the [video] extra (imageio) is not installed")
pytest.importorskip("imageio_ffmpeg", reason="the [video] extra (imageio-ffmpeg) is not installed")

# ReachTask acts every 0.02 s: 50 frames per second.
_FPS = 50.0


def _environment(time_limit=float("inf"), camera=False):
    task = ReachTask()
    if camera:
        task.arena.mjcf_model.worldbody.add(
            "camera", name="overhead", pos=[0.2, 0, 2.5], xyaxes=[0, -1, 0, 1, 0, 0]
        )
    return composer.Environment(task, time_limit=time_limit, random_state=3)


def _swinging_policy(timestep):
    # Full torque one way: the arm swings, so consecutive frames differ.
    return np.array([1.0, -1.0])


def _read_frames(path):
    return iio.imread(path, index=None)


def test_mp4_has_a_frame_for_the_reset_and_each_step(tmp_path):
    path = tmp_path / "reach.mp4"
    record = video.record_video(
        _environment(), path, _swinging_policy, width=160, height=120, max_steps=12
    )
    frames = _read_frames(path)
    assert frames.shape == (13, 120, 160, 3)
    assert record.frames == 13
    assert record.steps == 12
    assert record.path == path


def test_mp4_frames_show_the_scene_and_change_as_the_arm_moves(tmp_path):
    path = tmp_path / "reach.mp4"
    video.record_video(_environment(), path, _swinging_policy, width=160, height=120, max_steps=10)
    frames = _read_frames(path).astype(int)
    assert frames.max() > 50
    assert np.abs(frames[-1] - frames[0]).mean() > 0.5


def test_mp4_plays_one_frame_per_control_step(tmp_path):
    path = tmp_path / "reach.mp4"
    record = video.record_video(
        _environment(), path, _swinging_policy, width=64, height=48, max_steps=3
    )
    assert record.fps == _FPS
    assert iio.immeta(path, plugin="FFMPEG")["fps"] == _FPS


def test_gif_is_chosen_by_extension_and_holds_every_frame(tmp_path):
    path = tmp_path / "reach.gif"
    record = video.record_video(
        _environment(), path, _swinging_policy, width=80, height=60, max_steps=6
    )
    frames = _read_frames(path)
    assert frames.shape[:3] == (7, 60, 80)
    assert record.frames == 7
    # 50 fps: 20 ms per frame.
    assert iio.immeta(path, index=0)["duration"] == 20


def test_episode_ends_at_the_time_limit(tmp_path):
    path = tmp_path / "short.mp4"
    record = video.record_video(
        _environment(time_limit=0.1), path, _swinging_policy, width=64, height=48
    )
    # 0.1 s of 0.02 s control steps.
    assert record.steps == 5
    assert _read_frames(path).shape[0] == 6


def test_replayed_actions_are_all_applied_and_their_rewards_summed(tmp_path):
    actions = [np.array([0.5, 0.0]), np.array([-0.5, 0.3]), np.array([0.0, -1.0])]
    reference = _environment()
    reference.reset()
    expected_return = sum(reference.step(action).reward for action in actions)

    path = tmp_path / "replay.mp4"
    record = video.record_video(_environment(), path, actions=actions, width=64, height=48)
    assert record.steps == 3
    assert record.episode_return == pytest.approx(expected_return)
    assert _read_frames(path).shape[0] == 4


def test_policy_sees_the_first_timestep_and_every_later_one(tmp_path):
    seen = []

    def policy(timestep):
        seen.append(timestep.step_type)
        return np.zeros(2)

    video.record_video(
        _environment(time_limit=0.06), tmp_path / "a.mp4", policy, width=64, height=48
    )
    # Three steps: the policy answers FIRST, MID and MID; the LAST one needs no action.
    assert [int(step_type) for step_type in seen] == [0, 1, 1]


def test_named_camera_gives_a_different_view_than_the_free_camera(tmp_path):
    views = {}
    for camera_id in (-1, "overhead", 0):
        path = tmp_path / f"{camera_id}.mp4"
        environment = _environment(camera=True)
        video.record_video(environment, path, actions=[], camera_id=camera_id, width=64, height=48)
        views[camera_id] = _read_frames(path)[0].astype(int)
    assert np.abs(views[-1] - views["overhead"]).mean() > 5
    # The only camera has index 0.
    assert np.abs(views[0] - views["overhead"]).mean() < 0.5


def test_unknown_camera_is_named_and_no_file_is_written(tmp_path):
    path = tmp_path / "x.mp4"
    with pytest.raises(ValueError, match="camera_id 'nope'"):
        video.record_video(_environment(), path, _swinging_policy, camera_id="nope", max_steps=2)
    assert not path.exists()


def test_unknown_extension_is_rejected_naming_the_path(tmp_path):
    with pytest.raises(ValueError, match=r"path .*x\.avi.*'\.avi'.*\.mp4"):
        video.record_video(_environment(), tmp_path / "x.avi", _swinging_policy, max_steps=1)


@pytest.mark.parametrize(
    "argument, value", [("width", 0), ("height", -4), ("width", 2.5), ("max_steps", 0)]
)
def test_non_positive_sizes_and_step_counts_are_rejected(tmp_path, argument, value):
    with pytest.raises(ValueError, match=f"{argument}: expected an integer >= 1, got {value}"):
        video.record_video(
            _environment(), tmp_path / "x.mp4", _swinging_policy, **{argument: value}
        )


def test_odd_mp4_size_is_rejected_but_allowed_for_gif(tmp_path):
    with pytest.raises(ValueError, match="width: an mp4 needs an even frame size"):
        video.record_video(_environment(), tmp_path / "x.mp4", _swinging_policy, width=65)
    record = video.record_video(
        _environment(), tmp_path / "x.gif", _swinging_policy, width=65, height=49, max_steps=1
    )
    assert _read_frames(record.path).shape[1:3] == (49, 65)


def test_a_policy_without_max_steps_or_time_limit_is_refused_before_anything_runs(tmp_path):
    path = tmp_path / "endless.mp4"
    environment = _environment()
    with pytest.raises(ValueError) as raised:
        video.record_video(environment, path, _swinging_policy)
    assert str(raised.value) == (
        "max_steps: expected a number of steps for a policy on an environment without a "
        "time limit (time_limit=inf), got None: the recording would go on until the task "
        "ends the episode, perhaps never; pass max_steps, or give the environment a "
        "time_limit"
    )
    assert not path.exists()
    # Nothing was reset or stepped: the first step starts the first episode.
    assert environment.step(np.zeros(2)).first()


def test_replayed_actions_need_no_max_steps_without_a_time_limit(tmp_path):
    record = video.record_video(
        _environment(), tmp_path / "replay.gif", actions=[np.zeros(2)] * 3, width=32, height=24
    )
    assert record.steps == 3


def test_policy_and_actions_are_mutually_exclusive(tmp_path):
    with pytest.raises(ValueError, match="policy, actions: .*got neither"):
        video.record_video(_environment(), tmp_path / "x.mp4")
    with pytest.raises(ValueError, match="policy, actions: .*got both"):
        video.record_video(_environment(), tmp_path / "x.mp4", _swinging_policy, actions=[])


def test_fps_is_the_inverse_control_timestep_to_two_decimals():
    assert video.fps_for(0.02) == 50.0
    assert video.fps_for(0.03) == 33.33
    assert video.fps_for(1 / 60) == 60.0
    with pytest.raises(ValueError, match="control_timestep: expected a positive number"):
        video.fps_for(0.0)


def test_writer_rejects_frames_of_another_size(tmp_path):
    with video.VideoWriter(tmp_path / "x.gif", fps=10) as writer:
        writer.append(np.zeros((8, 8, 3), np.uint8))
        with pytest.raises(ValueError, match=r"frame 1: expected shape \(8, 8, 3\)"):
            writer.append(np.zeros((8, 10, 3), np.uint8))


def test_importing_the_packages_does_not_import_imageio():
    code = (
        "import sys, composer, mjcf, manipulation, composer.video\n"
        "print(sorted(m for m in sys.modules if m.startswith('imageio')))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "[]"
