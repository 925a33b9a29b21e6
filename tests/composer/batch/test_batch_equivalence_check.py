"""`composer.batch.equivalence`, the check users run on their own task, on reach_site: it
passes on the real batched task and names the quantity, step and world of a difference
put in on purpose, and tells the batch's difference from the task's own sensitivity to
float32 rounding."""

import contextlib
import io
import math

import numpy as np
import pytest

import mjcf
from composer.batch import equivalence
from manipulation import batch as manipulation_batch
from manipulation.tasks import registry
from manipulation.tasks import task_constants as tc

pytestmark = pytest.mark.warp

NAME = "reach_site_features"
TORQUES = "jaco_arm/joints_torque"


def make_reach():
    return registry.build_task(NAME)


def _reach_factors() -> dict[str, float]:
    """The gains of reach's derived quantities: the servos' kv for the torques; for the
    reward, two positions' errors times the Gaussian's steepest slope."""
    physics = mjcf.Physics.from_mjcf_model(make_reach().root_entity.mjcf_model)
    kv = float(np.max(np.abs(physics.model.ptr.actuator_gainprm[:, 0])))
    slope = math.sqrt(2.0 * math.log(10.0)) * math.exp(-0.5) / tc.REACH_MARGIN
    return {TORQUES: kv, "reward": 2.0 * slope}


class _PushedAtStep4(manipulation_batch.BatchReach):
    """BatchReach that pushes world 1's first actuator 0.5 further at the 4th step."""

    def __init__(self, task):
        super().__init__(task)
        self.steps = 0

    def before_step(self, physics, action):
        self.steps += 1
        if self.steps == 4:
            action = np.array(action)
            action[1, 0] += 0.5
        super().before_step(physics, action)


def test_reach_site_batch_stays_within_the_float32_bound_of_the_cpu_environment():
    report = equivalence.compare(make_reach, num_envs=2, control_steps=10, factors=_reach_factors())
    assert report.passed, str(report)
    assert report.rounded_cpu_first is None
    assert report.seeds == (0, 1)
    assert 0.0 < report.worst["qpos"] < 1.0


def test_a_difference_put_in_is_named_by_quantity_step_world_and_joint():
    report = equivalence.compare(
        make_reach, num_envs=2, control_steps=6, factors=_reach_factors(), batch_task=_PushedAtStep4
    )
    assert not report.passed
    first = report.first
    assert (first.quantity, first.step, first.world) == ("qpos", 4, 1)
    assert first.element == "jaco_arm/joint_1"
    assert abs(first.got - first.expected) > first.bound > 0
    # C MuJoCo rounded to float32 stays within the bound: the difference is the batch's.
    assert report.rounded_cpu_first is None


def test_command_line_reports_the_torques_that_need_their_servo_gain():
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        status = equivalence.main([f"{__name__}:make_reach", "--num-envs", "2", "--steps", "3"])
    assert status == 1
    assert f"left the bound: observation {TORQUES!r}" in printed.getvalue()
