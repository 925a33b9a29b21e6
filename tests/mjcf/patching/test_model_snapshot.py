"""mjcf.patching.model_snapshot: restoring a compiled model's parameters in place."""

import mujoco
import numpy as np
import pytest

from mjcf.patching.model_snapshot import ModelSnapshot, snapshots_supported

_XML = """
<mujoco>
  <option timestep="0.004" gravity="0 0 -9"/>
  <asset>
    <texture name="grid" type="2d" builtin="checker" width="32" height="32"/>
    <material name="grid" texture="grid"/>
  </asset>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1" material="grid"/>
    <body name="ball" pos="0 0 1">
      <freejoint/>
      <geom name="ball" size="0.1" mass="2"/>
      <site name="centre"/>
    </body>
  </worldbody>
  <sensor><accelerometer site="centre"/></sensor>
</mujoco>
"""


def _array_fields(model):
    return {
        name: getattr(model, name)
        for name in dir(model)
        if not name.startswith("_") and isinstance(getattr(model, name), np.ndarray)
    }


def test_snapshots_are_supported_by_the_installed_mujoco():
    assert snapshots_supported()


def test_restore_undoes_writes_to_every_array_field():
    model = mujoco.MjModel.from_xml_string(_XML)
    snapshot = ModelSnapshot(model)
    for array in _array_fields(model).values():
        if array.size and array.flags.writeable:
            array.flat[0] = 7
    snapshot.restore()
    pristine = mujoco.MjModel.from_xml_string(_XML)
    for name, array in _array_fields(pristine).items():
        np.testing.assert_array_equal(getattr(model, name), array, err_msg=name)


def test_restore_undoes_writes_to_option_visual_and_statistic_structs():
    model = mujoco.MjModel.from_xml_string(_XML)
    snapshot = ModelSnapshot(model)
    model.opt.timestep = 0.1
    model.opt.gravity[:] = 0
    model.vis.global_.fovy = 10
    model.stat.extent = 99
    snapshot.restore()
    assert model.opt.timestep == 0.004
    np.testing.assert_array_equal(model.opt.gravity, [0, 0, -9])
    assert model.vis.global_.fovy == mujoco.MjModel.from_xml_string(_XML).vis.global_.fovy
    assert model.stat.extent == mujoco.MjModel.from_xml_string(_XML).stat.extent


def test_views_taken_before_restore_see_restored_values():
    model = mujoco.MjModel.from_xml_string(_XML)
    mass = model.body_mass
    snapshot = ModelSnapshot(model)
    mass[1] = 50
    snapshot.restore()
    assert mass[1] == 2


def test_snapshot_taken_after_a_change_restores_that_change():
    model = mujoco.MjModel.from_xml_string(_XML)
    model.geom_rgba[1] = [1, 0, 0, 1]
    snapshot = ModelSnapshot(model)
    model.geom_rgba[1] = [0, 0, 1, 1]
    snapshot.restore()
    np.testing.assert_array_equal(model.geom_rgba[1], [1, 0, 0, 1])


def _variant(old, new):
    return mujoco.MjModel.from_xml_string(_XML.replace(old, new))


def test_load_takes_the_parameters_of_a_model_with_the_same_structure():
    model = mujoco.MjModel.from_xml_string(_XML)
    mass = model.body_mass
    snapshot = ModelSnapshot(model)
    assert snapshot.load(_variant('mass="2"', 'mass="3"'))
    assert mass[1] == 3
    mass[1] = 10
    snapshot.restore()
    assert mass[1] == 3


def test_load_takes_option_values_of_the_other_model():
    model = mujoco.MjModel.from_xml_string(_XML)
    snapshot = ModelSnapshot(model)
    assert snapshot.load(_variant('timestep="0.004"', 'timestep="0.001"'))
    assert model.opt.timestep == 0.001


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ('<site name="centre"/>', '<site name="centre"/><site name="extra"/>'),
        ('name="ball" pos', 'name="bell" pos'),
        ('width="32"', 'width="16"'),
        ('builtin="checker"', 'builtin="checker" rgb1="1 0 0"'),
        ("<option", '<size nuserdata="3"/><option'),
    ],
    ids=["more sites", "renamed body", "texture size", "texture colour", "data size"],
)
def test_load_refuses_a_model_with_another_structure_and_changes_nothing(old, new):
    model = mujoco.MjModel.from_xml_string(_XML)
    snapshot = ModelSnapshot(model)
    model.body_mass[1] = 5
    assert not snapshot.load(_variant(old, new))
    assert model.body_mass[1] == 5
    snapshot.restore()
    assert model.body_mass[1] == 2


def test_load_refuses_a_model_with_the_same_sizes_but_other_joint_types():
    body = "<body><joint type='{}'/><geom size='1'/></body>"
    xml = "<mujoco><worldbody>{}{}</worldbody></mujoco>"
    model = mujoco.MjModel.from_xml_string(xml.format(body.format("hinge"), body.format("ball")))
    other = mujoco.MjModel.from_xml_string(xml.format(body.format("ball"), body.format("hinge")))
    assert (model.nq, model.nv) == (other.nq, other.nv)
    assert not ModelSnapshot(model).load(other)
