"""composer.viewer.renderer and .viewer (dm_control compatibility): images of a physics from
a free camera whose pose is set through `camera.settings`."""

import numpy as np
import pytest

import mjcf
from composer.viewer import renderer, viewer


def _red_ball_on_black():
    model = mjcf.RootElement(model="ball")
    model.visual.headlight.ambient = [1, 1, 1]
    model.visual.headlight.diffuse = [0, 0, 0]
    model.worldbody.add("geom", type="sphere", size=[0.1], rgba=[1, 0, 0, 1])
    # Far from the ball: the free camera's default view shows both.
    model.worldbody.add("geom", type="box", pos=[5, 0, 0], size=[0.1, 0.1, 0.1], rgba=[0, 0, 1, 1])
    return mjcf.Physics.from_mjcf_model(model)


def _red_fraction(pixels):
    red = (pixels[..., 0] > 200) & (pixels[..., 1] < 50) & (pixels[..., 2] < 50)
    return red.mean()


def test_viewport_converts_screen_pixels_to_fractions():
    viewport = renderer.Viewport(200, 100)
    np.testing.assert_allclose(viewport.screen_to_viewport((50, 25)), [0.25, 0.25])
    np.testing.assert_allclose(viewport.screen_to_inverse_viewport((50, 25)), [0.25, 0.75])
    viewport.set_size(400, 100)
    assert viewport.aspect_ratio == 4.0
    assert (viewport.mujoco_rect.width, viewport.mujoco_rect.height) == (400, 100)
    np.testing.assert_array_equal(viewport.dimensions, [400, 100])


def test_viewport_refuses_a_size_that_is_not_a_positive_integer():
    with pytest.raises(ValueError, match="Viewport height: expected a positive integer, got 0"):
        renderer.Viewport(10, 0)


def test_null_renderer_is_one_black_pixel():
    pixels = renderer.NullRenderer().pixels
    assert pixels.shape == (1, 1, 3)
    assert not pixels.any()


def test_viewer_renders_at_the_viewport_size_from_the_camera_settings():
    physics = _red_ball_on_black()
    viewport = renderer.Viewport(64, 48)
    offscreen = renderer.OffScreenRenderer(physics.model, surface=None)
    view = viewer.Viewer(viewport, None, None)
    view.initialize(physics, offscreen, False)
    view.render()
    assert offscreen.pixels.shape == (48, 64, 3)
    far = _red_fraction(offscreen.pixels)
    view.camera.settings.lookat[:] = [0, 0, 0]
    view.camera.settings.distance = 0.25
    view.render()
    assert far < 0.05
    assert _red_fraction(offscreen.pixels) > 0.5
    viewport.set_size(32, 16)
    view.render()
    assert offscreen.pixels.shape == (16, 32, 3)
    offscreen.release()


def test_camera_pose_is_kept_from_one_initialize_to_the_next():
    physics = _red_ball_on_black()
    view = viewer.Viewer(renderer.Viewport(8, 8), None, None)
    view.initialize(physics, renderer.NullRenderer(), False)
    view.camera.settings.azimuth = 30.0
    view.camera.settings.lookat[:] = [0.0, 0.1, 0.2]
    view.deinitialize()
    assert view.camera is None
    view.initialize(physics, renderer.NullRenderer(), False)
    assert view.camera.settings.azimuth == 30.0
    np.testing.assert_array_equal(view.camera.settings.lookat, [0.0, 0.1, 0.2])


def test_offscreen_renderer_refuses_something_that_is_not_a_model():
    with pytest.raises(TypeError, match="expected a mujoco.MjModel.*got str"):
        renderer.OffScreenRenderer("model.xml")
