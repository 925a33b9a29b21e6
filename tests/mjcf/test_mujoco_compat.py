"""Supported MuJoCo range: the import-time floor check and errors naming missing features."""

import pathlib
import re
import subprocess
import sys

import mujoco
import pytest

import mjcf
from mjcf import mujoco_compat, schema
from mujoco_physics import field_layout

_REPO = pathlib.Path(__file__).resolve().parents[2]


def test_version_below_the_floor_is_an_import_error_naming_both_versions():
    with pytest.raises(
        ImportError, match=r"needs mujoco>=3\.3\.0, but mujoco 3\.2\.7 is installed"
    ):
        mujoco_compat.check_version("3.2.7")


@pytest.mark.parametrize("version", ["3.3.0", "3.3.7", "3.10.0", "4.0.0", "10.1.2"])
def test_versions_from_the_floor_up_pass_the_check(version):
    mujoco_compat.check_version(version)


@pytest.mark.parametrize("package", ["mjcf", "composer", "manipulation"])
def test_importing_the_project_on_an_old_mujoco_raises_one_clear_import_error(package):
    # A real mujoco with its version string made old: the check must stop the import
    # before any module reads MuJoCo's tables.
    script = f"import mujoco; mujoco.__version__ = '3.1.6'; import {package}"
    result = subprocess.run(
        [sys.executable, "-c", script], cwd=_REPO, capture_output=True, text=True
    )
    assert result.returncode != 0
    last_line = result.stderr.strip().splitlines()[-1]
    assert last_line == (
        "ImportError: this project needs mujoco>=3.3.0, but mujoco 3.1.6 is installed; "
        "upgrade it with: pip install 'mujoco>=3.3.0'"
    )


def test_pyproject_requires_the_floor_that_the_import_check_enforces():
    requirements = re.findall(
        r'"mujoco>=([\d.]+)"', (_REPO / "pyproject.toml").read_text(encoding="utf-8")
    )
    assert requirements == ["3.3.0"]
    assert mujoco_compat.MINIMUM_VERSION == "3.3.0"


def test_missing_mjcf_attribute_names_the_release_that_reads_it():
    assert mujoco_compat.missing_mjcf("mujoco/sensor/touch", "interval", installed="3.4.0") == (
        "MJCF 'interval' in <sensor> needs mujoco>=3.5.0 (installed: mujoco 3.4.0)"
    )


def test_missing_mjcf_is_empty_where_the_release_has_the_feature_or_never_will():
    assert mujoco_compat.missing_mjcf("mujoco/sensor/touch", "interval", installed="3.5.0") == ""
    assert mujoco_compat.missing_mjcf("mujoco/worldbody/geom", "interval", installed="3.3.0") == ""
    assert mujoco_compat.missing_mjcf("mujoco/sensor/touch", "intervall", installed="3.3.0") == ""


def test_missing_binding_field_names_the_release_that_has_it():
    assert mujoco_compat.missing_binding("geom", "xquat", installed="3.17.0") == (
        "geom attribute 'xquat' needs mujoco>=4.0.0 (installed: mujoco 3.17.0)"
    )
    assert mujoco_compat.missing_binding("geom", "xquat", installed="4.0.0") == ""


def test_every_mjcf_feature_in_the_table_exists_where_it_says_on_this_release():
    installed = mujoco_compat.version_tuple(mujoco.__version__)
    names_under = {}
    for spec in schema.all_specs():
        for tag in spec.path.split("/"):
            names = names_under.setdefault(tag, set())
            names.update(spec.attributes)
            names.update(spec.children)
    for key, since in mujoco_compat.MJCF_SINCE.items():
        tag, name = key.split(".")
        has = name in names_under.get(tag, ())
        assert has == (installed >= mujoco_compat.version_tuple(since)), key


def test_every_binding_feature_in_the_table_exists_where_it_says_on_this_release():
    installed = mujoco_compat.version_tuple(mujoco.__version__)
    for key, since in mujoco_compat.BINDING_SINCE.items():
        namespace, attribute = key.split(".")
        has = attribute in field_layout.FAMILIES[namespace].fields
        assert has == (installed >= mujoco_compat.version_tuple(since)), key


def test_setting_an_attribute_of_a_newer_mujoco_names_the_release(monkeypatch):
    monkeypatch.setitem(mujoco_compat.MJCF_SINCE, "geom.hardness", "99.0.0")
    geom = mjcf.RootElement().worldbody.add("geom", size=[0.1])
    with pytest.raises(AttributeError, match=r"'hardness'.*needs mujoco>=99\.0\.0"):
        geom.hardness = 1


def test_adding_an_element_of_a_newer_mujoco_names_the_release(monkeypatch):
    monkeypatch.setitem(mujoco_compat.MJCF_SINCE, "actuator.turbine", "99.0.0")
    with pytest.raises(AttributeError, match=r"<turbine>.*needs mujoco>=99\.0\.0"):
        mjcf.RootElement().actuator.add("turbine")


def test_binding_a_field_of_a_newer_mujoco_names_the_release(monkeypatch):
    monkeypatch.setitem(mujoco_compat.BINDING_SINCE, "geom.hardness", "99.0.0")
    root = mjcf.RootElement()
    geom = root.worldbody.add("geom", name="g", size=[0.1])
    physics = mjcf.Physics.from_mjcf_model(root)
    with pytest.raises(AttributeError, match=r"'hardness'.*needs mujoco>=99\.0\.0"):
        _ = physics.bind(geom).hardness


_XQUAT_MISSING = mujoco_compat.missing_binding("geom", "xquat")


@pytest.mark.skipif(
    not _XQUAT_MISSING,
    reason=f"error path of releases before 4.0.0; mujoco {mujoco.__version__} has geom xquat",
)
def test_binding_geom_xquat_on_a_release_without_it_names_the_release():
    root = mjcf.RootElement()
    geom = root.worldbody.add("geom", name="g", size=[0.1])
    physics = mjcf.Physics.from_mjcf_model(root)
    with pytest.raises(AttributeError, match=r"'xquat'.*needs mujoco>=4\.0\.0"):
        _ = physics.bind(geom).xquat


_INTERVAL_MISSING = mujoco_compat.missing_mjcf("mujoco/sensor/touch", "interval")


@pytest.mark.skipif(
    not _INTERVAL_MISSING,
    reason=f"error path of releases before 3.5.0; mujoco {mujoco.__version__} has intervals",
)
def test_sensor_interval_on_a_release_without_it_names_the_release():
    sensors = mjcf.RootElement().sensor
    with pytest.raises(AttributeError, match=r"'interval'.*needs mujoco>=3\.5\.0"):
        sensors.add("touch", site="s", interval=[0.5, 0])
