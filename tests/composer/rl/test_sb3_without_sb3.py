"""What of composer.rl.sb3 needs no Stable-Baselines3: importing composer, composer.rl and
the Gymnasium integration never imports SB3 or torch, and without SB3 importing the
adapter says which extra to install, and how to get torch's CPU build."""

import subprocess
import sys
import textwrap


def _run(code: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        check=False,
        env={"MUJOCO_GL": "egl", "PATH": ""},
    )


def test_importing_composer_rl_and_composer_gym_imports_no_training_library():
    result = _run(
        """
        import sys
        import composer, manipulation, composer.gym, composer.rl
        print("stable_baselines3" in sys.modules, "torch" in sys.modules)
        """
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False False"


def test_without_sb3_importing_the_adapter_names_the_extra_and_the_cpu_torch():
    result = _run(
        """
        import sys
        sys.modules["stable_baselines3"] = None  # as if SB3 were not installed
        try:
            import composer.rl.sb3
        except ImportError as error:
            print(error)
        """
    )
    assert result.returncode == 0, result.stderr
    message = result.stdout
    assert "pip install 'mujoco-composer[sb3]'" in message
    assert "--index-url https://download.pytorch.org/whl/cpu" in message
