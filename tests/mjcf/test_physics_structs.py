"""Tests for physics.model / physics.data: NumPy views, .ptr and dm_control's helpers."""

import mujoco
import numpy as np
import pytest

from mjcf.physics import Physics

_XML = """
<mujoco>
  <worldbody>
    <body name="box_body" pos="0 0 1">
      <freejoint/>
      <geom name="box" type="box" size="0.1 0.1 0.1"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture
def physics():
    return Physics.from_xml_string(_XML)


def test_ptr_gives_the_mujoco_objects(physics):
    assert isinstance(physics.model.ptr, mujoco.MjModel)
    assert isinstance(physics.data.ptr, mujoco.MjData)
    mujoco.mj_step(physics.model.ptr, physics.data.ptr)
    assert physics.data.time > 0


def test_data_arrays_are_views_of_mujoco_memory(physics):
    physics.data.qpos[2] = 5
    assert physics.data.ptr.qpos[2] == 5


def test_model_arrays_are_views_of_mujoco_memory(physics):
    physics.model.geom_rgba[0, 0] = 0.25
    assert physics.model.ptr.geom_rgba[0, 0] == 0.25


def test_scalar_data_fields_are_read_fresh(physics):
    physics.step(3)
    assert physics.data.time == pytest.approx(3 * physics.model.opt.timestep)


def test_assigning_a_data_attribute_writes_mujoco(physics):
    physics.data.time = 2.5
    assert physics.data.ptr.time == 2.5


def test_contact_arrays_follow_the_number_of_contacts(physics):
    assert len(physics.data.efc_force) == physics.data.nefc
    physics.data.qpos[2] = 0.05
    physics.forward()
    assert len(physics.data.efc_force) == physics.data.nefc


def test_data_model_is_the_wrapped_model(physics):
    assert physics.data.model is physics.model


def test_name2id_and_id2name_round_trip(physics):
    box = physics.model.name2id("box", "geom")
    assert physics.model.id2name(box, "geom") == "box"
    assert physics.model.name2id("box_body", mujoco.mjtObj.mjOBJ_BODY) == 1


def test_name2id_of_a_missing_name_is_an_error(physics):
    with pytest.raises(ValueError, match="'geom' with name 'ghost'"):
        physics.model.name2id("ghost", "geom")


def test_unknown_object_type_lists_the_known_ones(physics):
    with pytest.raises(ValueError, match="'gizmo'.*geom"):
        physics.model.name2id("box", "gizmo")


def test_id2name_of_an_unnamed_object_is_empty(physics):
    assert physics.model.id2name(0, "joint") == ""


def test_disable_switches_gravity_off_inside_the_block_only(physics):
    with physics.model.disable("gravity"):
        physics.forward()
        physics.step(10)
        np.testing.assert_array_equal(physics.data.qvel, np.zeros(6))
    physics.step(10)
    assert physics.data.qvel[2] < 0


def test_disable_rejects_unknown_flags(physics):
    with pytest.raises(ValueError, match="'gravitee'"):
        with physics.model.disable("gravitee"):
            pass


def test_enable_sets_an_enable_flag_inside_the_block_only(physics):
    energy = int(mujoco.mjtEnableBit.mjENBL_ENERGY)
    with physics.model.enable("energy"):
        assert physics.model.opt.enableflags & energy
    assert not physics.model.opt.enableflags & energy


def test_dir_lists_mujoco_fields(physics):
    assert {"geom_rgba", "nbody", "opt", "name2id"} <= set(dir(physics.model))
    assert {"qpos", "xpos", "time"} <= set(dir(physics.data))
