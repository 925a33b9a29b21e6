"""Tests for composer.constants and its re-export from the package."""

import composer
from composer import constants


def test_sensor_sites_group_is_four_and_re_exported_from_composer():
    assert constants.SENSOR_SITES_GROUP == 4
    assert composer.SENSOR_SITES_GROUP == 4
