"""Sub-models (`<asset><model file>`) reach the compile with the files they name, as in MuJoCo."""

import mujoco
import numpy as np
import pytest
from mjcf_test_files import checker_png, tetrahedron_stl

import mjcf

_SCENE = """
<mujoco model="scene">
  <asset>
    <model name="robot" file="robot/robot.xml"/>
  </asset>
  <worldbody>
    <body name="mount" pos="0 0 1">
      <attach model="robot" body="base" prefix="r_"/>
    </body>
  </worldbody>
</mujoco>
"""

_ROBOT = """
<mujoco model="robot">
  <compiler meshdir="meshes"/>
  <asset>
    <mesh name="pyramid" file="pyramid.stl"/>
  </asset>
  <worldbody>
    <body name="base">
      <geom type="mesh" mesh="pyramid"/>
    </body>
  </worldbody>
</mujoco>
"""


def _pyramid_stl() -> bytes:
    """A binary STL square pyramid: 5 distinct vertices, 6 outward-facing triangles."""
    corners = np.array(
        [[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0], [0, 0.1, 0], [0.05, 0.05, 0.1]], np.float32
    )
    faces = [(0, 2, 1), (0, 3, 2), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)]
    record = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("flags", "<u2")])
    triangles = np.zeros(len(faces), record)
    triangles["vertices"] = corners[faces]
    return bytes(80) + np.uint32(len(faces)).tobytes() + triangles.tobytes()


@pytest.fixture
def scene_path(tmp_path):
    """A scene whose sub-model lives in 'robot/' and reads its mesh from 'robot/meshes/'."""
    (tmp_path / "robot" / "meshes").mkdir(parents=True)
    (tmp_path / "robot" / "meshes" / "pyramid.stl").write_bytes(_pyramid_stl())
    (tmp_path / "robot" / "robot.xml").write_text(_ROBOT)
    (tmp_path / "scene.xml").write_text(_SCENE)
    return tmp_path / "scene.xml"


def _compile(root: mjcf.RootElement) -> mujoco.MjModel:
    return mjcf.Physics.from_mjcf_model(root).model


def test_sub_model_mesh_compiles_as_mujoco_reads_it_from_the_files(scene_path):
    expected = mujoco.MjModel.from_xml_path(str(scene_path))
    actual = _compile(mjcf.from_path(str(scene_path)))
    assert expected.mesh_vertnum.tolist() == [5]
    assert actual.mesh_vertnum.tolist() == expected.mesh_vertnum.tolist()
    assert actual.mesh("r_pyramid").id == expected.mesh("r_pyramid").id
    assert actual.body("r_base").parentid == actual.body("mount").id


def test_sub_model_files_can_come_from_an_assets_dict(scene_path):
    base = scene_path.parent
    assets = {
        name: (base / name).read_bytes() for name in ("robot/robot.xml", "robot/meshes/pyramid.stl")
    }
    root = mjcf.from_xml_string(_SCENE, model_dir="/nonexistent", assets=assets)
    assert _compile(root).mesh_vertnum.tolist() == [5]


def test_export_with_assets_writes_a_sub_model_that_compiles_from_the_files(scene_path, tmp_path):
    out_dir = tmp_path / "exported"
    mjcf.export_with_assets(mjcf.from_path(str(scene_path)), str(out_dir), "scene.xml")
    model = mujoco.MjModel.from_xml_path(str(out_dir / "scene.xml"))
    assert model.mesh_vertnum.tolist() == [5]
    assert not any(path.is_dir() for path in out_dir.iterdir())


def test_unnamed_sub_model_mesh_keeps_the_name_mujoco_gives_it_after_its_file(scene_path):
    robot = scene_path.parent / "robot" / "robot.xml"
    robot.write_text(_ROBOT.replace('name="pyramid" ', ""))
    expected = mujoco.MjModel.from_xml_path(str(scene_path))
    actual = _compile(mjcf.from_path(str(scene_path)))
    assert expected.mesh(0).name == "r_pyramid"
    assert actual.mesh(0).name == expected.mesh(0).name


def test_nested_sub_model_reads_its_files_from_its_own_directory(scene_path):
    hand_dir = scene_path.parent / "robot" / "hand"
    (hand_dir / "assets").mkdir(parents=True)
    (hand_dir / "assets" / "finger.stl").write_bytes(tetrahedron_stl())
    (hand_dir / "assets" / "skin.png").write_bytes(checker_png())
    (hand_dir / "hand.xml").write_text(
        """
        <mujoco model="hand">
          <compiler assetdir="assets"/>
          <asset>
            <mesh name="finger" file="finger.stl"/>
            <texture name="skin" type="2d" file="skin.png"/>
            <material name="skin" texture="skin"/>
          </asset>
          <worldbody>
            <body name="palm"><geom type="mesh" mesh="finger" material="skin"/></body>
          </worldbody>
        </mujoco>
        """
    )
    robot = _ROBOT.replace("</asset>", '<model name="hand" file="hand/hand.xml"/></asset>').replace(
        "</body>", '<attach model="hand" body="palm" prefix="h_"/></body>'
    )
    (scene_path.parent / "robot" / "robot.xml").write_text(robot)
    expected = mujoco.MjModel.from_xml_path(str(scene_path))
    actual = _compile(mjcf.from_path(str(scene_path)))
    assert expected.mesh_vertnum.tolist() == [5, 4]
    assert actual.mesh_vertnum.tolist() == expected.mesh_vertnum.tolist()
    assert (actual.ntex, actual.tex_width.tolist()) == (1, [8])
    assert actual.tex_width.tolist() == expected.tex_width.tolist()


def test_sub_model_includes_are_read_from_its_own_directory(scene_path):
    robot_dir = scene_path.parent / "robot"
    (robot_dir / "parts.xml").write_text(
        '<mujoco><asset><mesh name="pyramid" file="pyramid.stl"/></asset></mujoco>'
    )
    robot = _ROBOT.replace(
        '<asset>\n    <mesh name="pyramid" file="pyramid.stl"/>\n  </asset>',
        '<include file="parts.xml"/>',
    )
    assert "parts.xml" in robot
    (robot_dir / "robot.xml").write_text(robot)
    expected = mujoco.MjModel.from_xml_path(str(scene_path))
    actual = _compile(mjcf.from_path(str(scene_path)))
    assert actual.mesh_vertnum.tolist() == expected.mesh_vertnum.tolist() == [5]


def test_sub_model_is_read_from_the_model_directory_whatever_assetdir_says(scene_path):
    scene_path.write_text(_SCENE.replace("<asset>", '<compiler assetdir="robot"/><asset>', 1))
    expected = mujoco.MjModel.from_xml_path(str(scene_path))
    actual = _compile(mjcf.from_path(str(scene_path)))
    assert actual.mesh_vertnum.tolist() == expected.mesh_vertnum.tolist() == [5]


def test_missing_sub_model_file_names_the_file_and_the_element(scene_path):
    (scene_path.parent / "robot" / "robot.xml").unlink()
    with pytest.raises(
        FileNotFoundError, match=r"<model name='robot'> attribute 'file'.*'robot/robot.xml'"
    ):
        mjcf.from_path(str(scene_path))


def test_missing_file_of_a_sub_model_names_it_and_the_elements_leading_to_it(scene_path):
    (scene_path.parent / "robot" / "meshes" / "pyramid.stl").unlink()
    with pytest.raises(FileNotFoundError) as error:
        mjcf.from_path(str(scene_path))
    message = str(error.value)
    assert message.startswith(
        "<model name='robot'> attribute 'file': in sub-model 'robot/robot.xml': "
        "<mesh name='pyramid'> attribute 'file': cannot read file 'pyramid.stl'"
    )
    assert str(scene_path.parent / "robot" / "meshes" / "pyramid.stl") in message


def test_malformed_sub_model_is_an_error_naming_it(scene_path):
    (scene_path.parent / "robot" / "robot.xml").write_text("<mujoco><worldbody></mujoco>")
    with pytest.raises(ValueError, match=r"in sub-model 'robot/robot.xml': invalid MJCF XML"):
        mjcf.from_path(str(scene_path))


def test_sub_models_that_name_each_other_are_an_error_not_endless(tmp_path):
    # MuJoCo itself recurses until its stack overflows on these files.
    (tmp_path / "a.xml").write_text(
        '<mujoco><asset><model name="b" file="b.xml"/></asset></mujoco>'
    )
    (tmp_path / "b.xml").write_text(
        '<mujoco><asset><model name="a" file="a.xml"/></asset></mujoco>'
    )
    with pytest.raises(
        ValueError, match=r"in sub-model 'a.xml': .*'b.xml' is a sub-model of itself"
    ):
        mjcf.from_path(str(tmp_path / "a.xml"))


def test_unnamed_sub_model_is_named_after_the_model_in_its_file_as_in_mujoco(scene_path):
    scene_path.write_text(_SCENE.replace('name="robot" ', ""))
    expected = mujoco.MjModel.from_xml_path(str(scene_path))  # attaches model="robot"
    actual = _compile(mjcf.from_path(str(scene_path)))
    assert actual.body("r_base").parentid == actual.body("mount").id
    assert actual.nbody == expected.nbody == 3


def test_unnamed_sub_model_of_a_file_without_a_model_name_takes_mujocos_default(scene_path):
    robot = scene_path.parent / "robot" / "robot.xml"
    robot.write_text(_ROBOT.replace(' model="robot"', ""))
    default_name = mujoco.MjSpec().modelname
    scene_path.write_text(
        _SCENE.replace('name="robot" ', "").replace('model="robot"', f'model="{default_name}"')
    )
    expected = mujoco.MjModel.from_xml_path(str(scene_path))
    actual = _compile(mjcf.from_path(str(scene_path)))
    assert actual.body("r_base").parentid == actual.body("mount").id
    assert actual.nbody == expected.nbody == 3


@pytest.mark.parametrize("named", [True, False])
def test_a_scene_that_attaches_a_sub_model_can_itself_be_attached_twice(scene_path, named):
    if not named:
        scene_path.write_text(_SCENE.replace('name="robot" ', ""))
    world = mjcf.RootElement(model="world")
    world.attach(mjcf.from_path(str(scene_path)))
    world.attach(mjcf.from_path(str(scene_path)))
    model = _compile(world)
    # Each copy's attached robot is named inside its own scene's scope, on its own mount.
    for scope in ("scene/", "scene_1/"):
        assert model.body(f"{scope}r_base").parentid == model.body(f"{scope}mount").id
    assert model.mesh_vertnum.tolist() == [5, 5]
