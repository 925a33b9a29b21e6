"""Round trips of multi-file MJCF models through the object model, compared with MuJoCo."""

import os

import mujoco
import numpy as np
import pytest
from mjcf_test_files import checker_png, tetrahedron_stl

import mjcf

_MAIN = """
<mujoco model="rig">
  <compiler meshdir="meshes" texturedir="textures" angle="radian"/>
  <option timestep="0.004" integrator="implicitfast"/>
  <include file="parts/defaults.xml"/>
  <asset>
    <mesh name="tetra" file="tetra.stl" scale="2 2 2"/>
    <texture name="checks" type="2d" file="checks.png"/>
    <material name="checked" texture="checks" texrepeat="2 2"/>
  </asset>
  <worldbody>
    <light name="sun" pos="0 0 3" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="2 2 0.1" material="checked"/>
    <include file="parts/arm.xml"/>
  </worldbody>
  <tendon>
    <spatial name="rope" width="0.005">
      <site site="anchor"/>
      <site site="tip"/>
    </spatial>
    <fixed name="coupling">
      <joint joint="shoulder" coef="1"/>
      <joint joint="elbow" coef="-0.5"/>
    </fixed>
  </tendon>
  <equality>
    <joint name="lock" joint1="shoulder" joint2="elbow" polycoef="0 1 0 0 0"/>
    <connect name="pin" body1="hand" anchor="0 0 0.1"/>
  </equality>
  <actuator>
    <motor name="shoulder_motor" joint="shoulder" gear="10" class="strong"/>
    <position name="elbow_servo" joint="elbow" kp="5"/>
  </actuator>
  <sensor>
    <jointpos name="shoulder_angle" joint="shoulder"/>
    <tendonpos name="rope_length" tendon="rope"/>
    <framepos name="tip_pos" objtype="site" objname="tip"/>
    <touch name="palm_touch" site="tip"/>
  </sensor>
  <keyframe>
    <key name="bent" qpos="0.3 -0.6 0.2" time="1.5"/>
  </keyframe>
</mujoco>
"""

_DEFAULTS = """
<mujoco>
  <default>
    <joint damping="0.5" armature="0.01"/>
    <geom rgba="0.8 0.6 0.4 1" friction="0.7"/>
    <default class="strong">
      <motor ctrlrange="-2 2"/>
    </default>
    <default class="heavy">
      <geom density="5000"/>
    </default>
  </default>
</mujoco>
"""

_ARM = """
<mujoco>
  <site name="anchor" pos="0 0 1.5"/>
  <body name="upper" pos="0 0 1">
    <joint name="shoulder" axis="0 1 0" range="-1 1"/>
    <geom name="upper_geom" type="capsule" fromto="0 0 0 0 0 -0.3" size="0.04" class="heavy"/>
    <body name="lower" pos="0 0 -0.3">
      <joint name="elbow" axis="0 1 0"/>
      <geom name="lower_geom" type="mesh" mesh="tetra"/>
      <body name="hand" pos="0 0 -0.2">
        <joint name="wrist" type="slide" axis="0 0 1"/>
        <geom name="palm" type="box" size="0.03 0.03 0.01"/>
        <site name="tip" pos="0 0 -0.05"/>
      </body>
    </body>
  </body>
</mujoco>
"""


@pytest.fixture
def rig_path(tmp_path):
    files = {
        "rig.xml": _MAIN,
        "parts/defaults.xml": _DEFAULTS,
        "parts/arm.xml": _ARM,
        "meshes/tetra.stl": tetrahedron_stl(),
        "textures/checks.png": checker_png(),
    }
    for name, contents in files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(contents.encode() if isinstance(contents, str) else contents)
    return str(tmp_path / "rig.xml")


def _compile(root):
    return mujoco.MjModel.from_xml_string(root.to_xml_string(), root.get_assets())


_COUNTS = (
    "nbody",
    "njnt",
    "ngeom",
    "nsite",
    "nmesh",
    "ntex",
    "nmat",
    "ntendon",
    "neq",
    "nu",
    "nsensor",
    "nkey",
    "nlight",
    "nq",
    "nsensordata",
)
_FIELDS = (
    "geom_size",
    "geom_rgba",
    "geom_friction",
    "body_mass",
    "body_inertia",
    "jnt_range",
    "dof_damping",
    "dof_armature",
    "actuator_ctrlrange",
    "actuator_gear",
    "mesh_vert",
    "tex_data",
    "key_qpos",
    "key_time",
    "eq_data",
    "tendon_width",
    "wrap_prm",
    "mat_texrepeat",
    "opt.timestep",
)


def _field(model, name):
    if name.startswith("opt."):
        return getattr(model.opt, name[4:])
    return getattr(model, name)


def test_multi_file_model_compiles_like_mujoco_compiles_the_files(rig_path):
    expected = mujoco.MjModel.from_xml_path(rig_path)
    actual = _compile(mjcf.from_path(rig_path))
    for count in _COUNTS:
        assert getattr(actual, count) == getattr(expected, count), count
    for field in _FIELDS:
        np.testing.assert_allclose(_field(actual, field), _field(expected, field), err_msg=field)
    for obj in ("body", "joint", "geom", "site", "tendon", "actuator", "sensor"):
        count = getattr(
            expected,
            {
                "body": "nbody",
                "joint": "njnt",
                "geom": "ngeom",
                "site": "nsite",
                "tendon": "ntendon",
                "actuator": "nu",
                "sensor": "nsensor",
            }[obj],
        )
        for index in range(count):
            name = getattr(expected, obj)(index).name
            if name:
                assert getattr(actual, obj)(name).id == index


def test_includes_are_expanded_in_place(rig_path):
    root = mjcf.from_path(rig_path)
    assert [b.name for b in root.worldbody.body] == ["upper"]
    assert root.worldbody.all_children()[0].tag == "light"
    assert root.default.default["strong"].motor.ctrlrange.tolist() == [-2, 2]


def test_file_assets_are_read_through_meshdir_and_texturedir(rig_path):
    root = mjcf.from_path(rig_path)
    mesh = root.find("mesh", "tetra")
    assert mesh.file.contents == tetrahedron_stl()
    assert mesh.file.extension == ".stl"
    assert root.find("texture", "checks").file.contents == checker_png()
    assets = root.get_assets()
    assert assets[mesh.file.get_vfs_filename()] == tetrahedron_stl()


def test_files_can_come_from_an_assets_dict(rig_path):
    with open(rig_path) as handle:
        xml = handle.read()
    base = os.path.dirname(rig_path)
    assets = {}
    for name in ("parts/defaults.xml", "parts/arm.xml", "meshes/tetra.stl", "textures/checks.png"):
        with open(os.path.join(base, name), "rb") as handle:
            assets[name] = handle.read()
    root = mjcf.from_xml_string(xml, assets=assets)
    assert root.find("mesh", "tetra").file.contents == tetrahedron_stl()
    assert _compile(root).nmesh == 1


def test_written_model_parses_back_to_the_same_xml(rig_path):
    root = mjcf.from_path(rig_path)
    xml = root.to_xml_string()
    again = mjcf.from_xml_string(xml, escape_separators=True, assets=root.get_assets())
    assert _compile(again).nbody == _compile(root).nbody
    assert set(again.get_assets()) == set(root.get_assets())


def test_parsed_model_can_be_attached_with_its_assets(rig_path):
    scene = mjcf.RootElement(model="scene")
    scene.worldbody.add("geom", name="ground", type="plane", size=[3, 3, 0.1])
    rig = mjcf.from_path(rig_path)
    rig.keyframe.key["bent"].remove()
    scene.attach(rig)
    model = _compile(scene)
    assert model.mesh("rig/tetra").id >= 0
    assert model.texture("rig/checks").id >= 0
    assert model.geom("rig/floor").matid == model.material("rig/checked").id
    assert model.tendon("rig/rope").id >= 0
    assert model.equality("rig/pin").id >= 0


def test_model_saved_by_mujoco_round_trips(rig_path):
    spec = mujoco.MjSpec.from_file(rig_path)
    spec.compile()
    saved = spec.to_xml()
    assets = mjcf.from_path(rig_path).get_assets()
    files = {"tetra.stl": tetrahedron_stl(), "checks.png": checker_png()}
    del assets
    root = mjcf.from_xml_string(saved, assets=files)
    expected = mujoco.MjModel.from_xml_path(rig_path)
    actual = _compile(root)
    for count in _COUNTS:
        assert getattr(actual, count) == getattr(expected, count), count
    np.testing.assert_allclose(actual.body_mass, expected.body_mass)


def test_export_with_assets_writes_a_loadable_directory(rig_path, tmp_path):
    root = mjcf.from_path(rig_path)
    out_dir = tmp_path / "exported"
    mjcf.export_with_assets(root, str(out_dir))
    written = sorted(os.listdir(out_dir))
    assert "rig.xml" in written
    assert set(root.get_assets()) <= set(written)
    model = mujoco.MjModel.from_xml_path(str(out_dir / "rig.xml"))
    assert model.nmesh == 1 and model.ntex == 1


def test_export_with_assets_as_zip_holds_model_folder(rig_path, tmp_path):
    import zipfile

    root = mjcf.from_path(rig_path)
    mjcf.export_with_assets_as_zip(root, str(tmp_path), model_name="bundle")
    with zipfile.ZipFile(tmp_path / "bundle.zip") as archive:
        names = archive.namelist()
        xml = archive.read("bundle/bundle.xml").decode()
        files = {n.split("/", 1)[1]: archive.read(n) for n in names if not n.endswith(".xml")}
    assert mujoco.MjModel.from_xml_string(xml, files).nmesh == 1


def test_to_spec_gives_an_equivalent_mjspec(rig_path):
    root = mjcf.from_path(rig_path)
    spec = root.to_spec()
    assert isinstance(spec, mujoco.MjSpec)
    model = spec.compile()
    assert model.nbody == mujoco.MjModel.from_xml_path(rig_path).nbody
    assert model.joint("shoulder").id >= 0


def test_get_assets_follows_file_changes(rig_path):
    root = mjcf.from_path(rig_path)
    mesh = root.find("mesh", "tetra")
    before = set(root.get_assets())
    mesh.file = mjcf.Asset(tetrahedron_stl(scale=0.3), ".stl", "bigger")
    after = set(root.get_assets())
    assert after != before
    assert mesh.file.get_vfs_filename() in after
    assert _compile(root).mesh_vertnum[0] == 4
