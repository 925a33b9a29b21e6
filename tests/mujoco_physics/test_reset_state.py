"""mujoco_physics.reset_state: resetting by copying the data the last reset left."""

import mujoco
import numpy as np
import pytest

from mujoco_physics.engine import Physics
from mujoco_physics.reset_state import ResetState

# A box that starts sunk into the floor: the forward of a reset finds contacts and
# solves for their forces, so what it leaves depends on the model's contact parameters.
_XML = """
<mujoco>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="box" pos="0 0 0.08">
      <freejoint/>
      <geom name="box" type="box" size="0.1 0.1 0.1" mass="2"/>
    </body>
    <body name="pendulum" pos="0.5 0 1">
      <joint name="hinge" axis="0 1 0" damping="0.1"/>
      <geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02"/>
    </body>
  </worldbody>
  <actuator><motor joint="hinge"/></actuator>
  <sensor><jointpos joint="hinge"/><framepos objtype="body" objname="box"/></sensor>
</mujoco>
"""


def _data_bytes(data: mujoco.MjData) -> dict[str, bytes]:
    return {
        name: value.tobytes()
        for name in dir(data)
        if not name.startswith("_") and isinstance(value := getattr(data, name), np.ndarray)
    }


def _arrays_of(data: mujoco.MjData) -> list[np.ndarray]:
    return [
        value
        for name in dir(data)
        if not name.startswith("_")
        and isinstance(value := getattr(data, name), np.ndarray)
        and value.flags.writeable
    ]


def _physics() -> Physics:
    return Physics.from_xml_string(_XML)


def _play_an_episode(physics: Physics) -> None:
    """Leaves the data far from a reset's: moved, actuated, pushed and stepped."""
    physics.data.qpos[:3] = [0.2, -0.1, 0.5]
    physics.data.ctrl[:] = 0.7
    physics.data.xfrc_applied[1] = [1, 2, 3, 0, 0, 0.5]
    physics.step(25)


def _fresh_reset(physics: Physics) -> dict[str, bytes]:
    """What `reset()` leaves in MjData for `physics`'s model, in the arrays it defines.

    Scratch arrays a forward leaves unwritten (the sparse Jacobian's of a dense solve, ...)
    keep whatever the memory held: they are left out, found as the arrays that differ
    between resets of data whose every array was filled with one byte pattern or another
    after a reset (new data would hold whatever memory it was given).
    """
    resets = []
    for pattern in (0xAB, 0x5C):
        patterned = Physics.from_model(physics.model.ptr)
        # Filled where a reset puts its arrays: the arena holds them at the same places again.
        patterned.reset()
        for value in _arrays_of(patterned.data.ptr):
            value.view(np.uint8).fill(pattern)
        patterned.reset()
        resets.append(_data_bytes(patterned.data.ptr))
    first, second = resets
    return {name: value for name, value in first.items() if second[name] == value}


def _defined(data: mujoco.MjData, expected: dict[str, bytes]) -> dict[str, bytes]:
    return {name: value for name, value in _data_bytes(data).items() if name in expected}


def test_a_reset_after_an_episode_leaves_the_bytes_of_a_fresh_reset():
    physics, state = _physics(), ResetState()
    for _ in range(3):
        state.reset(physics)
        expected = _fresh_reset(physics)
        assert _defined(physics.data.ptr, expected) == expected
        _play_an_episode(physics)


needs_copy = pytest.mark.skipif(
    not hasattr(mujoco, "mj_copyData"),
    reason=f"mujoco {mujoco.__version__}'s bindings have no mj_copyData: every reset computes",
)


@needs_copy
def test_data_is_kept_from_the_second_reset_of_a_model_on(monkeypatch):
    physics, state = _physics(), ResetState()
    resets = []
    original = Physics.reset
    monkeypatch.setattr(Physics, "reset", lambda self: resets.append(self) or original(self))
    for _ in range(4):
        state.reset(physics)
        _play_an_episode(physics)
    assert len(resets) == 2


@needs_copy
def test_the_owner_must_invalidate_after_changing_a_field_forward_reads():
    physics, state = _physics(), ResetState()
    state.reset(physics)
    state.reset(physics)
    physics.model.geom_solref[1] = [0.05, 0.5]  # softer contact: other contact forces
    expected = _fresh_reset(physics)
    state.reset(physics)
    # Not told, the state copies what the old model's reset left (the documented contract).
    assert _defined(physics.data.ptr, expected)["efc_force"] != expected["efc_force"]
    state.invalidate()
    state.reset(physics)
    assert _defined(physics.data.ptr, expected) == expected


def test_a_physics_with_another_model_is_reset_afresh():
    physics, state = _physics(), ResetState()
    state.reset(physics)
    heavier = mujoco.MjModel.from_xml_string(_XML.replace('mass="2"', 'mass="5"'))
    other = Physics.from_model(heavier)
    state.reset(other)
    expected = _fresh_reset(other)
    assert _defined(other.data.ptr, expected) == expected


def test_with_a_global_callback_set_every_reset_runs_forward():
    physics, state = _physics(), ResetState()
    calls = []
    mujoco.set_mjcb_passive(lambda model, data: calls.append(data.time))
    try:
        for _ in range(3):
            state.reset(physics)
            _play_an_episode(physics)
        calls.clear()
        state.reset(physics)
    finally:
        mujoco.set_mjcb_passive(None)
    assert len(calls) == 1  # the reset's own forward called it
