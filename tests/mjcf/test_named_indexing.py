"""Tests for physics.named: MjModel/MjData fields indexed by object names."""

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf.physics import Physics

_XML = """
<mujoco>
  <worldbody>
    <body name="ball_body" pos="0 0 1">
      <freejoint name="free"/>
      <geom name="ball" size="0.1" rgba="1 0 0 1"/>
    </body>
    <body name="arm" pos="1 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0"/>
      <geom name="upper" size="0.05" rgba="0 1 0 1"/>
      <body name="forearm" pos="0.3 0 0">
        <joint name="ball_joint" type="ball"/>
        <geom name="lower" size="0.03" rgba="0 0 1 1"/>
        <site name="tip" pos="0.3 0 0"/>
      </body>
    </body>
    <body name="target" mocap="true" pos="0 1 1"/>
  </worldbody>
  <actuator>
    <motor name="motor" joint="hinge"/>
  </actuator>
  <sensor>
    <jointpos name="angle" joint="hinge"/>
    <framepos name="tip_pos" objtype="site" objname="tip"/>
  </sensor>
</mujoco>
"""


@pytest.fixture
def physics():
    return Physics.from_xml_string(_XML)


def _id(physics, obj_type, name):
    return mujoco.mj_name2id(physics.model.ptr, obj_type, name)


def test_body_position_by_name(physics):
    np.testing.assert_array_equal(physics.named.data.xpos["arm"], [1, 0, 1])


def test_list_of_names_gives_one_row_each(physics):
    np.testing.assert_array_equal(
        physics.named.data.xpos[["arm", "ball_body"]], [[1, 0, 1], [0, 0, 1]]
    )


def test_model_field_by_list_of_names(physics):
    rgba = physics.named.model.geom_rgba[["lower", "ball"]]
    np.testing.assert_array_equal(rgba, [[0, 0, 1, 1], [1, 0, 0, 1]])


def test_write_by_name_reaches_the_model(physics):
    physics.named.model.geom_rgba["upper"] = [0.5, 0.5, 0.5, 1]
    upper = _id(physics, mujoco.mjtObj.mjOBJ_GEOM, "upper")
    np.testing.assert_array_equal(physics.model.geom_rgba[upper], [0.5, 0.5, 0.5, 1])


def test_write_by_list_of_names(physics):
    physics.named.model.geom_rgba[["upper", "lower"], 3] = 0.25
    np.testing.assert_array_equal(physics.model.geom_rgba[:, 3], [1, 0.25, 0.25])


def test_qpos_of_free_joint_is_seven_wide(physics):
    np.testing.assert_array_equal(physics.named.data.qpos["free"], [0, 0, 1, 1, 0, 0, 0])


def test_qpos_of_ball_joint_is_four_wide(physics):
    np.testing.assert_array_equal(physics.named.data.qpos["ball_joint"], [1, 0, 0, 0])


def test_qpos_of_hinge_is_a_one_element_array(physics):
    assert physics.named.data.qpos["hinge"].shape == (1,)


def test_qvel_of_list_of_joints_concatenates(physics):
    physics.data.qvel[:] = np.arange(physics.model.nv)
    np.testing.assert_array_equal(physics.named.data.qvel[["hinge", "ball_joint"]], [6, 7, 8, 9])


def test_qpos_write_by_joint_name(physics):
    physics.named.data.qpos["hinge"] = 0.3
    hinge = _id(physics, mujoco.mjtObj.mjOBJ_JOINT, "hinge")
    assert physics.data.qpos[physics.model.jnt_qposadr[hinge]] == 0.3


def test_dof_field_by_joint_name(physics):
    assert physics.named.model.dof_damping["ball_joint"].shape == (3,)


def test_sensordata_by_sensor_name(physics):
    np.testing.assert_allclose(physics.named.data.sensordata["tip_pos"], [1.6, 0, 1])
    assert physics.named.data.sensordata["angle"].shape == (1,)


def test_control_by_actuator_name_is_a_scalar(physics):
    physics.named.data.ctrl["motor"] = 0.5
    assert physics.named.data.ctrl["motor"] == 0.5
    assert physics.data.ctrl[0] == 0.5


def test_mocap_position_by_body_name(physics):
    np.testing.assert_array_equal(physics.named.data.mocap_pos["target"], [0, 1, 1])


def test_mocap_position_of_a_regular_body_is_a_key_error(physics):
    with pytest.raises(KeyError, match="'arm' has no row"):
        _ = physics.named.data.mocap_pos["arm"]


def test_column_name_selects_a_coordinate(physics):
    assert physics.named.data.xpos["arm", "z"] == 1
    np.testing.assert_array_equal(physics.named.data.site_xpos["tip", ["x", "z"]], [1.6, 1])


def test_quaternion_columns_have_names(physics):
    assert physics.named.data.xquat["arm", "qw"] == 1


def test_unknown_column_name_is_a_key_error(physics):
    with pytest.raises(KeyError, match="'w'"):
        _ = physics.named.data.xpos["arm", "w"]


def test_integer_and_slice_keys_index_rows_directly(physics):
    np.testing.assert_array_equal(physics.named.data.xpos[2], physics.data.xpos[2])
    np.testing.assert_array_equal(physics.named.data.xpos[1:3], physics.data.xpos[1:3])


def test_unknown_name_is_a_key_error_naming_it(physics):
    with pytest.raises(KeyError, match="no body named 'leg'"):
        _ = physics.named.data.xpos["leg"]


def test_field_without_named_rows_rejects_names(physics):
    with pytest.raises(KeyError, match="have no names"):
        _ = physics.named.data.efc_force["x"]


def test_constraint_field_follows_the_current_number_of_constraints(physics):
    assert len(physics.named.data.efc_force) == physics.data.nefc


def test_unknown_field_is_an_attribute_error(physics):
    with pytest.raises(AttributeError, match="'geom_colour'"):
        _ = physics.named.model.geom_colour


def test_fields_are_listed(physics):
    assert {"xpos", "qpos", "sensordata", "ctrl"} <= set(dir(physics.named.data))
    assert {"geom_rgba", "body_mass", "jnt_range"} <= set(dir(physics.named.model))


def test_repr_shows_names_columns_and_values(physics):
    title, header, *rows = repr(physics.named.data.site_xpos).splitlines()
    assert title == "FieldIndexer(site_xpos):"
    assert header.split() == ["x", "y", "z"]
    assert rows[0].split() == ["0", "tip", "[", "1.6", "0", "1", "]"]


def test_repr_labels_every_row_of_a_multi_row_object(physics):
    lines = repr(physics.named.data.qpos).splitlines()[1:]
    assert sum("free" in line for line in lines) == 7


def test_repr_of_an_empty_field_says_it_is_empty(physics):
    assert repr(physics.named.data.efc_force) == "FieldIndexer(efc_force):\n(empty)"


def test_repr_aligns_values_in_fixed_width_columns(physics):
    rows = repr(physics.named.model.actuator_gear).splitlines()[1:]
    assert rows == ["0 motor [ 1         0         0         0         0         0       ]"]


def test_axes_row_names_list_one_name_per_object(physics):
    assert physics.named.data.qpos.axes.row.names == ["free", "hinge", "ball_joint"]
    assert physics.named.data.qpos.axes.col is None


def test_axes_col_names_list_column_labels(physics):
    axes = physics.named.data.xpos.axes
    assert axes.row.names == ["world", "ball_body", "arm", "forearm", "target"]
    assert axes.col.names == ["x", "y", "z"]


def test_row_axis_converts_joint_names_to_their_dof_rows(physics):
    # Degrees of freedom: free joint 0-5, hinge 6, ball joint 7-9.
    row = physics.named.model.dof_jntid.axes.row
    np.testing.assert_array_equal(row.convert_key_item(["hinge", "ball_joint"]), [6, 7, 8, 9])
    assert physics.named.model.dof_jntid[row.convert_key_item("hinge")].tolist() == [1]
    assert row.convert_key_item(slice(1, 3)) == slice(1, 3)


def test_column_axis_converts_labels_to_column_indices(physics):
    assert physics.named.data.xpos.axes.col.convert_key_item("z") == 2
    assert physics.named.data.xpos.axes.col.convert_key_item(["y", "x"]) == [1, 0]


def test_axis_conversion_of_an_unknown_name_is_a_key_error(physics):
    with pytest.raises(KeyError, match="nowhere"):
        physics.named.model.dof_jntid.axes.row.convert_key_item(["nowhere"])


def test_unlabelled_axes_have_no_names(physics):
    assert physics.named.data.efc_force.axes.row.names is None
    assert physics.named.data.xfrc_applied.axes.col.names is None


def test_array_attributes_are_those_of_the_field(physics):
    qpos = physics.named.data.qpos
    assert qpos.shape == (physics.model.nq,)
    assert qpos.dtype == np.float64
    copied = qpos.copy()
    copied[0] = 123.0
    assert physics.data.qpos[0] != 123.0


def test_dof_field_shadowed_in_bindings_is_still_named(physics):
    assert physics.named.model.dof_solref["ball_joint"].shape == (3, 2)


def test_attached_model_objects_are_named_with_their_scope():
    root = mjcf.RootElement(model="scene")
    robot = mjcf.RootElement(model="robot")
    robot.worldbody.add("site", name="grip", pos=[0, 0, 0.5])
    root.worldbody.attach(robot).pos = [1, 0, 0]
    physics = Physics.from_mjcf_model(root)
    np.testing.assert_array_equal(physics.named.data.site_xpos["robot/grip"], [1, 0, 0.5])


def test_open_mesh_grid_of_names_and_column_labels(physics):
    rows, columns = np.ix_(["lower", "ball"], ["r", "a"])
    np.testing.assert_array_equal(physics.named.model.geom_rgba[rows, columns], [[0, 1], [1, 1]])
    physics.named.model.geom_rgba[rows, columns] = [[0.5, 0.25], [0.75, 0.125]]
    np.testing.assert_array_equal(physics.named.model.geom_rgba["lower"], [0.5, 0, 1, 0.25])


def test_grid_of_names_owning_several_rows_is_index_error(physics):
    with pytest.raises(IndexError, match="several rows"):
        physics.named.data.qpos[np.array([["free"], ["hinge"]])]
