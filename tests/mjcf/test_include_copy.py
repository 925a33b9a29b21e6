"""RootElement.include_copy: copying one model's contents into another."""

import numpy as np
import pytest

import mjcf


def _mixin():
    mixin = mjcf.RootElement(model="mixin")
    site = mixin.worldbody.add("site", name="touch_site", size=[0.1])
    mixin.sensor.add("touch", name="touch", site=site)
    mixin.compiler.boundmass = 1
    return mixin


def test_copied_elements_reference_the_copies_and_model_keeps_its_name():
    model = mjcf.RootElement(model="target")
    mixin = _mixin()
    model.include_copy(mixin)
    assert model.model == "target"
    copied_site = model.find("site", "touch_site")
    assert copied_site is not mixin.find("site", "touch_site")
    assert model.find("sensor", "touch").site is copied_site
    assert model.compiler.boundmass == 1
    assert mjcf.Physics.from_mjcf_model(model).model.nsensor == 1


def test_conflicting_setting_is_value_error_unless_overridden():
    model = mjcf.RootElement(model="target")
    model.compiler.boundmass = 2
    mixin = _mixin()
    with pytest.raises(ValueError, match="boundmass"):
        model.include_copy(mixin)
    model = mjcf.RootElement(model="target")
    model.compiler.boundmass = 2
    model.include_copy(mixin, override_attributes=True)
    assert model.compiler.boundmass == 1


def test_override_updates_elements_with_the_same_identifier_in_place():
    model = mjcf.RootElement()
    body = model.worldbody.add("body", name="b", pos=[0, 0, 0])
    mixin = mjcf.RootElement()
    mixin.worldbody.add("body", name="b", pos=[0, 1, 2])
    model.include_copy(mixin, override_attributes=True)
    assert len(model.worldbody.body) == 1
    np.testing.assert_array_equal(body.pos, [0, 1, 2])


def test_copying_twice_without_override_clashes_on_identifiers():
    model = mjcf.RootElement()
    model.include_copy(_mixin())
    with pytest.raises(ValueError, match="touch"):
        model.include_copy(_mixin())


def test_model_with_attachments_cannot_be_copied_in():
    mixin = _mixin()
    mixin.attach(mjcf.RootElement(model="child"))
    with pytest.raises(NotImplementedError):
        mjcf.RootElement().include_copy(mixin)
