"""What of composer.rl.sb3 needs no Stable-Baselines3: importing composer, composer.rl and
the Gymnasium integration never imports SB3 or torch, and without SB3 importing the
adapter says which extra to install, and how to get torch's CPU build."""


def test_importing_composer_rl_and_composer_gym_imports_no_training_library(fresh_python):
    result = fresh_python(
        """
        import sys
        import composer, manipulation, composer.gym, composer.rl
        print("stable_baselines3" in sys.modules, "torch" in sys.modules)
        """
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "False False"


def test_without_sb3_importing_the_adapter_names_the_extra_and_the_cpu_torch(fresh_python):
    result = fresh_python(
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
