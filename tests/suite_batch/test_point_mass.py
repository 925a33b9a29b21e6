"""The batched point_mass tasks: world i is dm_control's
`suite.load("point_mass", task, task_kwargs={"random": seed})`."""

import pytest
from episodes import differences, needs_suite

pytestmark = needs_suite

POINT_MASS_TASKS = ("easy", "hard")


def test_the_batch_has_every_point_mass_task_of_the_suite(suite):
    assert set(POINT_MASS_TASKS) == {
        task for domain, task in suite.ALL_TASKS if domain == "point_mass"
    }


@pytest.mark.parametrize("task", POINT_MASS_TASKS)
def test_every_world_is_dm_controls_episode_bit_for_bit_across_resets(suite, task):
    assert differences(suite, "point_mass", task) == []
