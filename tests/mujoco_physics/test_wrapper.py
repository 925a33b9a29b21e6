"""Tests for mujoco_physics.wrapper: dm_control's struct wrappers, callbacks and mjbindings."""

import pydoc
import subprocess
import sys
import textwrap

import mujoco
import numpy as np
import pytest
from mujoco.introspect import structs as introspect_structs

from mujoco_physics import wrapper
from mujoco_physics.wrapper import core
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


def _introspect_doc(struct: str, field: str) -> str:
    return next(f.doc for f in introspect_structs.STRUCTS[struct].fields if f.name == field)


def _public_fields(struct: type) -> list[str]:
    return [n for n, v in vars(struct).items() if isinstance(v, property) and n[0] != "_"]


def test_every_field_of_the_mujoco_structs_is_a_class_attribute_of_the_wrapper():
    for struct, wrapped in ((mujoco.MjModel, wrapper.MjModel), (mujoco.MjData, wrapper.MjData)):
        missing = [name for name in _public_fields(struct) if name not in dir(wrapped)]
        assert not missing, (wrapped.__name__, missing)
        assert all(isinstance(getattr(wrapped, n), property) for n in _public_fields(struct))


def test_model_field_on_the_class_is_a_property_documented_as_mujoco_describes_it():
    field = type(wrapper.MjModel.from_xml_string(_XML)).geom_pos
    assert isinstance(field, property)
    assert field.__doc__.startswith(_introspect_doc("mjModel", "geom_pos"))
    assert "Shape (ngeom, 3)" in field.__doc__
    assert _introspect_doc("mjModel", "geom_pos") in pydoc.render_doc(field)


def test_data_field_on_the_class_reads_what_the_instance_reads():
    data = wrapper.MjData(wrapper.MjModel.from_xml_string(_XML))
    qpos = type(data).qpos
    assert isinstance(qpos, property)
    assert _introspect_doc("mjData", "qpos") in qpos.__doc__
    assert qpos.__get__(data) is data.qpos is data.qpos
    assert np.shares_memory(data.qpos, data.ptr.qpos)
    np.testing.assert_array_equal(data.qpos, [0, 0, 1, 1, 0, 0, 0])


def test_settable_field_sets_the_struct_and_a_read_only_one_has_no_setter():
    model = wrapper.MjModel.from_xml_string(_XML)
    data = wrapper.MjData(model)
    type(data).time.fset(data, 2.5)
    assert data.ptr.time == 2.5
    data.time = 3.5
    assert type(data).time.fget(data) == 3.5
    assert type(model).nq.fset is None and "read-only" in type(model).nq.__doc__
    with pytest.raises(AttributeError):
        model.nq = 1


def test_scalar_fields_follow_the_simulation():
    model = wrapper.MjModel.from_xml_string(_XML)
    data = wrapper.MjData(model)
    assert data.time == 0
    mujoco.mj_step(model.ptr, data.ptr)
    assert data.time == model.opt.timestep


def test_fields_the_wrappers_define_keep_the_wrappers_meaning():
    model = wrapper.MjModel.from_xml_string(_XML)
    data = wrapper.MjData(model)
    assert data.model is model
    assert len(data.contact) == 0 and len(data.ptr.contact) == 0
    assert model.name == "ball"


def test_core_mjlib_resets_a_core_visualisation_option():
    option = core.MjvOption()
    option.geomgroup[0] = 0
    core.mjlib.mjv_defaultOption(option.ptr)
    assert core.mjlib is mujoco and option.geomgroup[0] == 1


def test_core_mjlib_through_the_dm_control_redirect():
    code = """
        from composer import dm_control_compat
        dm_control_compat.install()
        from dm_control import mujoco
        from dm_control.mujoco.wrapper.core import mjlib
        option = mujoco.wrapper.core.MjvOption()
        option.geomgroup[0] = 0
        mujoco.wrapper.core.mjlib.mjv_defaultOption(option.ptr)
        physics = mujoco.Physics.from_xml_string("<mujoco><worldbody/></mujoco>")
        print(option.geomgroup[0], mjlib.mj_step is __import__("mujoco").mj_step)
        print(type(type(physics.data).qpos).__name__)
    """
    result = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[:2] == ["1 True", "property"]
