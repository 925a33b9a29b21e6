"""mjcf.patching.compiled_model: each update outcome where its contract names it, and reset
reuse."""

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf.patching import compiled_model
from mjcf.patching.compiled_model import CompiledModel, ModelUpdate

_SCENE = """
<mujoco>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.1" friction="1 0.005 0.0001"/>
    <body name="ball" pos="0 0 0.5">
      <freejoint/>
      <geom name="ball" type="sphere" size="0.1" rgba="1 0 0 1"/>
    </body>
  </worldbody>
</mujoco>
"""


def _root():
    return mjcf.from_xml_string(_SCENE)


def _updated(root, **kwargs) -> CompiledModel:
    model = CompiledModel(**kwargs)
    assert model.update(root) is ModelUpdate.NEW_PHYSICS
    return model


def _reset(model: CompiledModel) -> None:
    with model.reset_context():
        pass


def test_first_update_compiles_a_physics_that_binds_the_root():
    root = _root()
    model = _updated(root)
    ball = root.find("geom", "ball")
    assert model.physics.mjcf_model is root
    np.testing.assert_array_equal(model.physics.bind(ball).size, [0.1, 0, 0])


def test_unchanged_root_restores_the_compiled_values_without_compiling(compiles):
    root = _root()
    model = _updated(root)
    physics = model.physics
    physics.bind(root.find("geom", "ball")).rgba = [0, 0, 1, 1]
    assert model.update(root) is ModelUpdate.RESTORED
    assert model.physics is physics
    np.testing.assert_array_equal(physics.named.model.geom_rgba["ball"], [1, 0, 0, 1])
    assert compiles == [root]  # the first update's compile only


def test_a_patchable_change_patches_in_place_and_is_kept_for_later_restores(compiles):
    root = _root()
    model = _updated(root)
    physics = model.physics
    root.find("geom", "ball").rgba = [0, 1, 0, 1]
    assert model.update(root) is ModelUpdate.PATCHED
    physics.named.model.geom_rgba["ball"] = [0, 0, 0, 0]
    assert model.update(root) is ModelUpdate.RESTORED
    assert model.physics is physics
    np.testing.assert_array_equal(physics.named.model.geom_rgba["ball"], [0, 1, 0, 1])
    assert compiles == [root]  # the first update's compile only


def test_with_patching_off_a_patchable_change_is_compiled_and_loaded(compiles):
    root = _root()
    model = _updated(root, patch=False)
    physics = model.physics
    root.find("geom", "ball").rgba = [0, 1, 0, 1]
    assert model.update(root) is ModelUpdate.LOADED
    assert model.physics is physics
    np.testing.assert_array_equal(physics.named.model.geom_rgba["ball"], [0, 1, 0, 1])
    assert compiles == [root, root]


def test_a_parameter_change_that_does_not_patch_is_loaded_into_the_same_physics():
    root = _root()
    model = _updated(root)
    physics = model.physics
    root.find("body", "ball").pos = [0, 0, 0.7]
    assert model.update(root) is ModelUpdate.LOADED
    assert model.physics is physics
    np.testing.assert_array_equal(physics.named.model.body_pos["ball"], [0, 0, 0.7])
    # What was loaded is restored from then on.
    physics.named.model.body_pos["ball"] = [0, 0, 0]
    assert model.update(root) is ModelUpdate.RESTORED
    np.testing.assert_array_equal(physics.named.model.body_pos["ball"], [0, 0, 0.7])


def test_a_structural_change_gives_a_new_physics_and_frees_the_old_one():
    root = _root()
    model = _updated(root)
    old = model.physics
    root.worldbody.add("geom", name="box", type="box", size=[0.1, 0.1, 0.1])
    assert model.update(root) is ModelUpdate.NEW_PHYSICS
    assert model.physics is not old
    assert model.physics.model.ngeom == 3
    with pytest.raises(AttributeError):
        _ = old.model


def test_another_root_gives_a_new_physics_that_binds_it():
    model = _updated(_root())
    other = _root()
    assert model.update(other) is ModelUpdate.NEW_PHYSICS
    assert model.physics.mjcf_model is other
    assert model.physics.bind(other.find("geom", "ball")).rgba[0] == 1


def test_without_snapshots_every_update_gives_a_new_physics(monkeypatch):
    monkeypatch.setattr(compiled_model, "snapshots_supported", lambda: False)
    root = _root()
    model = _updated(root)
    assert model.update(root) is ModelUpdate.NEW_PHYSICS


def test_a_root_mujoco_rejects_raises_and_keeps_the_physics():
    root = _root()
    model = _updated(root)
    physics = model.physics
    root.worldbody.add("geom", type="mesh")
    with pytest.raises(ValueError, match="could not compile"):
        model.update(root)
    assert model.physics is physics


def test_physics_before_the_first_update_and_after_close_names_the_fix():
    model = CompiledModel()
    with pytest.raises(RuntimeError, match=r"call update\(root\) first"):
        _ = model.physics
    root = _root()
    model.update(root)
    physics = model.physics
    model.close()
    with pytest.raises(RuntimeError, match=r"call update\(root\) first"):
        model.reset_context()
    with pytest.raises(AttributeError):
        _ = physics.model
    model.close()
    assert model.update(root) is ModelUpdate.NEW_PHYSICS


def _model_with_kept_reset(root, physics_resets, **kwargs) -> CompiledModel:
    """A model whose last reset kept its data: physics_resets of a model keep data from the
    second on."""
    model = _updated(root, **kwargs)
    _reset(model)
    assert model.update(root) is ModelUpdate.RESTORED
    _reset(model)
    assert len(physics_resets) == 2
    return model


# Where the bindings cannot copy one MjData into another, every reset is computed afresh.
needs_copy = pytest.mark.skipif(
    not hasattr(mujoco, "mj_copyData"),
    reason=f"mujoco {mujoco.__version__}'s bindings have no mj_copyData: every reset computes",
)


@needs_copy
def test_a_reset_after_a_restore_copies_the_last_resets_data(physics_resets):
    root = _root()
    model = _model_with_kept_reset(root, physics_resets)
    model.physics.data.qpos[:] = 3.0
    assert model.update(root) is ModelUpdate.RESTORED
    _reset(model)
    assert len(physics_resets) == 2
    np.testing.assert_array_equal(model.physics.data.qpos, [0, 0, 0.5, 1, 0, 0, 0])


@needs_copy
def test_a_reset_after_a_colour_patch_copies_the_last_resets_data(physics_resets):
    root = _root()
    model = _model_with_kept_reset(root, physics_resets)
    root.find("geom", "ball").rgba = [0, 1, 0, 1]
    assert model.update(root) is ModelUpdate.PATCHED
    _reset(model)
    assert len(physics_resets) == 2


def test_a_reset_after_a_patch_that_forward_reads_is_afresh(physics_resets):
    root = _root()
    model = _model_with_kept_reset(root, physics_resets)
    root.find("geom", "floor").friction = [0.5, 0.005, 0.0001]
    assert model.update(root) is ModelUpdate.PATCHED
    _reset(model)
    assert len(physics_resets) == 3


@pytest.mark.parametrize("patch", [True, False])
def test_a_reset_after_a_load_is_afresh(physics_resets, patch):
    root = _root()
    model = _model_with_kept_reset(root, physics_resets, patch=patch)
    root.find("body", "ball").pos = [0, 0, 0.7]
    assert model.update(root) is ModelUpdate.LOADED
    _reset(model)
    assert len(physics_resets) == 3


def test_a_reset_after_model_may_have_changed_is_afresh(physics_resets):
    root = _root()
    model = _model_with_kept_reset(root, physics_resets)
    assert model.update(root) is ModelUpdate.RESTORED
    model.model_may_have_changed()
    _reset(model)
    assert len(physics_resets) == 3


def test_a_reset_after_close_and_update_is_afresh(physics_resets):
    root = _root()
    model = _model_with_kept_reset(root, physics_resets)
    model.close()
    model.update(root)
    _reset(model)
    assert len(physics_resets) == 3
