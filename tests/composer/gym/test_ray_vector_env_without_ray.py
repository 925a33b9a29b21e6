"""What of RayVectorEnv needs no Ray (no `ray` marker): importing the packages never
imports Ray, without Ray `RayVectorEnv` says which extra to install, and bad arguments
are refused, naming the argument, before Ray is started."""

import functools

import pytest
from gym_scene import CounterEnv

from composer.gym import RayVectorEnv


def test_importing_the_packages_and_composer_gym_does_not_import_ray(fresh_python):
    result = fresh_python(
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


def test_without_ray_making_a_ray_vector_env_names_the_extra_to_install(fresh_python):
    result = fresh_python(
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


_TWO = [functools.partial(CounterEnv, 3)] * 2


@pytest.mark.parametrize(
    ("args", "kwargs", "message"),
    [
        ((_TWO,), {"envs_per_actor": 0}, "envs_per_actor: expected an integer >= 1, got 0"),
        ((_TWO,), {"num_cpus_per_actor": -1}, "num_cpus_per_actor: expected a number >= 0"),
        ((_TWO,), {"max_restarts": -1}, "max_restarts: expected an integer >= 0, got -1"),
        (
            (_TWO,),
            {"start_timeout": 0},
            r"start_timeout: expected a positive number \(seconds\), got 0",
        ),
        (
            (_TWO,),
            {"call_timeout": float("inf")},
            r"call_timeout: expected a positive number \(seconds\), got inf",
        ),
        ((_TWO, 3), {}, r"num_envs: expected None or len\(env_fns\) = 2, got 3"),
        (([],), {}, "env_fns: expected at least one environment factory, got none"),
        (("composer/reach_site_features-v0",), {}, "num_envs: expected an integer >= 1"),
    ],
)
def test_bad_arguments_raise_value_error_naming_the_argument(args, kwargs, message):
    with pytest.raises(ValueError, match=message):
        RayVectorEnv(*args, **kwargs)
