"""Tests for mujoco_physics.wrapper: dm_control's struct wrappers, callbacks and mjbindings."""

import mujoco
import numpy as np
import pytest

from mujoco_physics import wrapper
from mujoco_physics.wrapper.mjbindings import constants, enums, mjlib, sizes

_XML = """
<mujoco model="ball">
  <worldbody>
    <body name="ball" pos="0 0 1"><freejoint/><geom name="sphere" size="0.1"/></body>
  </worldbody>
</mujoco>
"""


def test_model_from_bad_xml_raises_wrapper_error_which_is_a_value_error():
    with pytest.raises(wrapper.Error, match=r"unrecognized element\nElement 'bogus'"):
        wrapper.MjModel.from_xml_string("<mujoco><worldbody><bogus/></worldbody></mujoco>")
    assert issubclass(wrapper.Error, ValueError)


def test_data_allocates_for_a_wrapped_model_or_wraps_raw_data():
    model = wrapper.MjModel.from_xml_string(_XML)
    data = wrapper.MjData(model)
    assert data.model is model and data.qpos.shape == (7,)
    raw = mujoco.MjData(model.ptr)
    assert wrapper.MjData(raw).ptr is raw
    with pytest.raises(TypeError, match="expects a wrapper.MjModel or a mujoco.MjData, got str"):
        wrapper.MjData("model")


def test_object_velocity_is_linear_then_angular_by_name():
    model = wrapper.MjModel.from_xml_string(_XML)
    data = wrapper.MjData(model)
    data.qvel[:] = [1, 2, 3, 0.1, 0.2, 0.3]
    mujoco.mj_forward(model.ptr, data.ptr)
    velocity = data.object_velocity("ball", "body")
    np.testing.assert_allclose(velocity, [[1, 2, 3], [0.1, 0.2, 0.3]])


def test_callback_context_sets_and_restores_a_global_callback():
    model = wrapper.MjModel.from_xml_string(_XML)
    data = wrapper.MjData(model)
    calls = []
    with wrapper.callback_context("mjcb_passive", lambda m, d: calls.append(d.time)):
        mujoco.mj_step(model.ptr, data.ptr)
    mujoco.mj_step(model.ptr, data.ptr)
    assert len(calls) == 1
    assert mujoco.get_mjcb_passive() is None
    with pytest.raises(ValueError, match="unknown MuJoCo callback 'mjcb_nothing'"):
        wrapper.set_callback("mjcb_nothing", None)


def test_enums_are_named_tuples_of_the_installed_values():
    assert enums.mjtObj.mjOBJ_BODY == 1
    assert enums.mjtJoint.mjJNT_HINGE == 3
    assert isinstance(enums.mjtJoint.mjJNT_FREE, int)
    assert enums.mjtGeom._fields[0] == "mjGEOM_PLANE"


def test_constants_sizes_and_mjlib_come_from_the_installed_mujoco():
    assert constants.mjMAXVAL == 1e10
    assert constants.mjDISABLESTRING[0] == "Constraint"
    assert sizes.array_sizes["mjmodel"]["geom_size"] == ("ngeom", 3)
    assert sizes.array_sizes["mjdata"]["qpos"] == ("nq",)
    assert mjlib.mj_step is mujoco.mj_step


def test_visualisation_structs_pass_themselves_as_ptr_to_mujoco():
    option = wrapper.MjvOption()
    option.geomgroup[0] = 0
    mujoco.mjv_defaultOption(option.ptr)
    assert option.ptr is option and option.geomgroup[0] == 1
    camera = wrapper.MjvCamera()
    mujoco.mjv_defaultFreeCamera(wrapper.MjModel.from_xml_string(_XML).ptr, camera.ptr)
    assert camera.type == mujoco.mjtCamera.mjCAMERA_FREE


def test_scene_geoms_are_the_ones_in_use():
    scene = wrapper.MjvScene(wrapper.MjModel.from_xml_string(_XML), max_geom=10)
    assert len(scene.geoms) == 0
    scene.ngeom = 2
    assert len(scene.geoms) == 2


def test_mjr_context_names_a_bad_font_scale():
    with pytest.raises(ValueError) as raised:
        wrapper.MjrContext(wrapper.MjModel.from_xml_string(_XML), font_scale=99)
    assert str(raised.value) == "font_scale: expected one of [50, 100, 150, 200, 250, 300], got 99"
