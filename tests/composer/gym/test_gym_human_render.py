"""render_mode='human' on a virtual X display (Xvfb): the viewer window, and Gymnasium's
env checker (render checks included, 'human' among them) for every registered task, in
human mode for every scene.

Each check runs in a subprocess whose DISPLAY is the Xvfb server; skipped (saying why)
without Xvfb or xdotool.
"""

import json
import os
import pathlib
import shutil
import subprocess
import sys
import textwrap

import pytest

import manipulation

_HERE = pathlib.Path(__file__).resolve().parent
_REPO = _HERE.parents[2]


def _run(display, tmp_path, body, timeout):
    """Runs `body` (Python) with this checkout and gym_scene importable, under `display`
    (None: without one); returns what it printed as JSON."""
    script = tmp_path / "human_render.py"
    script.write_text(
        "import json, os, subprocess, sys, warnings\n"
        f"sys.path[:0] = [{str(_HERE)!r}, {str(_REPO)!r}]\n" + textwrap.dedent(body)
    )
    result = subprocess.run(
        [sys.executable, str(script)],
        cwd=_REPO,
        env={
            **{k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")},
            **({} if display is None else {"DISPLAY": display}),
            "MUJOCO_GL": "glfw",
        },
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


def test_human_mode_shows_a_window_of_the_given_size_until_close(display, tmp_path):
    if shutil.which("xdotool") is None:
        pytest.skip("xdotool is not installed (apt-get install xdotool); .ci/run installs it")
    seen = _run(
        display,
        tmp_path,
        """
        import threading
        import numpy as np
        import composer
        from composer.gym import GymnasiumEnv
        from gym_scene import SliderTask

        def windows():
            def xdotool(*args):
                return subprocess.run(["xdotool", *args], capture_output=True, text=True).stdout

            return [
                [xdotool("getwindowname", i).strip(), xdotool("getwindowgeometry", i).split()[-1]]
                for i in xdotool("search", "--pid", str(os.getpid())).split()
            ]

        threads = threading.active_count()
        env = GymnasiumEnv(
            composer.Environment(SliderTask(), time_limit=0.1),
            render_mode="human",
            width=400,
            height=300,
        )
        before_reset = windows()
        env.reset(seed=0)
        after_reset = windows()
        rendered = env.render()
        steps = 0
        terminated = truncated = False
        while not (terminated or truncated):
            _, _, terminated, truncated, _ = env.step(np.ones(1))
            steps += 1
        after_steps = windows()
        env.close()
        print(json.dumps({
            "before_reset": before_reset,
            "after_reset": after_reset,
            "rendered": repr(rendered),
            "steps": steps,
            "after_steps": after_steps,
            "after_close": windows(),
            "threads_left": threading.active_count() - threads,
        }))
        """,
        timeout=120,
    )
    window = ["SliderTask (Environment)", "400x300"]
    assert seen["before_reset"] == []
    assert seen["after_reset"] == [window]
    assert seen["rendered"] == "None"
    # 0.1 s at the slider's 0.02 s control step.
    assert seen["steps"] == 5
    assert seen["after_steps"] == [window]
    assert seen["after_close"] == []
    assert seen["threads_left"] == 0


def test_a_human_window_left_open_is_closed_at_exit_without_crashing(display, tmp_path):
    # MuJoCo's viewer thread, still running at interpreter exit, crashes the process.
    seen = _run(
        display,
        tmp_path,
        """
        import numpy as np
        import composer
        from composer.gym import GymnasiumEnv
        from gym_scene import SliderTask

        env = GymnasiumEnv(composer.Environment(SliderTask()), render_mode="human")
        env.reset(seed=0)
        env.step(np.ones(1))
        print(json.dumps("left open"))
        """,
        timeout=60,
    )
    assert seen == "left open"


def test_human_mode_without_a_display_raises_instead_of_ending_the_process(tmp_path):
    seen = _run(
        None,
        tmp_path,
        """
        import composer
        from composer.gym import GymnasiumEnv
        from gym_scene import SliderTask

        env = GymnasiumEnv(composer.Environment(SliderTask()), render_mode="human")
        try:
            env.reset(seed=0)
        except RuntimeError as error:
            print(json.dumps(str(error)))
        """,
        timeout=60,
    )
    assert seen.startswith("the viewer window cannot open: GLFW could not initialise (")
    assert seen.endswith(
        "It needs a display: on a headless machine run under Xvfb (xvfb-run python ...)"
    )


# The tasks in four shares, each checked in a process of its own, so that pytest-xdist can
# spread them over the cores (all 26 in one process took minutes).
_SHARES = 4


@pytest.mark.parametrize("share", range(_SHARES))
def test_every_task_passes_gymnasiums_env_checker_in_human_mode(display, tmp_path, share):
    # The checker also makes each task again in every listed render mode and renders it
    # (this is where 'human', 'rgb_array' and 'depth_array' pass its render checks): small
    # images keep the off-screen ones fast. Every scene is checked whole in human mode
    # through its features task; a vision task (its features twin's scene, with camera
    # observables) is checked in 'rgb_array' mode, so that its window is open only for the
    # checker's human-mode render check: under Xvfb the viewer draws without pause while
    # its window is open, which made the vision tasks' checks half of this test's time.
    names = manipulation.ALL[share::_SHARES]
    results = _run(
        display,
        tmp_path,
        """
        import gymnasium
        from gymnasium.utils.env_checker import check_env
        import manipulation

        results = {}
        for name in manipulation.ALL[SHARE::SHARES]:
            mode = "rgb_array" if name.endswith("_vision") else "human"
            env = gymnasium.make(f"composer/{name}-v0", render_mode=mode, width=64, height=48)
            try:
                with warnings.catch_warnings():
                    # Advice about unbounded observations and non-normalised actions.
                    warnings.simplefilter("ignore", UserWarning)
                    check_env(env.unwrapped)
                results[name] = "passed"
            except Exception as error:
                results[name] = f"{type(error).__name__}: {error}"
            finally:
                env.close()
        print(json.dumps(results))
        """.replace("SHARE::SHARES", f"{share}::{_SHARES}"),
        timeout=540,
    )
    assert results == dict.fromkeys(names, "passed")
    assert len(manipulation.ALL) == 26
    # Every vision task's scene is also checked whole in human mode, as its features twin.
    assert {name[: -len("_vision")] for name in manipulation.ALL if name.endswith("_vision")} <= {
        name[: -len("_features")] for name in manipulation.ALL if name.endswith("_features")
    }
