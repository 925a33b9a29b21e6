"""Tests for composer.entity_observables.Observables on entities built from MJCF models."""

import numpy as np
import pytest

import mjcf
from composer import define
from composer.entity_observables import Observables
from composer.observation import observable


class _Entity:
    """The part of an entity the container uses: its MJCF model."""

    def __init__(self, model_name):
        self.mjcf_model = mjcf.RootElement(model=model_name)
        self.mjcf_model.worldbody.add("site", name="tip")
        self.observables = _ArmObservables(self)


class _ArmObservables(Observables):
    @define.observable
    def tip_pos(self):
        return observable.MJCFFeature("xpos", self._entity.mjcf_model.find("site", "tip"))

    @define.observable
    def answer(self):
        return observable.Generic(lambda physics: 42.0)


def _attached(parent_name, child_name):
    parent, child = _Entity(parent_name), _Entity(child_name)
    parent.mjcf_model.worldbody.attach(child.mjcf_model)
    return parent, child


def test_decorated_methods_are_collected_in_name_order():
    assert list(_Entity("arm").observables.as_dict(fully_qualified=False)) == ["answer", "tip_pos"]


def test_observables_are_readable_as_attributes_and_built_once():
    observables = _Entity("arm").observables
    assert observables.answer is observables.as_dict(fully_qualified=False)["answer"]


def test_added_observable_is_readable_as_attribute():
    observables = _Entity("arm").observables
    extra = observable.Generic(lambda physics: 0.0)
    observables.add_observable("extra", extra)
    assert observables.extra is extra


def test_unknown_attribute_is_missing():
    entity = _Entity("arm")
    assert not hasattr(entity.observables, "missing")


def test_root_entity_keys_are_bare_names():
    assert list(_Entity("arena").observables.as_dict()) == ["answer", "tip_pos"]


def test_attached_entity_keys_are_prefixed_with_its_scope():
    _, child = _attached("arena", "arm")
    assert list(child.observables.as_dict()) == ["arm/answer", "arm/tip_pos"]


def test_keys_of_entity_attached_twice_deep_carry_the_full_scope():
    arena, arm = _attached("arena", "jaco_arm")
    hand = _Entity("jaco_hand")
    arm.mjcf_model.worldbody.attach(hand.mjcf_model)
    assert "jaco_arm/jaco_hand/tip_pos" in hand.observables.as_dict()


def test_dict_keys_gives_the_fully_qualified_key():
    _, child = _attached("arena", "arm")
    assert child.observables.dict_keys.tip_pos == "arm/tip_pos"


def test_get_observable_accepts_a_fully_qualified_name():
    _, child = _attached("arena", "arm")
    found = child.observables.get_observable("arm/answer", name_fully_qualified=True)
    assert found is child.observables.answer


def test_get_observable_with_unknown_name_lists_available():
    with pytest.raises(KeyError, match="answer"):
        _Entity("arm").observables.get_observable("nope")


def test_observables_are_disabled_until_enabled():
    entity = _Entity("arm")
    observables = entity.observables
    assert not any(obs.enabled for obs in observables.as_dict().values())
    observables.enable_all()
    assert all(obs.enabled for obs in observables.as_dict().values())
    observables.disable_all()
    assert not any(obs.enabled for obs in observables.as_dict().values())


def test_add_observable_enables_it_unless_told_otherwise():
    observables = _Entity("arm").observables
    observables.add_observable("on", observable.Generic(lambda p: 0.0))
    observables.add_observable("off", observable.Generic(lambda p: 0.0), enabled=False)
    assert observables.on.enabled and not observables.off.enabled


def test_set_options_configures_each_named_observable():
    observables = _Entity("arm").observables
    observables.set_options({"tip_pos": {"buffer_size": 3, "enabled": True}})
    assert (observables.tip_pos.buffer_size, observables.tip_pos.enabled) == (3, True)
    assert observables.answer.buffer_size is None


def test_set_options_with_option_keys_applies_to_every_observable():
    observables = _Entity("arm").observables
    observables.set_options({"update_interval": 5})
    assert observables.tip_pos.update_interval == observables.answer.update_interval == 5


def test_set_options_with_unknown_observable_name_raises_key_error():
    with pytest.raises(KeyError, match="elbow"):
        _Entity("arm").observables.set_options({"elbow": {"delay": 1}})


def test_set_options_with_invalid_value_names_observable_and_option():
    with pytest.raises(ValueError, match=r"'tip_pos'.*'delay'"):
        _Entity("arm").observables.set_options({"tip_pos": {"delay": -2}})


def test_observable_of_attached_entity_reads_its_site_in_the_compiled_model():
    arena, arm = _attached("arena", "arm")
    arm.mjcf_model.find("site", "tip").pos = [0.1, 0.2, 0.3]
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    np.testing.assert_allclose(arm.observables.tip_pos(physics), [0.1, 0.2, 0.3])
