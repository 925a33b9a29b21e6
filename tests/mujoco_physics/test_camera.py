"""Tests for mujoco_physics cameras: projection, selection, poses, overlays, callbacks."""

import mujoco
import numpy as np
import pytest

import mujoco_physics

# A camera 2 m above the origin looking straight down (MuJoCo cameras look along -z), with
# a 90 degree field of view: a point at height 0 and x = 1 is at the image's right edge.
_XML = """
<mujoco>
  <visual><global offwidth="200" offheight="200"/></visual>
  <worldbody>
    <light pos="0 0 3"/>
    <geom name="floor" type="plane" size="3 3 .1" rgba="0.2 0.2 0.2 1"/>
    <body name="ball" pos="0.5 0 0.25"><geom name="ball" size="0.25" rgba="1 0 0 1"/></body>
    <camera name="down" pos="0 0 2" fovy="90"/>
  </worldbody>
</mujoco>
"""


@pytest.fixture
def physics():
    return mujoco_physics.Physics.from_xml_string(_XML)


def test_camera_matrix_projects_world_points_to_the_expected_pixels(physics):
    camera = mujoco_physics.Camera(physics, height=101, width=101, camera_id="down")

    def pixel(point):
        x, y, s = camera.matrix @ np.append(point, 1.0)
        return x / s, y / s

    # Straight below: the centre. tan(45 deg) = 1, so 2 m down and 2 m aside is the edge,
    # 50.5 pixels from the centre at 50.
    np.testing.assert_allclose(pixel([0, 0, 0]), [50, 50], atol=1e-9)
    np.testing.assert_allclose(pixel([2, 0, 0]), [100.5, 50], atol=1e-9)
    # Image y grows downwards; world +y is the image's top for this camera.
    np.testing.assert_allclose(pixel([0, 2, 0]), [50, -0.5], atol=1e-9)


def test_segmentation_under_the_projected_ball_centre_is_the_ball(physics):
    camera = mujoco_physics.Camera(physics, height=101, width=101, camera_id="down")
    x, y, s = camera.matrix @ np.array([0.5, 0, 0.25, 1.0])
    segmentation = camera.render(segmentation=True)
    ball = physics.model.name2id("ball", "geom")
    assert tuple(segmentation[int(round(y / s)), int(round(x / s))]) == (
        ball,
        mujoco.mjtObj.mjOBJ_GEOM,
    )


def test_select_finds_the_ball_under_the_cursor_and_nothing_outside_the_floor(physics):
    camera = mujoco_physics.Camera(physics, height=100, width=100, camera_id="down")
    # The ball's centre is at x = 0.5 of a 2 m half-width: 0.625 of the image from the left.
    hit = camera.select((0.625, 0.5))
    assert (hit.body, hit.geom) == (1, physics.model.name2id("ball", "geom"))
    # The ray from the camera at (0, 0, 2) towards (0.5, 0, 0) enters the ball (centre
    # (0.5, 0, 0.25), radius 0.25) where |c + t d - centre| = 0.25 first holds.
    start, direction, centre = np.array([0, 0, 2.0]), np.array([0.5, 0, -2.0]), [0.5, 0, 0.25]
    offset = start - centre
    b, c = 2 * direction @ offset, offset @ offset - 0.25**2
    t = (-b - np.sqrt(b * b - 4 * (direction @ direction) * c)) / (2 * direction @ direction)
    np.testing.assert_allclose(hit.world_position, start + t * direction, atol=1e-6)
    floor = camera.select((0.1, 0.1))
    assert (floor.body, floor.geom) == (0, 0)


def test_movable_camera_pose_round_trips_and_moves_the_view(physics):
    camera = mujoco_physics.MovableCamera(physics, height=64, width=64)
    before = camera.render().copy()
    camera.set_pose([0.5, 0, 0.25], 1.0, 90.0, -89.0)
    pose = camera.get_pose()
    np.testing.assert_array_equal(pose.lookat, [0.5, 0, 0.25])
    assert (pose.distance, pose.azimuth, pose.elevation) == (1.0, 90.0, -89.0)
    after = camera.render()
    # Looking down at the red ball from 1 m, the centre pixel is red.
    assert after[32, 32, 0] > 2 * after[32, 32, 1]
    assert not np.array_equal(before, after)


def test_text_overlay_changes_the_pixels_and_bad_styles_are_named(physics):
    plain = physics.render(64, 64, camera_id="down")
    overlay = mujoco_physics.TextOverlay(title="Hi", body="there", position="top left")
    written = physics.render(64, 64, camera_id="down", overlays=[overlay])
    assert not np.array_equal(plain, written)
    np.testing.assert_array_equal(plain[40:], written[40:])
    with pytest.raises(ValueError) as raised:
        mujoco_physics.TextOverlay(style="huge")
    assert str(raised.value) == "style: expected one of ['big', 'normal'], got 'huge'"


def test_scene_callback_adds_geoms_before_rendering(physics):
    def add_green_box(_, scene):
        scene.ngeom += 1
        mujoco.mjv_initGeom(
            scene.geoms[scene.ngeom - 1],
            mujoco.mjtGeom.mjGEOM_BOX,
            np.array([3.0, 3.0, 0.1]),
            np.array([0.0, 0.0, 1.0]),
            np.eye(3).ravel(),
            np.array([0, 1, 0, 1], dtype=np.float32),
        )

    image = physics.render(32, 32, camera_id="down", scene_callback=add_green_box)
    assert image[16, 16, 1] > 2 * image[16, 16, 0]


def test_cameras_and_physics_render_of_one_size_share_one_opengl_context(physics, monkeypatch):
    from mujoco_physics import _gl_backend

    made = []
    original = _gl_backend.new_renderer

    def counting(model, height, width, **kwargs):
        made.append((height, width))
        return original(model, height=height, width=width, **kwargs)

    monkeypatch.setattr(_gl_backend, "new_renderer", counting)
    top = mujoco_physics.Camera(physics, height=64, width=64, camera_id="down")
    free = mujoco_physics.MovableCamera(physics, height=64, width=64)
    top.render()
    free.render()
    physics.render(64, 64, camera_id="down")
    assert made == [(64, 64)]
    mujoco_physics.Camera(physics, height=32, width=48).render()
    assert made == [(64, 64), (32, 48)]


def test_a_cameras_own_scene_flags_stay_its_own_on_the_shared_renderer(physics):
    camera = mujoco_physics.Camera(physics, height=64, width=64, camera_id="down")
    plain = physics.render(64, 64, camera_id="down")
    np.testing.assert_array_equal(camera.render(), plain)
    camera.scene.flags[mujoco.mjtRndFlag.mjRND_WIREFRAME] = 1
    wireframe = camera.render()
    assert not np.array_equal(wireframe, plain)
    # physics.render of the same size draws its own scene, the camera keeps its flag.
    np.testing.assert_array_equal(physics.render(64, 64, camera_id="down"), plain)
    np.testing.assert_array_equal(camera.render(), wireframe)
    # Depth from the camera is the Physics' depth of that view: the floor 2 m below the
    # camera along its axis (a corner pixel), the ball's top 0.5 m above the floor.
    depth = camera.render(depth=True)
    np.testing.assert_allclose(depth, physics.render(64, 64, "down", depth=True))
    assert depth[63, 0] == pytest.approx(2.0, abs=1e-3)
    assert depth.min() == pytest.approx(1.5, abs=0.005)
