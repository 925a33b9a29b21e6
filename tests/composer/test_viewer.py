"""composer.viewer: key handling, and the real window under Xvfb (screenshots, keys, exit)."""

import json
import os
import pathlib
import shutil
import subprocess
import sys
import textwrap

import mujoco
import mujoco.viewer
import numpy as np
import pytest

glfw = pytest.importorskip("glfw", reason="glfw (a mujoco dependency) cannot be imported")
viewer = pytest.importorskip("composer.viewer", reason="mujoco.viewer cannot be imported")

_SCENE_DIR = pathlib.Path(__file__).resolve().parent
_REPO = _SCENE_DIR.parents[1]
_SCREEN = (1024, 768)


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


# The real window on a virtual X display.


@pytest.fixture(scope="module")
def display():
    """Starts Xvfb on a display number it picks itself; yields ':N'."""
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb is not installed (apt-get install xvfb); .ci/run installs it")
    read_end, write_end = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write_end), "-screen", "0", f"{_SCREEN[0]}x{_SCREEN[1]}x24"]
        + ["-nolisten", "tcp"],
        pass_fds=(write_end,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write_end)
    with os.fdopen(read_end) as numbers:
        number = numbers.readline().strip()
    if not number:
        server.kill()
        pytest.skip(f"Xvfb did not start (exit code {server.wait()})")
    yield f":{number}"
    server.terminate()
    server.wait()


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
        screen = _screenshot(display)
        process.stdin.write("\n")
        process.stdin.flush()
        output, errors = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 0, errors
    assert json.loads(output) == {"steps": 40, "policy_calls": 40}
    # The window (not the black root window around it) has the grey scene with the arm,
    # and the status box in its top-left corner: dark panel, white text.
    assert screen.std() > 20
    assert len(np.unique(screen)) > 20
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
            env = composer.Environment(ReachTask(), random_state=0)
            viewer.launch(
                env,
                speed=speed,
                max_steps=26,
                on_refresh=lambda handle, status: times.append(time.perf_counter()),
            )
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
    # 25 steps between the first and the last refresh, 0.02 s each at speed 1.
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
