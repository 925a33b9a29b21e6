"""mjcf.patching.patch_table: which proof applies on the installed MuJoCo, and never
silently none."""

import json
import warnings

import mujoco
import pytest

import mjcf
from mjcf.patching import model_patch, patch_table, patchable_attributes

_SCENE = """
<mujoco>
  <worldbody>
    <body name="ball" pos="0 0 1">
      <freejoint/>
      <geom name="ball" type="sphere" size="0.1" rgba="1 0 0 1"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture
def unproven_release(monkeypatch, tmp_path):
    """The checked-in table claims another release, and the user's cache directory is a
    fresh temporary folder; returns that folder."""
    monkeypatch.setattr(patchable_attributes, "MUJOCO_VERSION", "0.0.0")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    return tmp_path


def _patches_a_colour() -> bool:
    root = mjcf.from_xml_string(_SCENE)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("geom", "ball").rgba = [0, 1, 0, 1]
    return physics.apply_attribute_changes(root.attribute_changes_since(count))


def _cache_file(folder):
    return folder / "mujoco-composer" / "patch_proof" / f"mujoco-{mujoco.__version__}.json"


def test_the_cache_file_is_one_per_mujoco_release_under_xdg_cache_home(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    expected = tmp_path / "xdg" / "mujoco-composer" / "patch_proof" / "mujoco-4.0.1.json"
    assert patch_table.cache_path("4.0.1") == expected


def test_the_cache_file_is_under_dot_cache_without_xdg_cache_home(monkeypatch, tmp_path):
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))
    expected = tmp_path / ".cache" / "mujoco-composer" / "patch_proof" / "mujoco-3.3.0.json"
    assert patch_table.cache_path("3.3.0") == expected


def test_the_checked_in_table_applies_on_the_release_it_was_proven_on(monkeypatch):
    monkeypatch.setattr(patchable_attributes, "MUJOCO_VERSION", mujoco.__version__)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = patch_table.current()
    assert table.proven is patchable_attributes.PROVEN
    assert table.source == "mjcf/patching/patchable_attributes.py"


def test_an_unproven_release_warns_once_naming_the_command_and_nothing_patches(
    unproven_release,
):
    with pytest.warns(RuntimeWarning) as caught:
        assert patch_table.current() is None
        assert not model_patch.patch_supported()
        assert not _patches_a_colour()
        assert not _patches_a_colour()
    assert len(caught) == 1
    message = str(caught[0].message)
    assert "`python -m manipulation.patch_proof`" in message
    assert f"proven on mujoco 0.0.0, not on the installed {mujoco.__version__}" in message
    assert str(_cache_file(unproven_release)) in message


def test_a_cached_proof_for_the_installed_release_turns_patching_on_for_its_pairs(
    unproven_release,
):
    patch_table.write_cache({("geom", "rgba"): False}, {("geom", "pos"): "body_ipos"})
    assert _cache_file(unproven_release).exists()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = patch_table.current()
        assert _patches_a_colour()
    assert table.proven == {("geom", "rgba"): False}
    assert table.refused == {("geom", "pos"): "body_ipos"}
    assert table.source == str(_cache_file(unproven_release))


def test_a_corrupt_cache_file_is_ignored_with_a_warning_naming_it(unproven_release):
    path = _cache_file(unproven_release)
    path.parent.mkdir(parents=True)
    path.write_text('{"format": 1, "mujoco": ', encoding="utf-8")
    with pytest.warns(RuntimeWarning, match="ignoring the cached patch proof") as caught:
        assert patch_table.current() is None
        assert not _patches_a_colour()
    assert len(caught) == 1
    assert str(path) in str(caught[0].message)
    assert "python -m manipulation.patch_proof" in str(caught[0].message)


def test_a_cache_file_with_malformed_pairs_is_ignored_with_a_warning(unproven_release):
    patch_table.write_cache({("geom", "rgba"): False}, {})
    path = _cache_file(unproven_release)
    record = json.loads(path.read_text(encoding="utf-8"))
    record["proven"] = [["geom"]]
    path.write_text(json.dumps(record), encoding="utf-8")
    with pytest.warns(RuntimeWarning, match="ignoring the cached patch proof"):
        assert patch_table.current() is None


def test_a_cache_file_proven_on_another_mujoco_release_is_ignored(unproven_release):
    patch_table.write_cache({("geom", "rgba"): False}, {})
    path = _cache_file(unproven_release)
    record = json.loads(path.read_text(encoding="utf-8"))
    record["mujoco"] = "9.9.9"
    path.write_text(json.dumps(record), encoding="utf-8")
    with pytest.warns(
        RuntimeWarning,
        match=rf"it was proven on mujoco 9\.9\.9, the installed one is {mujoco.__version__}",
    ):
        assert patch_table.current() is None
        assert not _patches_a_colour()


def test_a_cache_file_proven_by_another_version_of_the_project_is_ignored(unproven_release):
    patch_table.write_cache({("geom", "rgba"): False}, {})
    path = _cache_file(unproven_release)
    record = json.loads(path.read_text(encoding="utf-8"))
    record["project"] = "0.0.1-older"
    path.write_text(json.dumps(record), encoding="utf-8")
    with pytest.warns(RuntimeWarning, match=r"proven by mujoco-composer 0\.0\.1-older"):
        assert patch_table.current() is None
