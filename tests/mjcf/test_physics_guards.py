"""Physics behaviours whose loss went unnoticed by other tests: copies keep the stepping mode,
reset_context survives a diverging reset, and frame-offset writes clear MuJoCo's shortcuts."""

import numpy as np
import pytest

import mjcf

_XML = """
<mujoco>
  <worldbody>
    <body name="ball" pos="0 0 1">
      <freejoint/>
      <geom name="ball" type="sphere" size="0.1" mass="1"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture
def physics():
    return mjcf.Physics.from_xml_string(_XML)


@pytest.mark.parametrize("share_model", [False, True])
def test_copy_keeps_legacy_step_off(physics, share_model):
    physics.legacy_step = False
    assert physics.copy(share_model=share_model).legacy_step is False


def test_reset_context_tolerates_a_physics_error_from_the_reset(physics, monkeypatch):
    # mj_forward raises no divergence warnings in MuJoCo 4, so the reset is made to fail.
    real_reset = physics.reset

    def diverging_reset():
        real_reset()
        raise mjcf.PhysicsError("diverged while resetting")

    monkeypatch.setattr(physics, "reset", diverging_reset)
    physics.data.qpos[:3] = [5, 5, 5]
    with physics.reset_context():
        physics.data.qpos[2] = 2.0
    np.testing.assert_array_equal(physics.data.qpos[:3], [0, 0, 2])
    np.testing.assert_allclose(physics.data.xpos[1], [0, 0, 2])


def test_writing_ipos_through_a_binding_clears_the_simple_body_flag():
    root = mjcf.from_xml_string(_XML)
    physics = mjcf.Physics.from_mjcf_model(root)
    ball = root.find("body", "ball")
    assert physics.model.body_simple[1] != 0  # a sphere at the body origin: simple
    physics.bind(ball).ipos = [0.0, 0.0, 0.05]
    assert physics.model.body_simple[1] == 0
    physics.forward()
    np.testing.assert_allclose(physics.data.xipos[1], [0, 0, 1.05])


def _body_with_three_geoms_and_a_camera():
    root = mjcf.RootElement()
    body = root.worldbody.add("body", name="holder", pos=[0, 0, 1])
    for index in range(3):
        body.add("geom", name=f"geom{index}", size=[0.1])
    body.add("camera", name="eye")
    return root, mjcf.Physics.from_mjcf_model(root)


def test_writing_one_geoms_position_clears_only_its_own_frame_flag():
    root, physics = _body_with_three_geoms_and_a_camera()
    assert list(physics.model.geom_sameframe) == [1, 1, 1]  # all at the body origin
    physics.bind(root.find("geom", "geom1")).pos = [0.5, 0, 0]
    assert list(physics.model.geom_sameframe) == [1, 0, 1]
    physics.forward()
    np.testing.assert_allclose(physics.data.geom_xpos[1], [0.5, 0, 1])


def test_writing_a_list_of_geoms_positions_clears_each_frame_flag():
    root, physics = _body_with_three_geoms_and_a_camera()
    geoms = [root.find("geom", "geom0"), root.find("geom", "geom2")]
    physics.bind(geoms).pos = [[0, 0.5, 0], [0, 0, 0.5]]
    assert list(physics.model.geom_sameframe) == [0, 1, 0]
    physics.forward()
    np.testing.assert_allclose(physics.data.geom_xpos[[0, 2]], [[0, 0.5, 1], [0, 0, 1.5]])


def test_writing_a_camera_position_through_a_binding_moves_it():
    root, physics = _body_with_three_geoms_and_a_camera()
    camera = physics.bind(root.find("camera", "eye"))
    camera.pos = [0, -2, 0]
    np.testing.assert_allclose(camera.xpos, [0, -2, 1])
