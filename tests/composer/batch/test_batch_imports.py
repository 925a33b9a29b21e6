"""Importing the library never imports Warp; building a batch without it says how to get it."""

import subprocess
import sys

import pytest

import composer.batch


def test_import_composer_does_not_import_warp():
    code = (
        "import sys, composer, mjcf, manipulation, composer.batch, manipulation.batch; "
        "print(sorted(m for m in ('warp', 'mujoco_warp') if m in sys.modules))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "[]"


def test_unregistered_task_is_refused_with_the_way_to_register_one():
    class Unbatched(composer.NullTask):
        pass

    arena = composer.Arena()
    with pytest.raises(TypeError, match="no batched version of Unbatched.*BatchTask"):
        composer.batch.BatchEnvironment(Unbatched(arena), 2)


@pytest.mark.parametrize("num_envs", [0, -3, 2.5, True, "4"])
def test_num_envs_must_be_a_positive_int(num_envs):
    with pytest.raises(ValueError, match=r"num_envs: expected an integer >= 1, got"):
        composer.batch.BatchEnvironment(composer.NullTask(composer.Arena()), num_envs)


@pytest.mark.parametrize(
    "argument, message",
    [
        ({"num_envs": 0}, "num_envs: expected an integer >= 1, got 0"),
        ({"control_steps": -1}, "control_steps: expected an integer >= 0, got -1"),
    ],
)
def test_equivalence_check_refuses_bad_counts_before_building_anything(argument, message):
    from composer.batch import equivalence

    def never_called():
        raise AssertionError("the task was built")

    with pytest.raises(ValueError, match=message):
        equivalence.compare(never_called, **argument)
