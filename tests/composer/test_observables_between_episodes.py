"""Observables that a task adds, replaces or removes between episodes take effect at the
next reset, whether or not the MJCF model changed (dm_control builds a new observation
updater at every recompile, which is every episode by default)."""

import collections

import numpy as np
import pytest
from composer_scene import ReachTask

import composer
from composer import environment
from composer.observation import observable


def _constant(value):
    obs = observable.Generic(lambda physics: np.array([value]))
    obs.enabled = True
    return obs


class ExtraObservables(ReachTask):
    """The reach task plus whatever task observables the test puts in `extra`."""

    def __init__(self):
        super().__init__()
        self.extra = {}

    @property
    def task_observables(self):
        return dict(self.extra)


def _unchanged(task):
    pass


def _recoloured(task):
    task.box.geom.rgba = [1.0, 0.0, 0.0, 1.0]


def _new_site(task):
    task.arm.mjcf_model.worldbody.add("site", name="marker")


MODEL_CHANGES = pytest.mark.parametrize(
    "change_model", [_unchanged, _recoloured, _new_site], ids=["same", "parameters", "structure"]
)


@MODEL_CHANGES
def test_an_observable_added_between_episodes_is_observed_from_the_next_reset(change_model):
    task = ExtraObservables()
    env = composer.Environment(task)
    assert "seven" not in env.reset().observation
    task.extra["seven"] = _constant(7.0)
    change_model(task)
    assert env.reset().observation["seven"].tolist() == [[7.0]]
    assert "seven" in env.observation_spec()
    assert env.step(np.zeros(2)).observation["seven"].tolist() == [[7.0]]


@MODEL_CHANGES
def test_an_observable_replaced_under_its_name_is_read_from_the_next_reset(change_model):
    task = ExtraObservables()
    task.extra["value"] = _constant(1.0)
    env = composer.Environment(task)
    assert env.reset().observation["value"].tolist() == [[1.0]]
    task.extra["value"] = _constant(2.0)
    change_model(task)
    assert env.reset().observation["value"].tolist() == [[2.0]]


@MODEL_CHANGES
def test_an_observable_removed_between_episodes_leaves_the_observation(change_model):
    task = ExtraObservables()
    task.extra["value"] = _constant(1.0)
    env = composer.Environment(task)
    assert "value" in env.reset().observation
    del task.extra["value"]
    change_model(task)
    assert "value" not in env.reset().observation
    assert "value" not in env.observation_spec()


def _collection(*names, container=dict, observables=None):
    observables = observables or {}
    return environment._collected(container((name, observables[name]) for name in names))


_A, _B = _constant(1.0), _constant(2.0)
_BOTH = {"a": _A, "b": _B}
_SWAPPED = {"a": _B, "b": _A}


@pytest.mark.parametrize(
    ("second", "same"),
    [
        (_collection("a", "b", observables=_BOTH), True),
        (None, False),
        (_collection("a", observables=_BOTH), False),
        (_collection("a", "b", observables=_SWAPPED), False),
        (_collection("b", "a", observables=_BOTH), False),
        (_collection("a", "b", container=collections.OrderedDict, observables=_BOTH), False),
        (environment._collected([dict(_BOTH)]), False),
    ],
    ids=["same", "none", "fewer", "other_objects", "other_order", "other_dict_type", "in_a_list"],
)
def test_collections_are_equal_only_for_the_same_names_objects_and_types(second, same):
    # Whether the observation updater may be kept: only when nothing it depends on changed.
    first = _collection("a", "b", observables=_BOTH)
    assert (first == second) is same


@pytest.mark.parametrize(
    ("first", "second", "same"),
    [
        ([{"a": _A}, {"b": _B}], [{"a": _A}, {"b": _B}], True),
        ([{"a": _A}, {"b": _B}], [{"a": _A}], False),
        ([{"a": _A}, {"b": _B}], [{"a": _A}, collections.OrderedDict(b=_B)], False),
        ([{"a": _A}, {"b": _B}], [{"a": _A}, {"b": _B, "c": _A}], False),
    ],
    ids=["same", "fewer_dicts", "other_dict_type", "more_items"],
)
def test_collections_compare_lists_of_dicts_dict_by_dict(first, second, same):
    assert (environment._collected(first) == environment._collected(second)) is same
