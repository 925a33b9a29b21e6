"""composer.viewer: key handling, and the real window under Xvfb (screenshots, keys, exit)."""

import json
import os
import pathlib
import shutil
import subprocess
import sys
import textwrap
import time

import dm_env
import mujoco
import mujoco.viewer
import numpy as np
import pytest
from dm_env import specs

glfw = pytest.importorskip("glfw", reason="glfw (a mujoco dependency) cannot be imported")
viewer = pytest.importorskip("composer.viewer", reason="mujoco.viewer cannot be imported")

_SCENE_DIR = pathlib.Path(__file__).resolve().parent
_REPO = _SCENE_DIR.parents[1]


# Key handling, without a window.


def test_space_pauses_and_resumes_stepping():
    controls = viewer.Controls()
    assert controls.take_step()
    controls.on_key(glfw.KEY_SPACE)
    assert controls.paused
    assert not controls.take_step()
    controls.on_key(glfw.KEY_SPACE)
    assert controls.take_step()


def test_right_arrow_steps_once_per_press_only_while_paused():
    controls = viewer.Controls()
    controls.on_key(glfw.KEY_RIGHT)
    controls.on_key(glfw.KEY_SPACE)
    assert not controls.take_step()
    controls.on_key(glfw.KEY_RIGHT)
    controls.on_key(glfw.KEY_RIGHT)
    assert [controls.take_step() for _ in range(3)] == [True, True, False]


def test_backspace_requests_one_reset():
    controls = viewer.Controls()
    assert not controls.take_reset()
    controls.on_key(glfw.KEY_BACKSPACE)
    assert controls.take_reset()
    assert not controls.take_reset()


def test_plus_and_minus_double_and_halve_speed_within_bounds():
    controls = viewer.Controls(speed=1.0)
    controls.on_key(glfw.KEY_EQUAL)
    controls.on_key(glfw.KEY_KP_ADD)
    assert controls.speed == 4.0
    for _ in range(10):
        controls.on_key(glfw.KEY_MINUS)
    assert controls.speed == 1 / 16
    for _ in range(12):
        controls.on_key(glfw.KEY_KP_ADD)
    assert controls.speed == 16.0


@pytest.mark.parametrize("speed", [0, 20, -1.0, "fast"])
def test_bad_speed_is_rejected(speed):
    with pytest.raises(ValueError, match="speed: expected a number in"):
        viewer.Controls(speed=speed)


def test_launch_rejects_bad_arguments_before_opening_a_window():
    from composer_scene import ReachTask

    import composer

    env = composer.Environment(ReachTask(), random_state=0)
    with pytest.raises(ValueError, match="max_steps: expected an integer >= 1 or None, got 0"):
        viewer.launch(env, max_steps=0)
    with pytest.raises(ValueError, match="policy: expected a callable"):
        viewer.launch(env, policy="random")
    with pytest.raises(ValueError, match="speed: expected"):
        viewer.launch(env, speed=100)


class _EnvironmentWithoutPhysics(dm_env.Environment):
    """A dm_env environment that has nothing for the viewer to show."""

    def __init__(self, physics=None):
        if physics is not None:
            self.physics = physics

    def reset(self):
        return dm_env.restart({})

    def step(self, action):
        return dm_env.transition(0.0, {})

    def observation_spec(self):
        return {}

    def action_spec(self):
        return specs.Array((1,), float)


def _load_nothing():
    return None


@pytest.mark.parametrize(
    "environment_loader, got",
    [
        ("cartpole", "got 'cartpole'$"),
        (42, "got 42$"),
        (_load_nothing, r"got <function _load_nothing at .*>, which returned None \(no reset, "),
        (
            _EnvironmentWithoutPhysics,
            r"got <class '.*_EnvironmentWithoutPhysics'> returned <.*>, which has no physics$",
        ),
        (
            _EnvironmentWithoutPhysics(physics="not a physics"),
            r"got <.*_EnvironmentWithoutPhysics object .*>, which has a physics 'not a physics' "
            "whose model.ptr / data.ptr are None / None$",
        ),
    ],
    ids=["string", "number", "loader-returns-none", "no-physics", "bad-physics"],
)
def test_environment_loader_that_gives_no_viewable_environment_is_named_in_the_error(
    environment_loader, got
):
    expected = (
        r"^environment_loader: expected an environment \(with reset, step, action_spec and a "
        r"physics whose model.ptr and data.ptr are a mujoco.MjModel and a mujoco.MjData\) or "
        r"a callable returning one, "
    )
    with pytest.raises(TypeError, match=expected + got):
        viewer.launch(environment_loader)


def test_environment_loader_none_is_a_value_error_as_in_dm_control():
    expected = r"^environment_loader: expected an environment .* got None$"
    with pytest.raises(ValueError, match=expected):
        viewer.launch(None)


def test_environment_loader_that_raises_is_named_in_the_error_chained_to_its_own():
    def load():
        raise KeyError("no such domain")

    with pytest.raises(RuntimeError) as raised:
        viewer.launch(load)
    assert str(raised.value) == (
        "environment_loader: expected an environment (with reset, step, action_spec and a "
        "physics whose model.ptr and data.ptr are a mujoco.MjModel and a mujoco.MjData) or a "
        f"callable returning one; calling {load!r} raised KeyError: 'no such domain'"
    )
    assert isinstance(raised.value.__cause__, KeyError)


@pytest.mark.parametrize(
    "window, message",
    [
        ({"title": 3}, "title: expected a string, got 3"),
        ({"width": 0}, r"width: expected an integer >= 1 \(screen pixels\), got 0"),
        ({"height": 480.0}, r"height: expected an integer >= 1 \(screen pixels\), got 480.0"),
    ],
)
def test_bad_window_title_or_size_is_rejected_before_the_loader_is_called(window, message):
    def load():
        raise AssertionError("the loader must not be called")

    with pytest.raises(ValueError, match=f"^{message}$"):
        viewer.launch(load, **window)


# The real window on a virtual X display.


def _start(display, tmp_path, body):
    script = tmp_path / "run_viewer.py"
    script.write_text(
        textwrap.dedent(
            f"""\
            import json, subprocess, sys
            import numpy as np
            sys.path.insert(0, {str(_SCENE_DIR)!r})
            import composer
            from composer import viewer
            from composer_scene import ReachTask
            """
        )
        + textwrap.dedent(body)
    )
    environment = dict(os.environ, DISPLAY=display, MUJOCO_GL="glfw")
    return subprocess.Popen(
        [sys.executable, str(script)],
        cwd=_REPO,
        env=environment,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _screenshot(display):
    image_grab = pytest.importorskip("PIL.ImageGrab", reason="Pillow is not installed")
    return np.asarray(image_grab.grab(xdisplay=display).convert("L")).astype(int)


def _screenshot_once_drawn(display, timeout=5.0):
    """A screenshot taken once the screen is no longer one flat colour, or after `timeout` s:
    the viewer resizes its window asynchronously and repaints it on its next frame."""
    deadline = time.monotonic() + timeout
    while True:
        screen = _screenshot(display)
        _, counts = np.unique(screen, return_counts=True)
        if counts.max() < 0.99 * screen.size or time.monotonic() > deadline:
            return screen
        time.sleep(0.2)


def test_window_shows_scene_and_status_then_exits_cleanly_after_max_steps(display, tmp_path):
    process = _start(
        display,
        tmp_path,
        """
        calls = []

        def policy(timestep):
            calls.append(timestep.step_type)
            return np.array([1.0, -1.0])

        def pause_for_screenshot(handle, status):
            if status.steps == 30 and not pause_for_screenshot.done:
                pause_for_screenshot.done = True
                print("ready", flush=True)
                sys.stdin.readline()

        pause_for_screenshot.done = False
        env = composer.Environment(ReachTask(), random_state=0)
        final = viewer.launch(env, policy, max_steps=40, on_refresh=pause_for_screenshot)
        print(json.dumps({"steps": final.steps, "policy_calls": len(calls)}))
        """,
    )
    try:
        assert process.stdout.readline() == "ready\n", process.stderr.read()
        screen = _screenshot_once_drawn(display)
        process.stdin.write("\n")
        process.stdin.flush()
        output, errors = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 0, errors
    assert json.loads(output) == {"steps": 40, "policy_calls": 40}
    # The window (1024x768 by default, the whole virtual screen) has the grey scene with
    # the arm, not one flat colour, and the status box in its top-left corner: dark panel,
    # white text.
    _, counts = np.unique(screen, return_counts=True)
    assert len(counts) > 20
    assert counts.max() < 0.99 * screen.size
    if not hasattr(mujoco.viewer.Handle, "set_texts"):
        pytest.skip(
            f"mujoco {mujoco.__version__}'s viewer has no Handle.set_texts: the status is "
            "logged instead of drawn, so there is no status box to look for"
        )
    status_box = screen[:100, :130]
    assert status_box.min() < 60 and status_box.max() > 200


def test_keys_pause_step_change_speed_and_reset(display, tmp_path):
    if shutil.which("xdotool") is None:
        pytest.skip("xdotool is not installed (apt-get install xdotool); .ci/run installs it")
    process = _start(
        display,
        tmp_path,
        """
        seen = {"refreshes": 0}

        def press(key):
            subprocess.run(["xdotool", "key", key], check=True)

        def script(handle, status):
            seen["refreshes"] += 1
            if seen["refreshes"] > 2000:
                handle.close()
            phase = seen.setdefault("phase", "start")
            if phase == "start" and status.steps >= 5:
                press("space")
                seen["phase"] = "pausing"
            elif phase == "pausing" and status.paused:
                seen.update(phase="paused", paused_at=status.steps, paused_refreshes=0)
            elif phase == "paused":
                seen["paused_refreshes"] += 1
                if seen["paused_refreshes"] == 30:
                    seen["steps_while_paused"] = status.steps - seen["paused_at"]
                    press("Right")
                    seen["phase"] = "stepping"
            elif phase == "stepping" and status.steps > seen["paused_at"]:
                seen.update(phase="stepped", stepped_refreshes=0)
            elif phase == "stepped":
                seen["stepped_refreshes"] += 1
                if seen["stepped_refreshes"] == 30:
                    seen["single_step"] = status.steps - seen["paused_at"]
                    press("plus")
                    seen["phase"] = "faster"
            elif phase == "faster" and status.speed != 1.0:
                seen["faster"] = status.speed
                press("minus")
                press("minus")
                seen["phase"] = "slower"
            elif phase == "slower" and status.speed < 1.0:
                seen["slower"] = status.speed
                press("BackSpace")
                seen.update(phase="resetting", episodes_before=status.episodes)
            elif phase == "resetting" and status.episodes > seen["episodes_before"]:
                seen["after_reset"] = [status.episode_step, status.episode_return]
                handle.close()

        env = composer.Environment(ReachTask(), random_state=0)
        final = viewer.launch(env, on_refresh=script)
        seen["steps"] = final.steps
        print(json.dumps(seen))
        """,
    )
    try:
        output, errors = process.communicate(timeout=120)
    finally:
        process.kill()
    assert process.returncode == 0, errors
    seen = json.loads(output)
    assert seen["phase"] == "resetting", seen
    assert seen["steps_while_paused"] == 0
    assert seen["single_step"] == 1
    assert seen["faster"] == 2.0
    assert seen["slower"] == 0.5
    assert seen["after_reset"] == [0, 0.0]


def test_structural_recompile_reopens_the_window_on_the_new_physics(display, tmp_path):
    process = _start(
        display,
        tmp_path,
        """
        class GrowingTask(ReachTask):
            # A new geom every episode changes the model's structure: a new Physics.
            def initialize_episode_mjcf(self, random_state):
                self.arena.mjcf_model.worldbody.add("geom", type="sphere", size=[0.02])

        env = composer.Environment(GrowingTask(), time_limit=0.06, random_state=0)
        shown = []

        def check(handle, status):
            shown.append(handle.d is env.physics.data.ptr)

        final = viewer.launch(env, max_steps=9, on_refresh=check)
        print(json.dumps({"episodes": final.episodes, "all_current": all(shown)}))
        """,
    )
    try:
        output, errors = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 0, errors
    assert json.loads(output) == {"episodes": 3, "all_current": True}


def test_steps_take_control_timestep_divided_by_speed_in_wall_time(display, tmp_path):
    process = _start(
        display,
        tmp_path,
        """
        import time

        durations = {}
        for speed in (1.0, 0.5):
            times = []

            def refreshed(handle, status):
                if not times:
                    time.sleep(0.08)  # a first frame slower than a step, as a window's can be
                times.append(time.perf_counter())

            env = composer.Environment(ReachTask(), random_state=0)
            viewer.launch(env, speed=speed, max_steps=26, on_refresh=refreshed)
            durations[speed] = times[-1] - times[0]
        print(json.dumps(durations))
        """,
    )
    try:
        output, errors = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 0, errors
    durations = json.loads(output)
    # 25 steps between the first and the last refresh, 0.02 s each at speed 1, counted from
    # the first frame however long it took.
    assert durations["1.0"] >= 0.5 * 0.98
    assert durations["0.5"] >= 1.0 * 0.98


def test_status_is_logged_once_a_second_where_the_viewer_cannot_draw_text(caplog):
    status = viewer.ViewerStatus(
        steps=7,
        episodes=1,
        episode_step=7,
        reward=0.5,
        episode_return=2.25,
        speed=2.0,
        paused=False,
    )
    display = viewer._StatusDisplay()
    with caplog.at_level("INFO"):
        display.show(object(), status)
        display.show(object(), status)
    assert [record.getMessage() for record in caplog.records] == [
        "step 7, reward 0.500, return 2.250, speed 2x"
    ]


# dm_control's calling convention, through the import redirect.

_DM_CONTROL_SCRIPT = """\
import json, os, subprocess, sys

import dm_env
import numpy as np
from dm_env import specs

import dm_control
from dm_control import composer, mjcf, viewer

sys.path.insert(0, {scene_dir!r})
from composer_scene import ReachTask


def windows_of_this_process():
    ids = subprocess.run(
        ["xdotool", "search", "--pid", str(os.getpid())], capture_output=True, text=True
    ).stdout.split()
    return [
        [
            subprocess.run(["xdotool", what, i], capture_output=True, text=True).stdout
            for what in ("getwindowname", "getwindowgeometry")
        ]
        for i in ids
    ]


class Pendulum(dm_env.Environment):
    # Not composer: a plain dm_env environment on an mjcf.Physics, ten steps an episode.
    actions = []
    windows = []

    def __init__(self):
        self.physics = mjcf.Physics.from_xml_string(
            "<mujoco model='pendulum'><option timestep='0.01'/><worldbody>"
            "<body pos='0 0 1'><joint name='hinge' axis='0 1 0'/>"
            "<geom type='capsule' fromto='0 0 0 0.5 0 0' size='0.05'/></body></worldbody>"
            "<actuator><motor joint='hinge' ctrlrange='-1 3'/></actuator></mujoco>"
        )
        self._steps = 0

    def reset(self):
        self.physics.reset()
        self._steps = 0
        return dm_env.restart(self.physics.data.qpos.copy())

    def step(self, action):
        Pendulum.actions.append(np.asarray(action).tolist())
        if len(Pendulum.actions) == 3:
            Pendulum.windows = windows_of_this_process()
        self.physics.set_control(action)
        self.physics.step()
        self._steps += 1
        if self._steps == 10:
            return dm_env.termination(1.0, self.physics.data.qpos.copy())
        return dm_env.transition(1.0, self.physics.data.qpos.copy())

    def observation_spec(self):
        return specs.Array((1,), float)

    def action_spec(self):
        return specs.BoundedArray((1,), float, minimum=[-1.0], maximum=[3.0])


# A loader (the class itself), no policy, dm_control's default title and size.
pendulum = viewer.launch(Pendulum, max_steps=12)

timesteps, reach_windows = [], []


def policy(timestep):
    timesteps.append(type(timestep).__name__)
    if len(timesteps) == 3:
        reach_windows.extend(windows_of_this_process())
    return np.array([1.0, -1.0])


# A composer environment and a policy, every dm_control argument positional.
reach = viewer.launch(
    lambda: composer.Environment(ReachTask(), random_state=0),
    policy,
    "Reach explorer",
    800,
    600,
    max_steps=10,
)
print(json.dumps({{
    "viewer": viewer.__name__,
    "bare_dm_control": dm_control.__spec__.origin is None,
    "pendulum": [pendulum.steps, pendulum.episodes, Pendulum.actions[:3], Pendulum.windows],
    "reach": [reach.steps, sorted(set(timesteps)), reach_windows],
}}))
"""


def test_dm_control_viewer_launch_through_the_redirect_shows_plain_and_composer_envs(
    display, tmp_path
):
    if shutil.which("xdotool") is None:
        pytest.skip("xdotool is not installed (apt-get install xdotool); .ci/run installs it")
    probe = "import importlib.util as u; print(u.find_spec('dm_control') is None)"
    if subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True).stdout != (
        "True\n"
    ):
        pytest.skip("dm_control is installed here; this test is about the bare stand-in")
    script = tmp_path / "dm_control_viewer.py"
    script.write_text(_DM_CONTROL_SCRIPT.format(scene_dir=str(_SCENE_DIR)))
    result = subprocess.run(
        [sys.executable, "-m", "composer.dm_control_compat", str(script)],
        cwd=_REPO,
        env=dict(os.environ, DISPLAY=display, MUJOCO_GL="glfw"),
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    seen = json.loads(result.stdout)
    assert seen["viewer"] == "composer.viewer"
    assert seen["bare_dm_control"]
    # Ten steps end the first episode; without a policy the action is the middle of the
    # actuator's range [-1, 3].
    steps, episodes, actions, windows = seen["pendulum"]
    assert (steps, episodes, actions) == (12, 2, [[1.0]] * 3)
    assert [(name.strip(), geometry.split()[-1]) for name, geometry in windows] == [
        ("Explorer", "1024x768")
    ]
    steps, timestep_types, windows = seen["reach"]
    assert (steps, timestep_types) == (10, ["TimeStep"])
    assert [(name.strip(), geometry.split()[-1]) for name, geometry in windows] == [
        ("Reach explorer", "800x600")
    ]
