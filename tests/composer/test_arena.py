"""composer.Arena: default scene settings, free and offset attachment."""

import numpy as np
import pytest
from composer_scene import Box

import composer
import mjcf


class Planar(Box):
    """A box that slides in x and y instead of moving freely."""

    def create_root_joints(self, attachment_frame):
        attachment_frame.add("joint", name="x", type="slide", axis=[1, 0, 0])
        attachment_frame.add("joint", name="y", type="slide", axis=[0, 1, 0])


def test_arena_compiles_with_its_name_and_a_2ms_timestep():
    arena = composer.Arena(name="stage")
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    assert arena.mjcf_model.model == "stage"
    assert physics.timestep() == 0.002


class Stage(composer.Arena):
    """The mistake a new user makes: an arena whose _build forgets super()._build()."""

    def _build(self, name="stage"):
        self.mjcf_model.worldbody.add("geom", type="plane", size=[1, 1, 0.1])


def test_an_arena_whose_build_skips_super_build_names_the_mistake_and_the_fix():
    with pytest.raises(AttributeError) as raised:
        Stage()
    assert str(raised.value) == (
        "Stage has no MJCF model ('_mjcf_root'): Stage._build did not call super()._build(). "
        "Start Stage._build with super()._build(name=...), which creates the arena's model "
        "and its shared settings, then add to self.mjcf_model"
    )


def test_an_arena_subclass_of_a_broken_one_is_named_by_the_build_that_skips_super():
    class Floored(Stage):
        pass

    with pytest.raises(
        AttributeError,
        match=r"^Floored has no MJCF model \('_mjcf_root'\): "
        r"Stage\._build did not call super\(\)\._build\(\)\. ",
    ):
        Floored()


def test_arena_model_is_named_base_by_default():
    assert composer.Arena().mjcf_model.model == "base"


def test_add_free_entity_gives_the_entity_six_degrees_of_freedom():
    arena, box = composer.Arena(), Box()
    frame = arena.add_free_entity(box)
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    assert frame is box.root_body
    assert physics.model.nq == 7
    assert physics.model.nv == 6


def test_add_free_entity_uses_the_entitys_own_root_joints():
    arena, box = composer.Arena(), Planar()
    arena.add_free_entity(box)
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    assert physics.model.nq == 2
    assert mjcf.get_freejoint(box.root_body) is None


def test_attach_offset_with_position_places_the_entity():
    arena, box = composer.Arena(), Box()
    arena.attach_offset(box, [0.1, 0.2, 0.3])
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    np.testing.assert_allclose(physics.bind(box.geom).xpos, [0.1, 0.2, 0.3])


def test_attach_offset_with_position_and_quaternion_orients_the_entity():
    arena, box = composer.Arena(), Box()
    quaternion = [np.cos(0.25), 0, 0, np.sin(0.25)]  # 0.5 rad about z
    arena.attach_offset(box, [0, 0, 1, *quaternion])
    physics = mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    c, s = np.cos(0.5), np.sin(0.5)
    np.testing.assert_allclose(physics.bind(box.geom).xmat, [c, -s, 0, s, c, 0, 0, 0, 1])


def test_attach_offset_with_wrong_number_of_values_is_an_error():
    with pytest.raises(ValueError, match="3 values.*7.*got 4"):
        composer.Arena().attach_offset(Box(), [0, 0, 0, 1])


def _write_png(path):
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    Image.new("RGB", (4, 4), (0, 128, 0)).save(path)


# An arena that names its texture as dm_control's locomotion arenas do: relative to the
# folder of dm_control's own composer package.
_TEXTURED_ARENA = """
import sys
sys.path.insert(0, {packages!r})
{redirect}
import composer, mjcf
arena = composer.Arena()
arena.mjcf_model.compiler.texturedir = "../assets"
try:
    arena.mjcf_model.asset.add("texture", name="grass", type="2d", file="grass.png")
    mjcf.Physics.from_mjcf_model(arena.mjcf_model)
    print("compiled")
except FileNotFoundError as error:
    print("missing", error)
"""


@pytest.mark.parametrize("redirect", [True, False])
def test_arena_texture_paths_resolve_against_dm_controls_composer_folder_under_redirect(
    tmp_path, redirect
):
    import subprocess
    import sys

    packages = tmp_path / "site"
    (packages / "dm_control" / "composer").mkdir(parents=True)
    (packages / "dm_control" / "__init__.py").write_text("")
    _write_png(packages / "dm_control" / "assets" / "grass.png")
    elsewhere = tmp_path / "work"
    elsewhere.mkdir()
    code = _TEXTURED_ARENA.format(
        packages=str(packages),
        redirect="from composer import dm_control_compat; dm_control_compat.install()"
        if redirect
        else "",
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=elsewhere, timeout=120
    )
    assert result.returncode == 0, result.stderr
    if redirect:
        assert result.stdout.strip() == "compiled"
    else:
        # Without the redirect the arena is this project's own: paths are relative to the
        # working directory, where there is no ../assets/grass.png.
        assert result.stdout.startswith("missing ")
        assert "grass.png" in result.stdout


def test_arena_from_xml_path_keeps_the_file_settings_and_takes_the_name(tmp_path):
    path = tmp_path / "stage.xml"
    path.write_text("<mujoco model='file_model'><option timestep='0.005'/></mujoco>")
    arena = composer.Arena(name="renamed", xml_path=str(path))
    assert arena.mjcf_model.model == "renamed"
    assert arena.mjcf_model.option.timestep == 0.005
    assert composer.Arena(xml_path=str(path)).mjcf_model.model == "file_model"
