"""The batched suite's fixtures."""

import pytest

from suite_batch import loading


@pytest.fixture(scope="module")
def suite():
    """dm_control's suite, through the redirect (tests that take it also need
    `episodes.needs_suite`)."""
    return loading.import_suite()
