"""`manipulation.batch` batches every task of the suite, features and vision, and refuses
other names listing the batched ones; neither needs MuJoCo Warp."""

import pytest

from manipulation import batch
from manipulation.tasks import registry


def test_batched_names_are_every_name_of_the_registry():
    assert len(set(batch.BATCHED)) == len(batch.BATCHED)
    assert sorted(batch.BATCHED) == sorted(registry.names())
    assert len(batch.BATCHED_VISION) == 12
    assert all(name.endswith("_vision") for name in batch.BATCHED_VISION)


def test_load_refuses_an_unknown_name_listing_the_batched_ones():
    with pytest.raises(ValueError, match="expected one of .*'reach_site_features'.*got 'reach'"):
        batch.load("reach", 2)
