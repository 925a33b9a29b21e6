"""mjcf.patching.first_use_proof: on a MuJoCo release no table was proven on, a change is
proven on the model at hand the first time, then patched; a change that fails its proof
recompiles, with one warning that names it and the fields that differ."""

import os
import subprocess
import sys
import textwrap
import warnings

import pytest

import mjcf
from mjcf import physics as physics_module
from mjcf.patching import (
    compiled_model,
    first_use_proof,
    model_comparison,
    patchable_attributes,
)

_ARM = """
<mujoco model="arm">
  <compiler angle="{angle}"/>
  <worldbody>
    <site name="goal" pos="0.3 0 0" size="0.02"/>
    <body name="upper" pos="0 0 0.5">
      <joint name="shoulder" axis="0 1 0" range="-1 1"/>
      <geom name="upper" type="capsule" size="0.03 0.1" rgba="1 0 0 1"/>
    </body>
  </worldbody>
  <actuator>
    <motor name="limited" joint="shoulder" ctrlrange="-1 1"/>
    <motor name="free" joint="shoulder"/>
  </actuator>
</mujoco>
"""


@pytest.fixture(autouse=True)
def unproven_release(monkeypatch, tmp_path):
    """The checked-in table claims another release, the cache directory is empty, and
    nothing has been warned about in this process."""
    monkeypatch.setattr(patchable_attributes, "MUJOCO_VERSION", "0.0.0-elsewhere")
    monkeypatch.setattr(first_use_proof, "_WARNED", set())
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    return tmp_path


@pytest.fixture
def mujoco_compiles(monkeypatch) -> list:
    """Every compile of an MJCF model from now on, a proof's and an environment's alike."""
    calls = []
    original = physics_module.compile_mjcf_model

    def recording(root):
        calls.append(root)
        return original(root)

    monkeypatch.setattr(physics_module, "compile_mjcf_model", recording)
    monkeypatch.setattr(compiled_model, "compile_mjcf_model", recording)
    return calls


def _arm(angle="radian"):
    root = mjcf.from_xml_string(_ARM.format(angle=angle))
    return root, mjcf.Physics.from_mjcf_model(root)


def _change(root, physics, element, **values) -> bool:
    count = root.modification_count
    element.set_attributes(**values)
    return physics.apply_attribute_changes(root.attribute_changes_since(count))


def _differences_from_a_recompile(root, physics) -> list[str]:
    return model_comparison.differences(
        physics.model.ptr, mjcf.Physics.from_mjcf_model(root).model.ptr
    )


def test_a_change_no_proof_covers_is_proven_with_one_compile_then_patched_with_none(
    mujoco_compiles,
):
    root, physics = _arm()
    goal = root.find("site", "goal")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mujoco_compiles.clear()
        assert _change(root, physics, goal, pos=[0.1, 0.2, 0])
        assert len(mujoco_compiles) == 1  # the proof's, in place of the recompile
        assert _differences_from_a_recompile(root, physics) == []
        mujoco_compiles.clear()
        assert _change(root, physics, goal, pos=[-0.2, 0.1, 0])
        assert mujoco_compiles == []
    assert _differences_from_a_recompile(root, physics) == []


def test_a_change_that_fails_its_proof_recompiles_with_one_warning_naming_it_and_the_fields(
    mujoco_compiles,
):
    # An actuator given a control range where none was set also becomes limited.
    root, physics = _arm()
    free = root.find("actuator", "free")
    before = model_comparison.model_arrays(physics.model.ptr)
    with pytest.warns(RuntimeWarning) as caught:
        assert not _change(root, physics, free, ctrlrange=[-2, 2])
    [warning] = caught
    assert "<motor> 'ctrlrange' (on an element, set where nothing set it" in str(warning.message)
    assert "actuator_ctrllimited" in str(warning.message)
    assert model_comparison.model_arrays(physics.model.ptr) == before  # nothing written
    # Known refused now: the next such change recompiles at once, without a word.
    physics = mjcf.Physics.from_mjcf_model(root)
    root.find("actuator", "limited").ctrlrange = None
    physics = mjcf.Physics.from_mjcf_model(root)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mujoco_compiles.clear()
        assert not _change(root, physics, root.find("actuator", "limited"), ctrlrange=[-3, 3])
        assert mujoco_compiles == []


def test_a_value_replacing_another_is_proven_apart_from_one_set_where_none_was():
    root, physics = _arm()
    with pytest.warns(RuntimeWarning, match="actuator_ctrllimited"):
        assert not _change(root, physics, root.find("actuator", "free"), ctrlrange=[-2, 2])
    physics = mjcf.Physics.from_mjcf_model(root)
    assert _change(root, physics, root.find("actuator", "limited"), ctrlrange=[-0.5, 0.5])
    assert _differences_from_a_recompile(root, physics) == []


def test_a_proof_in_radians_does_not_patch_a_model_in_degrees():
    root, physics = _arm("radian")
    assert _change(root, physics, root.find("joint", "shoulder"), range=[-0.5, 0.5])
    assert _differences_from_a_recompile(root, physics) == []
    # The compiler converts degrees: written as they are, they would be a wrong range.
    root, physics = _arm("degree")
    with pytest.warns(RuntimeWarning, match=r"compiler: angle=degree.*jnt_range"):
        assert not _change(root, physics, root.find("joint", "shoulder"), range=[-30, 30])


def test_a_default_class_change_is_proven_apart_from_an_elements():
    root = mjcf.from_xml_string(
        "<mujoco><default><geom rgba='1 0 0 1'/></default><worldbody>"
        "<geom name='a' size='0.1'/><geom name='b' size='0.1' rgba='0 0 1 1'/>"
        "</worldbody></mujoco>"
    )
    physics = mjcf.Physics.from_mjcf_model(root)
    assert _change(root, physics, root.find("geom", "b"), rgba=[0, 1, 0, 1])
    assert _change(root, physics, root.default.geom, rgba=[1, 1, 0, 1])
    assert _differences_from_a_recompile(root, physics) == []
    assert physics.named.model.geom_rgba["a"].tolist() == [1, 1, 0, 1]


# Proves a goal's move in one process; prints whether it patched and how many compiles the
# change cost.
_MOVE_THE_GOAL = textwrap.dedent(
    """
    import mjcf
    from mjcf import physics as physics_module
    from mjcf.patching import patchable_attributes
    patchable_attributes.MUJOCO_VERSION = "0.0.0-elsewhere"
    compiles = []
    original = physics_module.compile_mjcf_model
    physics_module.compile_mjcf_model = lambda root: compiles.append(root) or original(root)
    root = mjcf.from_xml_string('''{xml}''')
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    compiles.clear()
    root.find("site", "goal").pos = [0.1, 0.2, 0.0]
    print(physics.apply_attribute_changes(root.attribute_changes_since(count)), len(compiles))
    """
)


def test_a_proof_made_in_one_process_patches_in_the_next_without_a_compile(unproven_release):
    command = [sys.executable, "-W", "error::RuntimeWarning", "-c"]
    command.append(_MOVE_THE_GOAL.format(xml=_ARM.format(angle="radian")))
    env = dict(os.environ, XDG_CACHE_HOME=str(unproven_release))
    runs = [
        subprocess.run(command, env=env, capture_output=True, text=True, timeout=120)
        for _ in range(2)
    ]
    assert [run.stderr for run in runs] == ["", ""]
    assert [run.stdout.split() for run in runs] == [["True", "1"], ["True", "0"]]


def test_joint_damping_is_proven_apart_in_a_model_whose_joints_take_springdamper():
    # The corpus refuses the pair (springdamper models differ in dof_damping); at first use
    # a model without springdamper proves it, and one with it is proven apart and refused.
    root = mjcf.from_xml_string(_ARM.format(angle="radian"))
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("joint", "shoulder").damping = 0.4
    assert physics.apply_attribute_changes(root.attribute_changes_since(count))
    assert (
        model_comparison.differences(physics.model.ptr, physics_module.compile_mjcf_model(root))
        == []
    )
    root.find("joint", "shoulder").springdamper = [0.5, 1]
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("joint", "shoulder").damping = 0.8
    with pytest.warns(RuntimeWarning, match="takes springdamper.*dof_damping"):
        assert not physics.apply_attribute_changes(root.attribute_changes_since(count))
