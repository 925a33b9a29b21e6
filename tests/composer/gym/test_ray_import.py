"""Ray is an optional extra: importing the packages never imports it, and without it
`RayVectorEnv` says which extra to install. Runs without Ray (no `ray` marker)."""

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


def test_importing_the_packages_and_composer_gym_does_not_import_ray():
    result = _run(
        """
        import sys
        import composer, mjcf, manipulation
        import composer.gym
        from composer.gym import RayVectorEnv
        print("ray" in sys.modules)
        """
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False"


def test_without_ray_making_a_ray_vector_env_names_the_extra_to_install():
    result = _run(
        """
        import sys
        sys.modules["ray"] = None  # as if Ray were not installed
        import gymnasium
        from composer.gym import RayVectorEnv
        try:
            RayVectorEnv([lambda: gymnasium.make("CartPole-v1")])
        except ImportError as error:
            print(error)
        """
    )
    assert result.returncode == 0, result.stderr
    assert "pip install 'mujoco-composer[ray]'" in result.stdout
