"""mjcf.patching.patch_proof proves value-only attributes and refuses those the compiler
derives; manipulation.patch_proof runs it on the task suite's models."""

import copy
import itertools
import math
import os
import subprocess
import sys
from pathlib import Path

import mujoco
import pytest

import mjcf
from manipulation import patch_proof as suite_proof
from mjcf.patching import model_comparison, patch_proof

_BALL = "<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body></worldbody></mujoco>"


@pytest.mark.patches_from_3_17
def test_colour_size_and_poses_are_proven_and_a_geoms_position_is_refused_with_its_fields():
    pairs = {("geom", "rgba"), ("geom", "size"), ("geom", "pos"), ("body", "pos"), ("site", "pos")}
    proven, refused = patch_proof._verdicts(
        patch_proof.prove(
            pairs, itertools.chain(suite_proof.task_models(), patch_proof.scene_models())
        )
    )
    # A size moves the body's inertia and the model's statistics, a body's or a site's
    # position the derived constants and statistics: mj_setConst must follow.
    assert proven == {
        ("geom", "rgba"): False,
        ("geom", "size"): True,
        ("body", "pos"): True,
        ("site", "pos"): True,
    }
    # A geom's position moves its body's inertial frame, which only the compiler computes.
    assert "body_ipos" in refused["geom", "pos"]


def test_candidates_are_float_attributes_of_compiled_objects():
    candidates = patch_proof._candidates()
    assert {("geom", "rgba"), ("joint", "damping"), ("motor", "ctrlrange")} <= candidates
    # Names, references and keywords are never candidates.
    assert not {("geom", "name"), ("geom", "material"), ("geom", "type")} & candidates


def test_data_arrays_that_differ_between_copies_of_one_model_do_not_refuse_a_pair(monkeypatch):
    # On mujoco 3.3.0 mj_forward leaves the island arrays unwritten: they hold scratch with
    # addresses in it, which two forwards may or may not leave alike. An array that differs
    # between forwards of copies of one compiled model says nothing about a patch; one that
    # differs with the model's values does.
    model = mjcf.Physics.from_xml_string(_BALL).model.ptr
    forwards = itertools.count()

    def data_arrays(model, data):
        # The scratch repeats for two forwards, then changes.
        scratch = next(forwards) // 2
        return {"dof_island": bytes([scratch]), "geom_xpos": model.geom_rgba.tobytes()}

    monkeypatch.setattr(model_comparison, "data_arrays", data_arrays)
    assert model_comparison.scratch_arrays(model) == {"dof_island"}
    recoloured = copy.copy(model)
    recoloured.geom_rgba[0] = [0, 1, 0, 1]
    assert model_comparison.differences(recoloured, model) == ["geom_rgba", "data.geom_xpos"]
    next(forwards)  # now the patched and the compiled model's forwards leave different scratch
    assert model_comparison.differences(copy.copy(model), model) == []


def test_on_an_unproven_release_the_command_caches_a_proof_that_the_next_process_uses(tmp_path):
    # The checked-in table claims another release, so the installed one is unproven; the
    # proof runs on one scene for two pairs (the full corpus takes half a minute).
    fake_release = (
        "import mjcf\n"
        "from mjcf.patching import patchable_attributes\n"
        "patchable_attributes.MUJOCO_VERSION = '0.0.0'\n"
    )
    prove = fake_release + (
        "from mjcf.patching import patch_proof\n"
        "patch_proof._candidates = lambda: {('geom', 'rgba'), ('geom', 'pos')}\n"
        "scene = patch_proof._scenes()['primitives_radians.xml']\n"
        "patch_proof._scenes = lambda: {'scene': scene}\n"
        "raise SystemExit(patch_proof.main(corpus=(), argv=[]))\n"
    )
    use = fake_release + (
        "from mjcf.patching import patch_table\n"
        'root = mjcf.from_xml_string("<mujoco><worldbody><body><freejoint/>'
        "<geom name='ball' size='0.1'/></body></worldbody></mujoco>\")\n"
        "physics = mjcf.Physics.from_mjcf_model(root)\n"
        "ball = root.find('geom', 'ball')\n"
        "count = root.modification_count\n"
        "ball.rgba = [0, 1, 0, 1]\n"
        "colour = physics.apply_attribute_changes(root.attribute_changes_since(count))\n"
        "count = root.modification_count\n"
        "ball.pos = [0, 0, 1]\n"
        "position = physics.apply_attribute_changes(root.attribute_changes_since(count))\n"
        "print(colour, position, sorted(patch_table.current().proven))\n"
    )
    env = dict(os.environ, XDG_CACHE_HOME=str(tmp_path))
    proving = subprocess.run(
        [sys.executable, "-c", prove], env=env, capture_output=True, text=True, timeout=300
    )
    assert proving.returncode == 0, proving.stderr
    path = tmp_path / "mujoco-composer" / "patch_proof" / f"mujoco-{mujoco.__version__}.json"
    assert f"wrote {path}" in proving.stdout
    assert "1 pairs patch, 1 recompile" in proving.stdout
    # A RuntimeWarning (no proof, or an unreadable one) would fail the second process.
    using = subprocess.run(
        [sys.executable, "-W", "error::RuntimeWarning", "-c", use],
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert using.returncode == 0, using.stderr
    assert using.stdout.split("\n")[0] == "True False [('geom', 'rgba')]"


_SCENE_FILES = {"blocks_geom_sizes.xml", "creature_degrees.xml", "primitives_radians.xml"}


def test_the_proof_reads_its_three_scenes_from_package_data_and_each_compiles():
    scenes = patch_proof._scenes()
    assert set(scenes) == _SCENE_FILES
    models = {name: mujoco.MjModel.from_xml_string(text) for name, text in scenes.items()}
    # What each scene is there for: degree angles, tendons, geom sizes of a class.
    assert models["creature_degrees.xml"].joint("knee").range[1] == pytest.approx(math.radians(70))
    assert models["primitives_radians.xml"].ntendon == 2
    assert models["blocks_geom_sizes.xml"].geom("knob_1").size[:2] == pytest.approx([0.006, 0.003])


def test_every_scene_file_is_package_data_so_that_a_wheel_ships_it():
    tomllib = pytest.importorskip("tomllib")  # Python 3.11 and later
    root = Path(mjcf.__file__).parent.parent
    with open(root / "pyproject.toml", "rb") as file:
        package_data = tomllib.load(file)["tool"]["setuptools"]["package-data"]["mjcf.patching"]
    shipped = {
        path.name for pattern in package_data for path in (root / "mjcf" / "patching").glob(pattern)
    }
    assert shipped == _SCENE_FILES


def test_the_proof_changes_the_models_it_is_given_besides_its_scenes(monkeypatch, capsys):
    monkeypatch.setattr(patch_proof, "_candidates", lambda: {("geom", "rgba")})
    monkeypatch.setattr(patch_proof, "_scenes", lambda: {})
    ball = ("ball", mjcf.from_xml_string(_BALL))
    with pytest.raises(SystemExit):  # the proof exits 1: one pair is no table
        raise SystemExit(patch_proof.main(corpus=[ball], argv=[]))
    printed = capsys.readouterr()
    assert "ball: 1 changes of 1 pairs" in printed.err
    assert "1 pairs patch, 0 recompile" in printed.out


def test_the_library_module_run_as_a_command_names_the_suite_command():
    result = subprocess.run(
        [sys.executable, "-m", "mjcf.patching.patch_proof"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 1
    assert "python -m manipulation.patch_proof" in result.stderr
