"""Images after an update that keeps the Physics equal a fresh compile's (real EGL pixels):
the render contexts, made from the model before the change, are refreshed where what they
hold of the model changed, and kept where nothing they hold changed."""

import numpy as np
import pytest

import mjcf
from mjcf.patching.compiled_model import CompiledModel, ModelUpdate

# A lit scene with shadows, a floor plane, a box, a box-shaped mesh and a height field, all
# in view.
_SCENE = """
<mujoco>
  <visual>
    <global offwidth="96" offheight="72"/>
    <quality shadowsize="1024" offsamples="4"/>
  </visual>
  <asset>
    <mesh name="brick" vertex="-0.1 -0.15 -0.2  -0.1 -0.15 0.2  -0.1 0.15 -0.2  -0.1 0.15 0.2
                               0.1 -0.15 -0.2  0.1 -0.15 0.2  0.1 0.15 -0.2  0.1 0.15 0.2"/>
    <hfield name="bumps" nrow="3" ncol="3" size="0.3 0.3 0.2 0.05"
            elevation="0 0 0  0 1 0  0 0 0"/>
  </asset>
  <worldbody>
    <light pos="0.3 -0.5 2" dir="0 0.2 -1" castshadow="true"/>
    <camera name="view" pos="0 -2.2 1.4" xyaxes="1 0 0 0 0.55 0.83"/>
    <geom name="floor" type="plane" size="2 2 0.1" rgba="0.6 0.6 0.6 1"/>
    <geom name="box" type="box" pos="-0.6 0 0.3" size="0.15 0.15 0.3" rgba="1 0 0 1"/>
    <geom name="brick" type="mesh" mesh="brick" pos="0 0 0.25" rgba="0 1 0 1"/>
    <geom name="bumps" type="hfield" hfield="bumps" pos="0.6 0 0.01" rgba="0 0 1 1"/>
  </worldbody>
</mujoco>
"""
_HEIGHT, _WIDTH = 60, 80


def _frames(physics) -> list[np.ndarray]:
    """The camera's RGB and depth images."""
    return [
        physics.render(_HEIGHT, _WIDTH, camera_id="view"),
        physics.render(_HEIGHT, _WIDTH, camera_id="view", depth=True),
    ]


def _fresh_frames(root) -> list[np.ndarray]:
    """What a Physics compiled afresh from `root` renders (what dm_control renders after
    the recompile of its reset)."""
    physics = mjcf.Physics.from_mjcf_model(root)
    try:
        return _frames(physics)
    finally:
        physics.free()


def _assert_same_frames(actual, expected) -> None:
    for actual_image, expected_image in zip(actual, expected, strict=True):
        np.testing.assert_array_equal(actual_image, expected_image)


@pytest.fixture
def scene():
    """(root, compiled model) after a first update and a render."""
    root = mjcf.from_xml_string(_SCENE)
    model = CompiledModel()
    assert model.update(root) is ModelUpdate.NEW_PHYSICS
    _frames(model.physics)
    yield root, model
    model.close()


def _update_and_reset(model: CompiledModel, root) -> ModelUpdate:
    outcome = model.update(root)
    with model.reset_context():
        pass
    return outcome


def test_a_visual_quality_change_renders_as_a_fresh_compile(scene):
    root, model = scene
    before = _frames(model.physics)
    root.visual.quality.shadowsize = 256
    root.visual.quality.offsamples = 0
    physics = model.physics
    assert _update_and_reset(model, root) in (ModelUpdate.LOADED, ModelUpdate.PATCHED)
    assert model.physics is physics
    after = _frames(physics)
    _assert_same_frames(after, _fresh_frames(root))
    assert not np.array_equal(after[0], before[0])  # the change shows in the pixels


def test_a_larger_offscreen_buffer_renders_as_a_fresh_compile(scene):
    root, model = scene
    root.visual.__getattr__("global").offwidth = 160
    root.visual.__getattr__("global").offheight = 120
    physics = model.physics
    assert _update_and_reset(model, root) in (ModelUpdate.LOADED, ModelUpdate.PATCHED)
    assert model.physics is physics
    _assert_same_frames(_frames(physics), _fresh_frames(root))
    # An image larger than the old buffer renders, as from a fresh compile.
    large = physics.render(110, 150, camera_id="view")
    fresh = mjcf.Physics.from_mjcf_model(root)
    np.testing.assert_array_equal(large, fresh.render(110, 150, camera_id="view"))
    fresh.free()


@pytest.mark.parametrize(
    "change",
    [
        pytest.param(
            # The same box, larger: only float arrays of the compiled model change.
            lambda root: setattr(
                root.find("mesh", "brick"), "vertex", root.find("mesh", "brick").vertex * 1.2
            ),
            id="mesh vertices",
        ),
        pytest.param(
            lambda root: setattr(
                root.find("hfield", "bumps"), "elevation", [1, 0, 1, 0, 0, 0, 1, 0, 1]
            ),
            id="height field elevation",
        ),
    ],
)
def test_an_asset_change_loaded_in_place_renders_as_a_fresh_compile(scene, change):
    root, model = scene
    before = _frames(model.physics)
    change(root)
    physics = model.physics
    assert _update_and_reset(model, root) is ModelUpdate.LOADED
    assert model.physics is physics
    after = _frames(physics)
    _assert_same_frames(after, _fresh_frames(root))
    assert not np.array_equal(after[1], before[1])  # the asset's shape shows in depth


def test_a_colour_change_keeps_the_render_context(scene):
    root, model = scene
    physics = model.physics
    renderer = physics._offscreen_renderer(_HEIGHT, _WIDTH)
    for rgba in ([0, 1, 1, 1], [1, 1, 0, 1]):
        root.find("geom", "box").rgba = rgba
        assert _update_and_reset(model, root) in (ModelUpdate.PATCHED, ModelUpdate.LOADED)
        _assert_same_frames(_frames(physics), _fresh_frames(root))
        assert physics._offscreen_renderer(_HEIGHT, _WIDTH) is renderer


def test_an_unchanged_model_keeps_the_render_context_and_its_images(scene):
    root, model = scene
    physics = model.physics
    renderer = physics._offscreen_renderer(_HEIGHT, _WIDTH)
    before = _frames(physics)
    assert _update_and_reset(model, root) is ModelUpdate.RESTORED
    _assert_same_frames(_frames(physics), before)
    assert physics._offscreen_renderer(_HEIGHT, _WIDTH) is renderer
