"""Tests for Physics.render: RGB, depth and segmentation images from real pixels (EGL)."""

import mujoco
import numpy as np
import pytest

from mjcf.physics import Physics
from mujoco_physics import TextOverlay

# A red box 2 m in front of a camera looking along +y; nothing else in view.
_XML = """
<mujoco>
  <visual><global offwidth="160" offheight="120"/></visual>
  <worldbody>
    <light pos="0 -2 2" dir="0 1 -1"/>
    <camera name="front" pos="0 -2 0" xyaxes="1 0 0 0 0 1"/>
    <camera name="side" pos="-2 0 0" xyaxes="0 -1 0 0 0 1"/>
    <body name="box_body">
      <geom name="box" type="box" size="0.3 0.3 0.3" rgba="1 0 0 1"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture(scope="module")
def physics():
    return Physics.from_xml_string(_XML)


def test_rgb_shows_the_red_box_in_the_middle(physics):
    image = physics.render(height=60, width=80, camera_id="front")
    assert image.shape == (60, 80, 3)
    assert image.dtype == np.uint8
    red, green, blue = image[30, 40].astype(int)
    assert red > 100 and red > 2 * green and red > 2 * blue


def test_rgb_background_is_not_red(physics):
    image = physics.render(height=60, width=80, camera_id="front")
    red, green, blue = image[2, 2].astype(int)
    assert not (red > 100 and red > 2 * green)


def test_camera_index_and_name_give_the_same_image(physics):
    by_name = physics.render(height=60, width=80, camera_id="side")
    by_index = physics.render(height=60, width=80, camera_id=1)
    np.testing.assert_array_equal(by_name, by_index)


def test_free_camera_is_the_default(physics):
    free = physics.render(height=60, width=80)
    np.testing.assert_array_equal(physics.render(height=60, width=80, camera_id=-1), free)
    assert not np.array_equal(free, physics.render(height=60, width=80, camera_id="front"))


def test_default_size_is_240_by_320():
    assert Physics.from_xml_string("<mujoco/>").render().shape == (240, 320, 3)


def test_image_size_follows_the_arguments(physics):
    assert physics.render(height=30, width=50, camera_id="front").shape == (30, 50, 3)
    assert physics.render(height=60, width=80, camera_id="front").shape == (60, 80, 3)


def test_depth_is_the_distance_to_the_box_face(physics):
    depth = physics.render(height=60, width=80, camera_id="front", depth=True)
    assert depth.shape == (60, 80)
    assert depth[30, 40] == pytest.approx(2 - 0.3, abs=0.02)


def test_segmentation_labels_the_box_geom(physics):
    segmentation = physics.render(height=60, width=80, camera_id="front", segmentation=True)
    assert segmentation.shape == (60, 80, 2)
    box = mujoco.mj_name2id(physics.model.ptr, mujoco.mjtObj.mjOBJ_GEOM, "box")
    assert tuple(segmentation[30, 40]) == (box, int(mujoco.mjtObj.mjOBJ_GEOM))
    assert tuple(segmentation[0, 0]) == (-1, -1)


def test_rgb_after_depth_is_rgb_again(physics):
    physics.render(height=60, width=80, camera_id="front", depth=True)
    assert physics.render(height=60, width=80, camera_id="front").dtype == np.uint8


def test_render_flag_overrides_apply_to_one_image_only(physics):
    plain = physics.render(height=60, width=80, camera_id="front")
    wireframe = physics.render(
        height=60, width=80, camera_id="front", render_flag_overrides={"wireframe": True}
    )
    assert not np.array_equal(plain, wireframe)
    np.testing.assert_array_equal(physics.render(height=60, width=80, camera_id="front"), plain)


def test_unknown_camera_name_is_an_error(physics):
    with pytest.raises(ValueError, match="'back'"):
        physics.render(camera_id="back")


def test_camera_index_out_of_range_is_an_error(physics):
    with pytest.raises(ValueError, match="camera_id 2"):
        physics.render(camera_id=2)


def test_image_larger_than_the_offscreen_buffer_is_an_error(physics):
    with pytest.raises(ValueError, match="height 480 and width 640 exceeds.*offscreen buffer"):
        physics.render(height=480, width=640)


def test_overlays_are_rgb_only(physics):
    overlay = TextOverlay(title="Title")
    with pytest.raises(ValueError) as raised:
        physics.render(60, 80, overlays=[overlay], depth=True)
    assert str(raised.value) == "overlays only apply to RGB images, not to depth or segmentation"


def test_render_after_free_is_a_clear_error():
    physics = Physics.from_xml_string(_XML)
    physics.render(height=8, width=8)
    physics.free()
    with pytest.raises(AttributeError, match="^this Physics was freed"):
        physics.render(height=8, width=8)


def test_scene_option_hiding_geom_group_0_hides_the_box(physics):
    option = mujoco.MjvOption()
    option.geomgroup[0] = 0
    image = physics.render(height=60, width=80, camera_id="front", scene_option=option)
    red, green, blue = image[30, 40].astype(int)
    assert not (red > 100 and red > 2 * green and red > 2 * blue)
