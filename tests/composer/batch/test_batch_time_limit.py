"""A batch's time limit ends episodes at the control step where C MuJoCo's float64 time
reaches it, also for limits of millions of steps, and refuses limits its counters cannot
hold."""

import pytest

from composer.batch.time_limit import NO_LIMIT, control_step_limit


def _summed_step_by_step(time_limit, timestep, n_sub_steps):
    time, steps = 0.0, 0
    while time < time_limit:
        for _ in range(n_sub_steps):
            time += timestep
        steps += 1
    return steps


@pytest.mark.parametrize(
    ("time_limit", "timestep", "n_sub_steps"),
    [
        (0.0, 0.002, 10),
        (10.0, 0.002, 10),
        (0.3, 0.1, 1),
        (1.0, 1 / 3, 1),
        (12345.678, 0.005, 7),
        (6000.0, 0.002, 1),
        (3000.0, 0.001 + 2.0**-40, 3),  # a timestep whose rounding ties in one binade
    ],
)
def test_limit_matches_the_float64_time_summed_step_by_step(time_limit, timestep, n_sub_steps):
    assert control_step_limit(time_limit, timestep, n_sub_steps) == _summed_step_by_step(
        time_limit, timestep, n_sub_steps
    )


def test_one_second_of_tenth_seconds_takes_one_step_more_than_the_ratio():
    # Ten float64 additions of 0.1 make 0.9999999999999999, below 1.
    assert control_step_limit(1.0, 0.1, 1) == 11
    assert control_step_limit(1.0, 0.1, 5) == 3


def test_infinite_limit_is_no_limit():
    assert control_step_limit(float("inf"), 0.002, 10) == NO_LIMIT


def test_limit_beyond_the_int32_counters_is_refused_by_name():
    with pytest.raises(ValueError, match=r"time_limit: 1e\+20 s is 2147483646 control steps"):
        control_step_limit(1e20, 0.002, 10)
