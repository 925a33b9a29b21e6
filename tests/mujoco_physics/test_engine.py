"""Tests for mujoco_physics.Physics: the engine Physics that dm_control's suite subclasses."""

import mujoco
import numpy as np
import pytest
from dm_env import specs

import mujoco_physics
from mujoco_physics import wrapper

_XML = """
<mujoco model="cart">
  <option timestep="0.01"/>
  <worldbody>
    <body name="cart">
      <joint name="slider" type="slide" axis="1 0 0" damping="0.1"/>
      <geom name="box" type="box" size="0.2 0.1 0.05" mass="1"/>
      <body name="pole">
        <joint name="hinge" type="hinge" axis="0 1 0"/>
        <geom name="rod" type="capsule" fromto="0 0 0 0 0 1" size="0.02" mass="0.1"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="push" joint="slider" ctrllimited="true" ctrlrange="-1 1"/>
    <motor name="free_motor" joint="hinge"/>
  </actuator>
</mujoco>
"""


class CartPhysics(mujoco_physics.Physics):
    """A subclass as a suite domain writes one: derived state kept in _reload_from_data."""

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        self.pole_body = self.model.name2id("pole", "body")

    def pole_height(self):
        return self.named.data.xpos["pole", "z"]


def test_subclass_constructors_return_the_subclass_with_its_derived_state():
    physics = CartPhysics.from_xml_string(_XML)
    assert type(physics) is CartPhysics
    assert physics.pole_body == 2
    physics.reload_from_xml_string(_XML.replace('name="pole"', 'name="pole" pos="0 0 1"'))
    assert physics.pole_height() == pytest.approx(1.0)


def test_steps_match_raw_mj_step_on_the_same_model():
    physics = mujoco_physics.Physics.from_xml_string(_XML)
    model = mujoco.MjModel.from_xml_string(_XML)
    data = mujoco.MjData(model)
    with physics.reset_context():
        physics.named.data.qpos["hinge"] = 0.3
    data.qpos[1] = 0.3
    physics.legacy_step = False
    rng = np.random.default_rng(0)
    for _ in range(50):
        control = rng.uniform(-1, 1, 2)
        physics.set_control(control)
        data.ctrl[:] = control
        physics.step(3)
        mujoco.mj_step(model, data, 3)
    np.testing.assert_array_equal(physics.data.qpos, data.qpos)
    np.testing.assert_array_equal(physics.data.qvel, data.qvel)
    assert physics.time() == pytest.approx(1.5)


def test_model_and_data_are_dm_control_wrappers_around_the_raw_structs():
    physics = mujoco_physics.Physics.from_xml_string(_XML)
    assert isinstance(physics.model, wrapper.MjModel)
    assert isinstance(physics.data, wrapper.MjData)
    assert isinstance(physics.model.ptr, mujoco.MjModel)
    assert isinstance(physics.data.ptr, mujoco.MjData)
    assert physics.data.model.ptr is physics.model.ptr
    assert physics.model.name == "cart"


def test_named_indexing_reads_rows_by_object_name():
    physics = mujoco_physics.Physics.from_xml_string(_XML)
    physics.named.data.qpos["slider"] = 0.25
    physics.forward()
    assert physics.named.data.xpos["cart", "x"] == pytest.approx(0.25)
    np.testing.assert_array_equal(physics.named.model.actuator_ctrlrange["push"], [-1, 1])


def test_get_state_with_a_signature_round_trips_through_set_state():
    physics = mujoco_physics.Physics.from_xml_string(_XML)
    physics.named.data.qpos["hinge"] = 0.5
    physics.named.data.qvel["slider"] = -2.0
    signature = mujoco.mjtState.mjSTATE_QPOS | mujoco.mjtState.mjSTATE_QVEL
    state = physics.get_state(sig=signature)
    np.testing.assert_array_equal(state, [0, 0.5, -2.0, 0])
    physics.reset()
    physics.set_state(state, sig=signature)
    assert physics.named.data.qpos["hinge"] == 0.5
    with pytest.raises(ValueError, match=r"physics_state has shape \(3,\); expected \(4,\)"):
        physics.set_state(np.zeros(3), sig=signature)


def test_action_spec_is_bounded_by_ctrlrange_where_limited_and_mjmaxval_elsewhere():
    spec = mujoco_physics.action_spec(mujoco_physics.Physics.from_xml_string(_XML))
    assert isinstance(spec, specs.BoundedArray)
    assert spec.shape == (2,)
    np.testing.assert_array_equal(spec.minimum, [-1, -1e10])
    np.testing.assert_array_equal(spec.maximum, [1, 1e10])


def test_divergence_raises_physics_error_and_reset_context_recovers():
    physics = mujoco_physics.Physics.from_xml_string(_XML)
    physics.data.qvel[:] = np.inf
    with pytest.raises(mujoco_physics.PhysicsError, match=r"Warning\(s\) raised: mjWARN_BADQ"):
        physics.step()
    with physics.reset_context():
        pass
    physics.step()
    assert np.isfinite(physics.data.qpos).all()


def test_copy_has_the_state_and_is_independent():
    physics = mujoco_physics.Physics.from_xml_string(_XML)
    physics.named.data.qpos["hinge"] = 0.7
    copied = physics.copy()
    physics.named.data.qpos["hinge"] = 0.0
    assert copied.named.data.qpos["hinge"] == 0.7
    assert copied.model.ptr is not physics.model.ptr
    assert physics.copy(share_model=True).model.ptr is physics.model.ptr


def test_from_byte_string_loads_what_to_bytes_wrote():
    physics = mujoco_physics.Physics.from_xml_string(_XML)
    again = mujoco_physics.Physics.from_byte_string(physics.model.to_bytes())
    assert again.model.nq == 2
    np.testing.assert_array_equal(again.model.geom_size, physics.model.geom_size)


def test_contexts_are_none_before_rendering_and_upload_to_every_renderer_after():
    xml = """
    <mujoco>
      <asset><hfield name="terrain" nrow="4" ncol="4" size="1 1 0.5 0.1"/></asset>
      <worldbody>
        <geom type="hfield" hfield="terrain"/>
        <light pos="0 0 3"/>
        <camera name="top" pos="0 0 2.5"/>
      </worldbody>
    </mujoco>"""
    physics = mujoco_physics.Physics.from_xml_string(xml)
    assert physics.contexts is None
    flat = physics.render(32, 32, camera_id="top", depth=True)
    physics.render(16, 16, camera_id="top", depth=True)
    physics.model.hfield_data[:] = 1.0
    contexts = physics.contexts
    with contexts.gl.make_current() as ctx:
        ctx.call(mujoco.mjr_uploadHField, physics.model.ptr, contexts.mujoco.ptr, 0)
    raised = physics.render(32, 32, camera_id="top", depth=True)
    small = physics.render(16, 16, camera_id="top", depth=True)
    # The terrain rose by its elevation, 0.5: the camera at 2.5 sees it 0.5 closer.
    assert flat[16, 16] - raised[16, 16] == pytest.approx(0.5, abs=1e-3)
    assert small[8, 8] == pytest.approx(raised[16, 16], abs=1e-3)


def test_freed_physics_says_so_and_keeps_its_subclass():
    physics = CartPhysics.from_xml_string(_XML)
    physics.free()
    assert isinstance(physics, CartPhysics)
    with pytest.raises(AttributeError, match="this Physics was freed"):
        physics.step()


def test_repeated_reads_and_writes_by_a_list_of_names_follow_the_data():
    physics = mujoco_physics.Physics.from_xml_string(_XML)
    joints = ["hinge", "slider"]
    for value in (0.25, -0.5):
        physics.named.data.qpos[joints] = [value, 2 * value]
        np.testing.assert_array_equal(physics.named.data.qpos[joints], [value, 2 * value])
        np.testing.assert_array_equal(physics.data.qpos, [2 * value, value])
        np.testing.assert_array_equal(physics.named.data.qpos[["hinge"]], [value])
        np.testing.assert_array_equal(physics.named.data.qpos[joints[::-1]], [2 * value, value])
    with pytest.raises(KeyError, match="'qpos': no joint named 'elbow' in this model"):
        physics.named.data.qpos[["hinge", "elbow"]]
