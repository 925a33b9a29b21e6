"""mjcf.patching.model_patch: writing changed attribute values into a compiled model equals
a recompile.

Each test changes a model, patches a copy of its old compile and recompiles it, then
compares every MjModel array byte for byte (in the style of test_appearance.py).
"""

import copy

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf.patching import patchable_attributes
from mjcf.patching.compiled_model import CompiledModel, ModelUpdate
from mjcf.patching.model_snapshot import ModelSnapshot

_SCENE = """
<mujoco model="scene">
  <compiler angle="radian"/>
  <default>
    <joint frictionloss="0.2"/>
    <default class="stiff">
      <joint frictionloss="3"/>
    </default>
  </default>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1" friction="1 0.005 0.0001"/>
    <body name="arm" pos="0 0 0.5">
      <joint name="shoulder" axis="0 1 0" class="stiff"/>
      <geom name="upper" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" rgba="1 0 0 1"/>
      <body name="forearm" pos="0.3 0 0">
        <joint name="elbow" axis="0 1 0"/>
        <joint name="wrist" axis="1 0 0" frictionloss="0.7"/>
        <geom name="lower" type="box" size="0.1 0.02 0.02"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="shoulder" joint="shoulder" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""


@pytest.fixture
def scene():
    root = mjcf.from_xml_string(_SCENE)
    physics = mjcf.Physics.from_mjcf_model(root)
    return root, physics, root.modification_count


def _model_bytes(model: mujoco.MjModel) -> dict[str, bytes]:
    return {
        name: value.tobytes()
        for name in dir(model)
        if not name.startswith("_") and isinstance(value := getattr(model, name), np.ndarray)
    }


def _assert_equals_a_recompile(root, physics):
    patched = _model_bytes(physics.model.ptr)
    compiled = _model_bytes(mjcf.Physics.from_mjcf_model(root).model.ptr)
    assert [name for name in compiled if patched[name] != compiled[name]] == []


def _patch(root, physics, count) -> bool:
    return physics.apply_attribute_changes(root.attribute_changes_since(count))


def test_colour_friction_frictionloss_and_solref_patch_to_a_recompile(scene):
    root, physics, count = scene
    root.find("geom", "upper").rgba = [0.2, 0.4, 0.6, 0.8]
    root.find("geom", "floor").friction = [0.7, 0.01, 0.0002]
    root.find("joint", "wrist").frictionloss = 1.3
    root.find("geom", "lower").solref = [0.04, 0.8]
    assert _patch(root, physics, count)
    _assert_equals_a_recompile(root, physics)
    np.testing.assert_array_equal(physics.named.model.geom_solref["lower"], [0.04, 0.8])


def test_a_default_class_change_reaches_the_elements_that_inherit_it(scene):
    root, physics, count = scene
    root.default.joint.frictionloss = 0.9
    assert _patch(root, physics, count)
    _assert_equals_a_recompile(root, physics)
    # elbow inherits the top-level default; shoulder's class and wrist's own value win.
    np.testing.assert_array_equal(
        physics.named.model.dof_frictionloss[["shoulder", "elbow", "wrist"]], [3, 0.9, 0.7]
    )


def test_unsetting_a_value_patches_the_inherited_one(scene):
    root, physics, count = scene
    del root.find("joint", "wrist").frictionloss
    assert _patch(root, physics, count)
    assert physics.named.model.dof_frictionloss["wrist"] == 0.2
    _assert_equals_a_recompile(root, physics)


@pytest.mark.parametrize(
    "change",
    [
        # A capsule given by fromto: its compiled size is not the attribute.
        lambda root: setattr(root.find("geom", "upper"), "size", [0.05]),
        # Adds a site: the structure changes.
        lambda root: root.worldbody.add("site", name="marker"),
        # A value MuJoCo's built-in default gives: nothing in the model says which.
        lambda root: delattr(root.find("geom", "upper"), "rgba"),
    ],
    ids=["geom_size", "structure", "unset_to_builtin_default"],
)
def test_a_change_that_cannot_be_patched_changes_nothing(scene, change):
    root, physics, count = scene
    before = _model_bytes(physics.model.ptr)
    root.find("geom", "floor").friction = [0.3, 0.01, 0.0002]
    change(root)
    changes = root.attribute_changes_since(count)
    assert changes is None or not physics.apply_attribute_changes(changes)
    assert _model_bytes(physics.model.ptr) == before


def test_a_control_range_where_none_was_set_is_not_patched(scene):
    # MuJoCo then also marks the actuator as limited (autolimits).
    root, physics, count = scene
    root.find("actuator", "shoulder").ctrlrange = None
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("actuator", "shoulder").ctrlrange = [-1, 1]
    assert not _patch(root, physics, count)


def test_joint_range_in_degrees_is_not_patched():
    # The compiler converts degrees to radians, so the value is not the field.
    root = mjcf.from_xml_string(_SCENE.replace('angle="radian"', 'angle="degree"'))
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("joint", "elbow").range = [-30, 30]
    assert not _patch(root, physics, count)


def test_attachment_frames_are_not_patched(scene):
    root, physics, _ = scene
    child = mjcf.RootElement(model="child")
    child.worldbody.add("geom", name="ball", type="sphere", size=[0.1])
    frame = root.attach(child)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    frame.pos = [0, 0, 1]
    assert not _patch(root, physics, count)


def test_an_attached_models_values_patch_through_the_parent(scene):
    root, _, _ = scene
    child = mjcf.RootElement(model="child")
    ball = child.worldbody.add("geom", name="ball", type="sphere", size=[0.1])
    root.attach(child)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    ball.rgba = [0, 1, 0, 0.5]
    assert _patch(root, physics, count)
    _assert_equals_a_recompile(root, physics)


def test_set_const_pairs_bring_derived_constants_up_to_date():
    # A camera's position feeds cam_pos0 and cam_poscom0, which mj_setConst computes.
    root = mjcf.from_xml_string(
        "<mujoco><worldbody><body name='b' pos='0 0 1'><freejoint/><geom size='0.1'/>"
        "<camera name='eye' mode='trackcom' pos='0 -1 0'/></body></worldbody></mujoco>"
    )
    assert patchable_attributes.PROVEN[("camera", "pos")] is True
    physics = mjcf.Physics.from_mjcf_model(root)
    model = copy.copy(physics.model.ptr)
    count = root.modification_count
    root.find("camera", "eye").pos = [0, -2, 0.5]
    assert _patch(root, physics, count)
    _assert_equals_a_recompile(root, physics)
    assert _model_bytes(model)["cam_pos0"] != _model_bytes(physics.model.ptr)["cam_pos0"]


# A block whose mass and inertia come from its geoms: walls of boxes, a massless lid, pegs
# of a default class whose cylinder size several geoms use, and massless helper capsules.
_BLOCK = """
<mujoco model="block">
  <default>
    <default class="peg">
      <geom type="cylinder" size="0.005 0.002" density="600"/>
    </default>
  </default>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1"/>
    <body name="block" pos="0 0 0.05">
      <freejoint/>
      <geom name="lid" type="box" size="0.02 0.01 0.001" pos="0 0 0.01" mass="0"/>
      <geom name="wall_1" type="box" size="0.02 0.001 0.01" pos="0 0.009 0"/>
      <geom name="wall_2" type="box" size="0.02 0.001 0.01" pos="0 -0.009 0"/>
      <geom name="peg_1" class="peg" pos="0.01 0 0.012"/>
      <geom name="peg_2" class="peg" pos="-0.01 0 0.012"/>
      <geom name="peg_3" class="peg" pos="0 0 0.012"/>
      <geom name="helper" type="capsule" size="0.003 0.002" pos="0 0 0.013" mass="0"/>
    </body>
  </worldbody>
</mujoco>
"""


def _everything(model: mujoco.MjModel) -> dict[str, bytes]:
    """Every MjModel array, the `stat` fields, and every MjData array after mj_forward."""
    found = {f"model.{name}": value for name, value in _model_bytes(model).items()}
    for name in ("center", "extent", "meansize", "meanmass", "meaninertia"):
        found[f"stat.{name}"] = np.asarray(getattr(model.stat, name)).tobytes()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    for name in dir(data):
        if not name.startswith("_") and isinstance(value := getattr(data, name), np.ndarray):
            found[f"data.{name}"] = value.tobytes()
    return found


@pytest.mark.patches_from_3_17
def test_a_default_class_cylinder_radius_patches_a_body_whose_inertia_comes_from_geoms():
    root = mjcf.from_xml_string(_BLOCK)
    physics = mjcf.Physics.from_mjcf_model(root)
    before = copy.copy(physics.model.ptr)
    count = root.modification_count
    root.default.find("default", "peg").geom.size = [0.0065, 0.002]
    assert _patch(root, physics, count)
    patched = _everything(physics.model.ptr)
    compiled = _everything(mjcf.Physics.from_mjcf_model(root).model.ptr)
    assert [name for name in compiled if patched[name] != compiled[name]] == []
    # The change reached what the compiler derives from sizes, not only geom_size.
    for name in ("body_mass", "body_inertia", "bvh_aabb", "geom_rbound"):
        assert _model_bytes(before)[name] != _model_bytes(physics.model.ptr)[name]
    assert before.stat.meanmass != physics.model.stat.meanmass


def test_a_geom_size_in_a_model_with_springdamper_recompiles():
    # The compiler turns springdamper into stiffness and damping with the inertia the
    # joint moves, which the size of any geom of its tree changes.
    root = mjcf.from_xml_string(
        _BLOCK.replace(
            "<freejoint/>",
            '<joint name="hinge" axis="0 1 0" springdamper="0.5 1"/>',
        )
    )
    physics = mjcf.Physics.from_mjcf_model(root)
    before = _model_bytes(physics.model.ptr)
    count = root.modification_count
    root.find("geom", "wall_1").size = [0.02, 0.002, 0.01]
    assert not _patch(root, physics, count)
    assert _model_bytes(physics.model.ptr) == before


@pytest.mark.patches_from_3_17
def test_patches_in_a_row_each_equal_a_recompile_after_other_values_were_loaded():
    root = mjcf.from_xml_string(_BLOCK)
    physics = mjcf.Physics.from_mjcf_model(root)
    snapshot = ModelSnapshot(physics.model.ptr)
    peg = root.default.find("default", "peg").geom
    for radius in (0.006, 0.0045, 0.0052):
        count = root.modification_count
        peg.size = [radius, 0.002]
        assert _patch(root, physics, count)
        compiled = mjcf.Physics.from_mjcf_model(root).model.ptr
        patched = _everything(physics.model.ptr)
        assert [
            name for name, value in _everything(compiled).items() if patched[name] != value
        ] == []
        # A value that does not patch changes between patches: the environment compiles it
        # and loads the new parameters into the same model.
        root.find("geom", "wall_1").density = 500 + 1000 * radius
        assert snapshot.load(mjcf.Physics.from_mjcf_model(root).model.ptr)


def test_a_springdamper_set_after_a_size_patch_stops_the_next_one():
    root = mjcf.from_xml_string(
        _BLOCK.replace("<freejoint/>", '<joint name="hinge" axis="0 1 0"/>')
    )
    physics = mjcf.Physics.from_mjcf_model(root)
    snapshot = ModelSnapshot(physics.model.ptr)
    peg = root.default.find("default", "peg").geom
    count = root.modification_count
    peg.size = [0.006, 0.002]
    assert _patch(root, physics, count)
    root.find("joint", "hinge").springdamper = [0.5, 1]
    assert snapshot.load(mjcf.Physics.from_mjcf_model(root).model.ptr)
    count = root.modification_count
    peg.size = [0.0045, 0.002]
    assert not _patch(root, physics, count)


def _assert_everything_equals_a_recompile(root, physics):
    patched = _everything(physics.model.ptr)
    compiled = _everything(mjcf.Physics.from_mjcf_model(root).model.ptr)
    assert [name for name in compiled if patched[name] != compiled[name]] == []


# A goal site on the world, and a site a spatial tendon with a derived rest length runs to.
_SITES = """
<mujoco model="sites">
  <worldbody>
    <site name="goal" pos="0.1 0.2 0"/>
    <site name="anchor" pos="0 0 1"/>
    <body name="slider" pos="0 0 0.2">
      <joint name="x" type="slide" axis="1 0 0"/>
      <geom size="0.05" mass="1"/>
      <site name="hook" pos="0 0 0.05"/>
    </body>
  </worldbody>
  <tendon>
    <spatial name="cord" stiffness="10">
      <site site="anchor"/>
      <site site="hook"/>
    </spatial>
  </tendon>
</mujoco>
"""


@pytest.mark.patches_from_3_17
def test_a_moved_goal_site_patches_to_a_recompile_framing_statistics_included():
    root = mjcf.from_xml_string(_SITES)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("site", "goal").pos = [1.5, -0.7, 0.3]
    assert _patch(root, physics, count)
    # The viewer's framing follows the goal, as a recompile's does.
    assert physics.model.ptr.stat.center[0] > 0.5
    _assert_everything_equals_a_recompile(root, physics)


@pytest.mark.patches_from_3_17
def test_a_moved_tendon_site_moves_the_tendons_derived_rest_length():
    root = mjcf.from_xml_string(_SITES)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("site", "hook").pos = [0.3, 0, 0.05]
    assert _patch(root, physics, count)
    # anchor (0, 0, 1) to hook (0.3, 0, 0.25): the spring rests at that length.
    np.testing.assert_allclose(physics.model.ptr.tendon_lengthspring[0], [0.8077747] * 2)
    _assert_everything_equals_a_recompile(root, physics)


@pytest.mark.patches_from_3_17
def test_a_site_quaternion_is_normalised_as_the_compiler_does():
    root = mjcf.from_xml_string(_SITES)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("site", "goal").quat = [2, 0, 0, 2]
    assert _patch(root, physics, count)
    np.testing.assert_allclose(physics.model.ptr.site_quat[0], [0.5**0.5, 0, 0, 0.5**0.5])
    _assert_everything_equals_a_recompile(root, physics)


_BODIES = """
<mujoco model="bodies">
  <worldbody>
    <light name="lamp" pos="0 0 3" dir="0 0 -1"/>
    <body name="wall" pos="0.5 0 0.1">
      <geom type="box" size="0.02 0.3 0.1"/>
      <camera name="eye" pos="0 0 0.2" xyaxes="0 1 0 0 0 1"/>
    </body>
    <body name="ball" pos="0 0 0.1">
      <freejoint/>
      <geom size="0.05"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.patches_from_3_17
def test_a_welded_bodys_pose_and_a_lights_direction_patch_to_a_recompile():
    root = mjcf.from_xml_string(_BODIES)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    wall = root.find("body", "wall")
    wall.pos = [0.7, -0.2, 0.1]
    wall.quat = [1, 0, 0, 1]
    root.find("light", "lamp").dir = [0, 1, -1]
    assert _patch(root, physics, count)
    np.testing.assert_allclose(physics.model.ptr.light_dir[0], [0, 0.5**0.5, -(0.5**0.5)])
    _assert_everything_equals_a_recompile(root, physics)


@pytest.mark.patches_from_3_17
def test_unit_quaternions_and_directions_drawn_at_random_patch_to_a_recompiles_bits():
    # A drawn unit vector's norm is 1 give or take an ulp; the compiler keeps such a
    # vector as given (dividing it by its norm moves one ulp in about a quarter of draws).
    root = mjcf.from_xml_string(_BODIES)
    physics = mjcf.Physics.from_mjcf_model(root)
    wall, lamp = root.find("body", "wall"), root.find("light", "lamp")
    rng = np.random.default_rng(7)
    for _ in range(40):
        count = root.modification_count
        quat, direction = rng.normal(size=4), rng.normal(size=3)
        wall.quat = quat / np.linalg.norm(quat)
        lamp.dir = direction / np.linalg.norm(direction)
        assert _patch(root, physics, count)
        _assert_everything_equals_a_recompile(root, physics)


@pytest.mark.parametrize(
    "change",
    [
        # A free body's qpos0 is its pose, which only the compiler sets.
        lambda root: setattr(root.find("body", "ball"), "pos", [0.2, 0, 0.1]),
        # A quaternion beside xyaxes: the compiler refuses the model.
        lambda root: setattr(root.find("camera", "eye"), "quat", [1, 0, 0, 0]),
    ],
    ids=["free_body_pos", "second_orientation"],
)
def test_a_pose_only_a_compile_resolves_is_not_patched(change):
    root = mjcf.from_xml_string(_BODIES)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    change(root)
    assert not _patch(root, physics, count)


@pytest.mark.patches_from_3_17
def test_a_moving_body_in_a_model_with_springdamper_recompiles_and_a_welded_one_patches():
    # springdamper's stiffness and damping come from the inertia of the joint's tree.
    root = mjcf.from_xml_string(_BODIES)
    arm = root.worldbody.add("body", name="arm", pos=[0, 0.5, 0.5])
    arm.add("joint", name="hinge", axis=[0, 1, 0], springdamper=[0.5, 1])
    link = arm.add("body", name="link", pos=[0.2, 0, 0])
    link.add("geom", size=[0.05])
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    link.pos = [0.3, 0, 0]
    assert not _patch(root, physics, count)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("body", "wall").pos = [0.6, 0, 0.1]
    assert _patch(root, physics, count)
    _assert_everything_equals_a_recompile(root, physics)


def test_a_default_class_change_reaches_an_element_that_took_the_class_since():
    root = mjcf.from_xml_string(_SCENE)
    compiled = CompiledModel()
    compiled.update(root)
    stiff = root.default.find("default", "stiff").joint
    stiff.frictionloss = 4.0
    assert compiled.update(root) is ModelUpdate.PATCHED
    # A class is not patched: the recompile has the same structure and is loaded in place.
    root.find("joint", "elbow").dclass = "stiff"
    assert compiled.update(root) is ModelUpdate.LOADED
    stiff.frictionloss = 5.0
    assert compiled.update(root) is ModelUpdate.PATCHED
    np.testing.assert_array_equal(
        compiled.physics.named.model.dof_frictionloss[["shoulder", "elbow", "wrist"]], [5, 5, 0.7]
    )
    _assert_equals_a_recompile(root, compiled.physics)
