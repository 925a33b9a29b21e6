"""`manipulation.batch` batches every features task of the suite, and refuses the others
saying why; neither needs MuJoCo Warp."""

import pytest

from manipulation import batch
from manipulation.tasks import registry


def test_batched_names_are_the_features_names_of_the_registry():
    assert len(set(batch.BATCHED)) == len(batch.BATCHED)
    assert sorted(batch.BATCHED) == sorted(registry.names_with_tag("features"))


def test_load_refuses_a_vision_task_because_a_batch_renders_no_camera():
    with pytest.raises(
        ValueError,
        match="'lift_brick_vision' observes camera images.*'lift_brick_features' is batched",
    ):
        batch.load("lift_brick_vision", 2)


def test_load_refuses_an_unknown_name_listing_the_batched_ones():
    with pytest.raises(ValueError, match="expected one of .*'reach_site_features'.*got 'reach'"):
        batch.load("reach", 2)
