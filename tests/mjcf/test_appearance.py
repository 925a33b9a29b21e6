"""Appearance fields: writing them cannot change what mj_forward computes, proven per field."""

import copy

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf import schema
from mjcf.appearance import APPEARANCE_FIELDS, forward_neutral_fields

# Every kind of object that carries a colour or a material, with sensors that read contacts,
# frames, tendons and cameras, and (with a rangefinder) ray casting.
_SCENE = """
<mujoco>
  <asset>
    <texture name="checker" type="2d" builtin="checker" width="8" height="8"/>
    <texture name="flat" type="2d" builtin="flat" width="8" height="8"/>
    <material name="floor" texture="checker" rgba=".5 .5 .5 1" specular=".3"/>
    <material name="arm" texture="flat" emission=".2"/>
  </asset>
  <worldbody>
    <light pos="0 0 3" {light_texture}/>
    <camera name="eye" pos="0 -2 1" xyaxes="1 0 0 0 .5 1"/>
    <geom name="floor" type="plane" size="2 2 .1" material="floor"/>
    <body name="box" pos="0 0 .3">
      <freejoint/>
      <geom name="box" type="box" size=".1 .1 .1" rgba="1 0 0 1"/>
      <site name="pad" size=".12" rgba="0 1 0 1" material="arm"/>
      <site name="top" pos="0 0 .1" size=".02"/>
    </body>
    <body name="arm" pos="1 0 .5">
      <joint name="hinge" type="hinge" axis="0 1 0"/>
      <geom type="capsule" fromto="0 0 0 .3 0 0" size=".03" material="arm"/>
      <site name="tip" pos=".3 0 0"/>
    </body>
    {extra_site}
  </worldbody>
  <deformable>
    <flex name="string" dim="1" body="box arm" vertex="0 0 0 0 0 0" element="0 1"
          material="arm" rgba="0 0 1 1">
      <edge stiffness="1"/>
    </flex>
    <skin name="patch" vertex="0 0 0 .1 0 0 0 .1 0" face="0 1 2" material="floor"
          rgba="1 1 0 1">
      <bone body="box" bindpos="0 0 0" bindquat="1 0 0 0" vertid="0 1 2" vertweight="1 1 1"/>
    </skin>
  </deformable>
  <tendon>
    <spatial name="cord" material="arm" rgba="1 1 0 1">
      <site site="top"/>
      <site site="tip"/>
    </spatial>
  </tendon>
  <actuator><motor joint="hinge"/></actuator>
  <sensor>
    <touch site="pad"/>
    <framepos objtype="site" objname="top"/>
    <tendonpos tendon="cord"/>
    <camprojection site="top" camera="eye"/>
    {extra_sensor}
  </sensor>
</mujoco>
"""
_RANGEFINDER_SITE = "<site name='beam' pos='0 0 1.5' zaxis='0 0 -1'/>"
_RANGEFINDER = "<rangefinder name='range' site='beam'/>"


def _scene(with_rangefinder: bool = False) -> mujoco.MjModel:
    # Lights take a texture only in newer releases (light_texid); where they cannot, the
    # installed MuJoCo has no such field to prove.
    light_takes_texture = (
        "texture" in schema.root_spec().children["worldbody"].children["light"].attributes
    )
    return mujoco.MjModel.from_xml_string(
        _SCENE.format(
            light_texture='texture="flat"' if light_takes_texture else "",
            extra_site=_RANGEFINDER_SITE if with_rangefinder else "",
            extra_sensor=_RANGEFINDER if with_rangefinder else "",
        )
    )


def _moving_state(model: mujoco.MjModel) -> mujoco.MjData:
    """A state with the box fallen onto the floor (so there are contacts) and the arm swinging."""
    data = mujoco.MjData(model)
    data.qvel[-1] = 1.0
    mujoco.mj_step(model, data, 100)
    return data


def _forward_outputs(model: mujoco.MjModel, state: mujoco.MjData) -> dict[str, bytes]:
    data = copy.deepcopy(state)
    mujoco.mj_forward(model, data)
    return {
        name: getattr(data, name).tobytes()
        for name in dir(data)
        if not name.startswith("_") and isinstance(getattr(data, name), np.ndarray)
    }


def _perturbed(name: str, array: np.ndarray) -> np.ndarray:
    """Another valid value for every entry: ids swap between -1 and 0, numbers go to 1 - x."""
    if name.endswith("id"):
        return np.where(array >= 0, -1, 0).astype(array.dtype)
    return (1 - array).astype(array.dtype)


def _release() -> tuple[int, ...]:
    return tuple(int(part) for part in mujoco.__version__.split(".")[:2])


def test_every_appearance_field_leaves_forward_outputs_bit_identical():
    if _release() < (3, 17):
        pytest.skip(
            f"mujoco {mujoco.__version__} leaves island maps (and on 3.16 the efm_* arrays) "
            "unwritten when a model has no islands, so their bytes change with any earlier "
            "write and a bit-for-bit comparison cannot be made; it holds from mujoco 3.17"
        )
    model = _scene()
    state = _moving_state(model)
    reference = _forward_outputs(model, state)
    # Arrays that differ between identical calls cannot be compared: timers, and memory that
    # some releases leave unwritten (mujoco 3.4's island maps when there are no islands).
    unstable = {
        name
        for _ in range(4)
        for name, value in _forward_outputs(model, state).items()
        if value != reference[name]
    }
    assert forward_neutral_fields(model) == APPEARANCE_FIELDS
    for name in sorted(APPEARANCE_FIELDS):
        array = getattr(model, name)
        assert array.size, f"the scene has no {name} to perturb"
        original = array.copy()
        array[...] = _perturbed(name, original)
        outputs = _forward_outputs(model, state)
        array[...] = original
        changed = [key for key in outputs if key not in unstable and outputs[key] != reference[key]]
        assert changed == [], f"writing {name} changed {changed}"


def test_appearance_fields_are_the_colours_and_materials_of_every_object():
    assert {"geom_rgba", "site_rgba", "tendon_rgba", "mat_rgba", "geom_matid"} <= APPEARANCE_FIELDS
    assert {"geom_size", "body_mass", "geom_friction", "light_pos"}.isdisjoint(APPEARANCE_FIELDS)


def test_a_rangefinder_reads_geom_transparency_so_its_model_exempts_nothing():
    model = _scene(with_rangefinder=True)
    state = _moving_state(model)
    sensor = model.sensor("range").adr[0]
    box = model.geom("box").id
    seen = copy.deepcopy(state)
    mujoco.mj_forward(model, seen)
    model.geom_rgba[box, 3] = 0
    hidden = copy.deepcopy(state)
    mujoco.mj_forward(model, hidden)
    assert seen.sensordata[sensor] == pytest.approx(1.3, abs=0.01)
    # The floor belongs to the beam's own body (the world), which the ray does not see.
    assert hidden.sensordata[sensor] == -1
    assert forward_neutral_fields(model) == frozenset()


def _button_scene(with_rangefinder: bool):
    root = mjcf.RootElement()
    button = root.worldbody.add("body", name="button", pos=[0, 0, 0.05])
    button.add("freejoint")
    geom = button.add("geom", type="box", size=[0.1, 0.1, 0.05], rgba=[0, 0, 1, 1])
    pad = button.add("site", name="pad", size=[0.12])
    root.sensor.add("touch", name="touch", site=pad)
    if with_rangefinder:
        beam = root.worldbody.add("site", name="beam", pos=[0, 0, 1], zaxis=[0, 0, -1])
        root.sensor.add("rangefinder", name="range", site=beam)
    return root, geom


def test_writing_rgba_through_a_binding_leaves_the_physics_clean():
    root, geom = _button_scene(with_rangefinder=False)
    physics = mjcf.Physics.from_mjcf_model(root)
    physics.bind(geom).rgba = [1, 0, 0, 1]
    assert not physics.is_dirty
    np.testing.assert_array_equal(physics.model.geom_rgba[0], [1, 0, 0, 1])
    physics.bind(geom).size = [0.2, 0.2, 0.05]
    assert physics.is_dirty


def test_writing_rgba_in_a_model_with_a_rangefinder_updates_its_reading():
    root, geom = _button_scene(with_rangefinder=True)
    physics = mjcf.Physics.from_mjcf_model(root)
    sensor = root.find("sensor", "range")
    assert physics.bind(sensor).sensordata[0] == pytest.approx(0.9)
    physics.bind(geom).rgba = [0, 0, 1, 0]
    assert physics.is_dirty
    assert physics.bind(sensor).sensordata[0] == -1


@pytest.mark.parametrize("with_rangefinder", [False, True])
def test_patching_rgba_leaves_the_physics_clean_as_a_binding_write(with_rangefinder):
    root, geom = _button_scene(with_rangefinder)
    physics = mjcf.Physics.from_mjcf_model(root)
    physics.forward()
    count = root.modification_count
    geom.rgba = [1, 0, 0, 1]
    assert physics.apply_attribute_changes(root.attribute_changes_since(count))
    np.testing.assert_array_equal(physics.model.geom_rgba[0], [1, 0, 0, 1])
    # A rangefinder sees colours, so there the patch needs a forward before the next read.
    assert physics.is_dirty == with_rangefinder
    count = root.modification_count
    geom.friction = [0.5, 0.005, 0.0001]
    assert physics.apply_attribute_changes(root.attribute_changes_since(count))
    assert physics.is_dirty
