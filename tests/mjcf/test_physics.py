"""Tests for mjcf.Physics: construction, stepping, resets, errors, state and copies."""

import copy
import logging
import pickle
import re

import mujoco
import numpy as np
import pytest

import mjcf
from mjcf.physics import Physics, PhysicsError

_XML = """
<mujoco model="pendulums">
  <option timestep="0.005" integrator="{integrator}"/>
  <worldbody>
    <geom name="floor" type="plane" size="5 5 .1"/>
    <body name="ball_body" pos="0 0 1">
      <freejoint name="free"/>
      <geom name="ball" size="0.1"/>
    </body>
    <body name="arm" pos="1 0 1">
      <joint name="hinge" type="hinge" axis="0 1 0" damping="0.01"/>
      <geom name="upper" type="capsule" fromto="0 0 0 0.3 0 0" size="0.04"/>
      <body name="forearm" pos="0.3 0 0">
        <joint name="ball_joint" type="ball"/>
        <geom name="lower" type="capsule" fromto="0 0 0 0.3 0 0" size="0.03"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="hinge_motor" joint="hinge" gear="2"/>
    <general name="filtered" joint="hinge" dyntype="filter" dynprm="0.1"/>
  </actuator>
  <keyframe>
    <key name="bent" qpos="0 0 2 1 0 0 0 0.5 1 0 0 0" ctrl="1 0"/>
  </keyframe>
</mujoco>
"""


def _xml(integrator="Euler"):
    return _XML.format(integrator=integrator)


@pytest.fixture
def physics():
    return Physics.from_xml_string(_xml())


def _body_id(physics, name):
    return mujoco.mj_name2id(physics.model.ptr, mujoco.mjtObj.mjOBJ_BODY, name)


def test_physics_and_error_are_exported_from_mjcf():
    assert mjcf.Physics is Physics
    assert mjcf.PhysicsError is PhysicsError


def test_from_xml_string_compiles_the_model():
    physics = Physics.from_xml_string(_xml())
    assert physics.model.nbody == 4
    assert physics.model.njnt == 3
    assert physics.model.nu == 2


def test_from_xml_string_resolves_files_from_assets():
    xml = '<mujoco><include file="part.xml"/></mujoco>'
    part = b'<mujoco><worldbody><geom name="from_asset" size="1"/></worldbody></mujoco>'
    physics = Physics.from_xml_string(xml, assets={"part.xml": part})
    assert physics.model.name2id("from_asset", "geom") == 0


def test_from_xml_path_loads_a_file(tmp_path):
    path = tmp_path / "model.xml"
    path.write_text(_xml())
    assert Physics.from_xml_path(str(path)).model.nq == 12


def test_from_binary_path_loads_an_mjb_file(tmp_path):
    path = tmp_path / "model.mjb"
    mujoco.mj_saveModel(mujoco.MjModel.from_xml_string(_xml()), str(path), None)
    assert Physics.from_binary_path(str(path)).model.nv == 10


def test_from_byte_string_loads_mjb_bytes():
    model = mujoco.MjModel.from_xml_string(_xml())
    buffer = np.zeros(mujoco.mj_sizeModel(model), np.uint8)
    mujoco.mj_saveModel(model, None, buffer)
    physics = Physics.from_byte_string(buffer.tobytes())
    assert physics.model.nv == 10
    np.testing.assert_array_equal(physics.model.body_pos, model.body_pos)


def test_from_byte_string_of_other_bytes_names_the_argument():
    with pytest.raises(ValueError, match="byte_string .11 bytes. is not a MuJoCo model binary"):
        Physics.from_byte_string(b"<mujoco/>\n\n")


def test_from_model_uses_the_given_model():
    model = mujoco.MjModel.from_xml_string(_xml())
    physics = Physics.from_model(model)
    assert physics.model.ptr is model
    assert isinstance(physics.data.ptr, mujoco.MjData)


def test_construction_computes_positions(physics):
    np.testing.assert_allclose(physics.data.xpos[_body_id(physics, "ball_body")], [0, 0, 1])


def test_legacy_step_leaves_positions_in_sync_with_qpos(physics):
    physics.step(10)
    body = _body_id(physics, "ball_body")
    np.testing.assert_array_equal(physics.data.xpos[body], physics.data.qpos[:3])


def test_plain_step_leaves_positions_one_step_behind_qpos(physics):
    physics.legacy_step = False
    physics.step(10)
    body = _body_id(physics, "ball_body")
    assert physics.data.xpos[body][2] > physics.data.qpos[2]


def test_legacy_step_follows_the_same_trajectory_as_mj_step(physics):
    model = physics.model.ptr
    reference = mujoco.MjData(model)
    reference.ctrl[:] = physics.data.ctrl[:] = [0.3, 0.5]
    for _ in range(20):
        mujoco.mj_step(model, reference)
    physics.step(20)
    np.testing.assert_array_equal(physics.data.qpos, reference.qpos)
    np.testing.assert_array_equal(physics.data.act, reference.act)


def test_plain_step_matches_mj_step(physics):
    physics.legacy_step = False
    model = physics.model.ptr
    reference = mujoco.MjData(model)
    mujoco.mj_forward(model, reference)
    physics.step(7)
    for _ in range(7):
        mujoco.mj_step(model, reference)
    np.testing.assert_array_equal(physics.data.qpos, reference.qpos)


@pytest.mark.parametrize("integrator", ["Euler", "RK4", "implicitfast"])
@pytest.mark.parametrize("legacy_step", [True, False])
def test_step_in_one_chunk_equals_single_steps(integrator, legacy_step):
    chunked = Physics.from_xml_string(_xml(integrator))
    single = Physics.from_xml_string(_xml(integrator))
    for physics in (chunked, single):
        physics.legacy_step = legacy_step
        physics.set_control([0.4, -0.2])
    chunked.step(150)  # long enough for the ball to land: contacts are included
    for _ in range(150):
        single.step()
    assert single.data.ncon > 0
    np.testing.assert_array_equal(chunked.data.qpos, single.data.qpos)
    np.testing.assert_array_equal(chunked.data.qvel, single.data.qvel)
    np.testing.assert_array_equal(chunked.data.xpos, single.data.xpos)


@pytest.mark.parametrize("nstep", [2, 3])
def test_legacy_step_of_a_few_steps_advances_exactly_that_many(physics, nstep):
    model = physics.model.ptr
    reference = mujoco.MjData(model)
    reference.qvel[:] = physics.data.qvel[:] = 0.5
    physics.forward()  # a legacy step continues from the last forward pass
    mujoco.mj_step(model, reference, nstep)
    physics.step(nstep)
    assert physics.time() == reference.time
    np.testing.assert_array_equal(physics.data.qpos, reference.qpos)
    np.testing.assert_array_equal(physics.data.qvel, reference.qvel)


def test_step_advances_time_by_nstep_timesteps(physics):
    physics.step(4)
    assert physics.time() == pytest.approx(4 * 0.005)


def test_timestep_reads_the_model_option(physics):
    assert physics.timestep() == 0.005


def test_forward_updates_positions_after_a_qpos_write(physics):
    physics.data.qpos[:3] = [2, 3, 4]
    physics.forward()
    np.testing.assert_array_equal(physics.data.xpos[_body_id(physics, "ball_body")], [2, 3, 4])


def test_mark_as_dirty_makes_bindings_recompute_positions():
    root = mjcf.from_xml_string(_xml())
    physics = Physics.from_mjcf_model(root)
    ball_body = root.find("body", "ball_body")
    np.testing.assert_array_equal(physics.bind(ball_body).xpos, [0, 0, 1])
    physics.data.qpos[:3] = [4, 5, 6]  # a direct write: the binding cannot see it
    physics.mark_as_dirty()
    assert physics.is_dirty is True
    np.testing.assert_array_equal(physics.bind(ball_body).xpos, [4, 5, 6])


def test_reset_restores_the_initial_state(physics):
    physics.step(50)
    physics.reset()
    assert physics.time() == 0
    np.testing.assert_array_equal(physics.data.qpos, physics.model.qpos0)


def test_reset_to_keyframe_loads_its_qpos(physics):
    physics.reset(keyframe_id=0)
    np.testing.assert_array_equal(physics.data.qpos, physics.model.key_qpos[0])


def test_reset_runs_forward_without_actuation(physics):
    physics.reset(keyframe_id=0)
    assert physics.data.ctrl[0] == 1
    assert not physics.data.qfrc_actuator.any()


def test_reset_rejects_a_missing_keyframe(physics):
    with pytest.raises(ValueError, match="keyframe_id 3"):
        physics.reset(keyframe_id=3)


def test_reset_rejects_the_keyframe_id_one_past_the_last(physics):
    with pytest.raises(ValueError) as raised:
        physics.reset(keyframe_id=1)  # the model has one keyframe, id 0
    assert str(raised.value) == "keyframe_id 1 is out of range: expected 0 to 0"


def test_reset_context_keeps_the_state_set_inside_and_updates_positions(physics):
    physics.step(10)
    with physics.reset_context() as yielded:
        assert yielded is physics
        physics.data.qpos[:3] = [0, 2, 5]
    assert physics.time() == 0
    np.testing.assert_array_equal(physics.data.xpos[_body_id(physics, "ball_body")], [0, 2, 5])


def test_reset_context_propagates_errors_raised_inside(physics):
    with pytest.raises(KeyError):
        with physics.reset_context():
            raise KeyError("from the block")


def test_after_reset_updates_positions(physics):
    physics.data.qpos[:3] = [1, 1, 1]
    physics.after_reset()
    np.testing.assert_array_equal(physics.data.xpos[_body_id(physics, "ball_body")], [1, 1, 1])


def test_step_raises_physics_error_on_divergence(physics):
    physics.data.qvel[0] = np.nan
    with pytest.raises(PhysicsError, match="Physics state is invalid.*mjWARN_BADQ"):
        physics.step()


def test_suppress_physics_errors_logs_instead_of_raising(physics, caplog):
    physics.data.qvel[0] = np.nan
    with caplog.at_level(logging.WARNING):
        with physics.suppress_physics_errors():
            physics.step()
    assert "mjWARN_BADQ" in caplog.text


def test_suppress_physics_errors_is_undone_after_the_block(physics):
    with physics.suppress_physics_errors():
        pass
    physics.data.qvel[0] = np.nan
    with pytest.raises(PhysicsError):
        physics.step()


def test_check_invalid_state_raises_for_warnings_inside_the_block(physics):
    physics.data.qpos[0] = np.nan
    with pytest.raises(PhysicsError, match="mjWARN_BADQPOS"):
        with physics.check_invalid_state():
            mujoco.mj_step(physics.model.ptr, physics.data.ptr)


def test_set_control_writes_the_controls(physics):
    physics.set_control([0.25, -0.5])
    np.testing.assert_array_equal(physics.data.ctrl, [0.25, -0.5])


def test_control_returns_a_copy(physics):
    physics.set_control([1, 2])
    control = physics.control()
    control[:] = 0
    np.testing.assert_array_equal(physics.data.ctrl, [1, 2])


def test_get_state_is_qpos_qvel_act(physics):
    physics.set_control([0.3, 0.7])
    physics.step(5)
    data = physics.data
    expected = np.concatenate([data.qpos, data.qvel, data.act])
    np.testing.assert_array_equal(physics.get_state(), expected)
    np.testing.assert_array_equal(physics.state(), expected)


def test_set_state_restores_a_saved_state(physics):
    physics.set_control([0.3, 0.7])
    physics.step(5)
    saved = physics.get_state()
    qpos = physics.data.qpos.copy()
    act = physics.data.act.copy()
    physics.step(20)
    physics.set_state(saved)
    np.testing.assert_array_equal(physics.data.qpos, qpos)
    np.testing.assert_array_equal(physics.data.act, act)


def test_set_state_rejects_a_wrong_size(physics):
    with pytest.raises(ValueError) as raised:
        physics.set_state(np.zeros(5))
    assert str(raised.value) == (
        "physics_state has shape (5,); expected (23,) (qpos, qvel, act, ...)"
    )


def test_set_state_accepts_a_list_of_ints(physics):
    state = [0] * 23
    state[2] = 3  # ball height (qpos)
    state[12] = 2  # ball x velocity (qvel)
    physics.set_state(state)
    np.testing.assert_array_equal(physics.data.qpos[:4], [0, 0, 3, 0])
    assert physics.data.qvel[0] == 2.0


def test_copy_starts_from_the_same_state(physics):
    physics.step(5)
    copied = physics.copy()
    np.testing.assert_array_equal(copied.data.qpos, physics.data.qpos)
    assert copied.time() == physics.time()


def test_copy_steps_independently(physics):
    copied = physics.copy()
    copied.step(10)
    assert physics.time() == 0
    assert copied.time() > 0


def test_copy_copies_the_model_by_default(physics):
    copied = physics.copy()
    copied.model.geom_rgba[0] = [0, 0, 0, 0]
    assert physics.model.geom_rgba[0, 3] != 0


def test_copy_can_share_the_model(physics):
    assert physics.copy(share_model=True).model.ptr is physics.model.ptr


def _slider_model():
    root = mjcf.RootElement(model="slider")
    body = root.worldbody.add("body", name="cart")
    body.add("joint", name="rail", type="slide", axis=[1, 0, 0])
    body.add("geom", size=[0.1])
    return root


def test_pickled_physics_continues_the_same_trajectory(physics):
    physics.data.qvel[:] = 0.3
    physics.step(7)
    restored = pickle.loads(pickle.dumps(physics))
    assert restored.time() == physics.time()
    physics.step(20)
    restored.step(20)
    np.testing.assert_array_equal(restored.data.qpos, physics.data.qpos)
    assert restored.named.data.qpos["hinge"] == physics.named.data.qpos["hinge"]


def test_physics_pickled_with_its_mjcf_model_binds_the_unpickled_elements():
    root = _slider_model()
    physics = mjcf.Physics.from_mjcf_model(root)
    physics.bind(root.find("joint", "rail")).qpos = 0.25
    root_again, physics_again = pickle.loads(pickle.dumps((root, physics)))
    assert physics_again.bind(root_again.find("joint", "rail")).qpos == 0.25


def test_deep_copied_physics_after_binding_has_its_own_data_and_elements():
    root = _slider_model()
    physics = mjcf.Physics.from_mjcf_model(root)
    rail = root.find("joint", "rail")
    physics.bind(rail).qpos = 0.25
    copied = copy.deepcopy(physics)
    copied.named.data.qpos["rail"] = 0.75
    assert physics.bind(rail).qpos == 0.25
    with pytest.raises(ValueError, match="copy.deepcopy binds its own elements"):
        copied.bind(rail)


def test_unpickled_physics_keeps_legacy_step_off(physics):
    physics.legacy_step = False
    assert pickle.loads(pickle.dumps(physics)).legacy_step is False


def test_free_makes_the_physics_unusable(physics):
    physics.free()
    with pytest.raises(AttributeError, match="was freed"):
        physics.step()
    with pytest.raises(AttributeError, match="was freed"):
        physics.set_control([0.0])
    physics.free()
    assert isinstance(physics, Physics)


def test_free_drops_named_indexing_and_bindings_with_a_clear_error():
    root = mjcf.from_xml_string(_xml())
    physics = Physics.from_mjcf_model(root)
    geoms = root.find_all("geom")
    _ = physics.named.data.qpos, physics.bind(geoms).xpos
    physics.free()
    with pytest.raises(AttributeError, match="^this Physics was freed"):
        _ = physics.named
    with pytest.raises(AttributeError, match="^this Physics was freed"):
        physics.bind(geoms[:2])
    with pytest.raises(AttributeError, match="^this Physics was freed"):
        physics.bind(geoms[0])


def test_a_missing_attribute_of_a_live_physics_is_named(physics):
    with pytest.raises(AttributeError, match="^'Physics' object has no attribute 'colour'$"):
        _ = physics.colour


def _arm_model():
    root = mjcf.RootElement(model="scene")
    arm = mjcf.RootElement(model="arm")
    link = arm.worldbody.add("body", name="link")
    link.add("joint", name="elbow", type="hinge", range=[1, -1], limited=True)
    link.add("geom", name="link_geom", size=[0.1])
    root.worldbody.attach(arm)
    return root


def test_from_mjcf_model_compiles_attached_models():
    root = mjcf.RootElement(model="scene")
    arm = mjcf.RootElement(model="arm")
    arm.worldbody.add("body", name="link").add("geom", name="link_geom", size=[0.1])
    root.worldbody.attach(arm)
    physics = Physics.from_mjcf_model(root)
    assert physics.model.name2id("arm/link_geom", "geom") >= 0


def test_from_mjcf_model_error_names_the_offending_element():
    with pytest.raises(ValueError) as raised:
        Physics.from_mjcf_model(_arm_model())
    assert "'arm/elbow'" in str(raised.value)
    assert '<joint name="arm/elbow"' in str(raised.value)


def test_from_mjcf_model_error_keeps_mujocos_message():
    with pytest.raises(ValueError, match="range"):
        Physics.from_mjcf_model(_arm_model())


def test_reload_from_mjcf_model_recompiles():
    physics = Physics.from_xml_string(_xml())
    root = mjcf.RootElement(model="small")
    root.worldbody.add("geom", name="only", size=[1])
    physics.reload_from_mjcf_model(root)
    assert physics.model.ngeom == 1


def test_mujoco_warnings_go_to_logging_not_to_a_log_file(tmp_path, monkeypatch, caplog):
    monkeypatch.chdir(tmp_path)
    physics = mjcf.Physics.from_xml_string(
        "<mujoco><worldbody><body><joint/><geom size='1'/></body></worldbody></mujoco>"
    )
    physics.data.qvel[:] = np.nan
    with caplog.at_level("WARNING"), physics.suppress_physics_errors():
        physics.step()
    messages = [record.getMessage() for record in caplog.records]
    assert any(
        message.startswith("MuJoCo warning: Nan, Inf or huge value in Q") and message.endswith(".")
        for message in messages
    ), messages
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


def test_warnings_raised_together_are_all_named():
    physics = Physics.from_xml_string(_xml())
    with pytest.raises(PhysicsError) as raised:
        with physics.check_invalid_state():
            physics.data.qpos[0] = np.nan
            mujoco.mj_step(physics.model.ptr, physics.data.ptr)  # resets the data
            physics.data.ctrl[0] = np.nan
            mujoco.mj_step(physics.model.ptr, physics.data.ptr)  # zeroes the control
    assert str(raised.value) == (
        "Physics state is invalid. Warning(s) raised: mjWARN_BADQPOS, mjWARN_BADCTRL"
    )


def test_constructor_accepts_a_data_wrapper(physics):
    physics.step(3)
    twin = Physics(physics.data)
    assert twin.data.ptr is physics.data.ptr
    assert twin.time() == pytest.approx(3 * 0.005)


def test_from_model_accepts_a_model_wrapper(physics):
    assert Physics.from_model(physics.model).model.ptr is physics.model.ptr


def test_bind_none_error_in_full(physics):
    with pytest.raises(ValueError) as raised:
        physics.bind(None)
    assert str(raised.value) == "bind expects an mjcf element or a sequence of them, got None"


def test_bind_of_a_non_sequence_error_names_its_type(physics):
    with pytest.raises(ValueError) as raised:
        physics.bind(5)
    assert str(raised.value) == "bind expects an mjcf element or a sequence of them, got int"


def test_binding_a_generator_after_a_list_returns_the_cached_binding():
    root = mjcf.from_xml_string(_xml())
    physics = Physics.from_mjcf_model(root)
    geoms = root.find_all("geom")[:2]
    first = physics.bind(geoms)
    assert physics.bind(geom for geom in geoms) is first


def test_forward_raises_when_mujoco_warns(physics):
    physics.data.ctrl[0] = np.nan
    with pytest.raises(PhysicsError) as raised:
        physics.forward()
    assert str(raised.value) == "Physics state is invalid. Warning(s) raised: mjWARN_BADCTRL"


def test_construction_logs_a_warning_raised_by_its_first_forward(caplog):
    # Six overlapping free spheres make more constraints than 16 KB of arena memory holds.
    bodies = "<body><freejoint/><geom size='1'/></body>" * 6
    xml = f"<mujoco model='crowd'><size memory='16K'/><worldbody>{bodies}</worldbody></mujoco>"
    try:
        with caplog.at_level(logging.WARNING):
            Physics.from_xml_string(xml)
    except PhysicsError as error:
        # mujoco 3.17 aborts that forward (FatalError) instead of warning.
        assert str(error).startswith(
            "MuJoCo could not run the first forward of the model 'crowd': "
        )
        assert isinstance(error.__cause__, mujoco.FatalError)
        return
    messages = [record.getMessage() for record in caplog.records]
    # mujoco 3.3 names the full arena after contacts, 4.0 after constraints.
    expected = r"Physics state is invalid\. Warning\(s\) raised: mjWARN_(CNSTR|CONTACT)FULL"
    assert any(re.fullmatch(expected, message) for message in messages)


def test_construction_turns_an_aborted_first_forward_into_a_physics_error_naming_the_model(
    monkeypatch,
):
    def aborting_forward(model, data):
        raise mujoco.FatalError("mj_stackAlloc: out of memory, stack overflow")

    model = mujoco.MjModel.from_xml_string("<mujoco model='cramped'/>")
    monkeypatch.setattr(mujoco, "mj_forward", aborting_forward)
    with pytest.raises(PhysicsError) as raised:
        Physics.from_model(model)
    assert str(raised.value) == (
        "MuJoCo could not run the first forward of the model 'cramped': mj_stackAlloc: out of "
        "memory, stack overflow (a model that needs more memory than <size memory=...> gives "
        "fails here)"
    )


def test_is_dirty_is_false_after_forward_and_on_copies(physics):
    physics.mark_as_dirty()
    physics.forward()
    assert physics.is_dirty is False
    assert physics.copy().is_dirty is False
    assert pickle.loads(pickle.dumps(physics)).is_dirty is False
