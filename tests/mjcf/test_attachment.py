"""Attaching models: frames, scoping of names, defaults and assets, detaching, errors."""

import mujoco
import numpy as np
import pytest

import mjcf


def _arm(name="arm"):
    arm = mjcf.RootElement(model=name)
    arm.default.joint.damping = 2.0
    stiff = arm.default.add("default", dclass="stiff")
    stiff.joint.stiffness = 5.0
    arm.asset.add("material", name="skin", rgba=[0.2, 0.3, 0.4, 1])
    arm.worldbody.add("geom", name="base", size=[0.05], material="skin")
    upper = arm.worldbody.add("body", name="upper", pos=[0, 0, 0.1])
    shoulder = upper.add("joint", name="shoulder", axis=[0, 1, 0])
    upper.add("joint", name="twist", dclass="stiff", axis=[0, 0, 1])
    upper.add("geom", name="limb", type="capsule", size=[0.02, 0.1])
    upper.add("site", name="tip", pos=[0, 0, 0.2])
    arm.actuator.add("motor", name="drive", joint=shoulder)
    arm.sensor.add("jointpos", name="angle", joint="shoulder")
    return arm


def _compile(root):
    return mujoco.MjModel.from_xml_string(root.to_xml_string(), root.get_assets())


@pytest.fixture
def scene():
    arena = mjcf.RootElement(model="arena")
    arena.default.joint.damping = 100.0
    arena.worldbody.add("geom", name="floor", type="plane", size=[1, 1, 0.1])
    arena.worldbody.add("site", name="mount", pos=[0, 0, 0.5], quat=[0, 0, 0, 1])
    return arena


def test_attach_to_site_returns_frame_at_site_pose(scene):
    frame = scene.find("site", "mount").attach(_arm())
    assert frame.tag == "body"
    assert frame.spec.namespace == "body"
    np.testing.assert_array_equal(frame.pos, [0, 0, 0.5])
    np.testing.assert_array_equal(frame.quat, [0, 0, 0, 1])
    model = _compile(scene)
    np.testing.assert_allclose(model.body("arm/").pos, [0, 0, 0.5])


def test_attached_identifiers_are_scoped_by_model_name(scene):
    arm = _arm()
    scene.attach(arm)
    model = _compile(scene)
    assert model.joint("arm/shoulder").id >= 0
    assert model.actuator("arm/drive").id >= 0
    assert model.sensor("arm/angle").id >= 0
    assert model.material("arm/skin").id >= 0
    assert arm.find("joint", "shoulder").full_identifier == "arm/shoulder"


def test_full_identifier_matches_compiled_name_for_nested_attachments(scene):
    arm = _arm()
    hand = mjcf.RootElement(model="hand")
    finger = hand.worldbody.add("body", name="finger")
    finger.add("geom", size=[0.01])
    pinch = finger.add("site", name="pinch")
    arm.find("site", "tip").attach(hand)
    scene.attach(arm)
    assert pinch.full_identifier == "arm/hand/pinch"
    model = _compile(scene)
    assert model.site(pinch.full_identifier).id >= 0
    assert scene.find("site", "arm/hand/pinch") is pinch


def test_unnamed_elements_get_compiled_names(scene):
    arm = _arm()
    unnamed = arm.worldbody.add("geom", size=[0.01], pos=[0.3, 0, 0])
    frame = scene.attach(arm)
    free = frame.add("freejoint")
    model = _compile(scene)
    assert model.geom(unnamed.full_identifier).id >= 0
    assert model.joint(free.full_identifier).type == mujoco.mjtJoint.mjJNT_FREE
    assert unnamed.full_identifier != free.full_identifier


def test_child_defaults_apply_to_child_only(scene):
    scene.attach(_arm())
    own = scene.worldbody.add("body", name="own")
    own.add("joint", name="own_joint")
    own.add("geom", size=[0.1])
    model = _compile(scene)
    assert model.joint("arm/shoulder").damping == pytest.approx(2.0)
    assert model.joint("arm/twist").stiffness == pytest.approx(5.0)
    assert model.joint("arm/twist").damping == pytest.approx(2.0)
    assert model.joint("own_joint").damping == pytest.approx(100.0)


def test_frame_joints_use_parent_defaults(scene):
    frame = scene.attach(_arm())
    hinge = frame.add("joint", name="slide", type="slide")
    model = _compile(scene)
    assert model.joint(hinge.full_identifier).damping == pytest.approx(100.0)


def test_frame_accepts_only_joints_and_inertial(scene):
    frame = scene.attach(_arm())
    frame.add("inertial", mass=1, pos=[0, 0, 0])
    with pytest.raises(AttributeError, match="cannot have a child <geom>"):
        frame.add("geom")


def test_found_as_attachment_frame(scene):
    arm = _arm()
    frame = scene.attach(arm)
    assert scene.find("attachment_frame", "arm") is frame
    assert mjcf.get_attachment_frame(arm) is frame
    assert scene.find_all("attachment_frame") == [frame]
    assert frame.full_identifier == "arm/"


def test_find_all_sees_attached_elements_unless_excluded(scene):
    scene.attach(_arm())
    names = [j.full_identifier for j in scene.find_all("joint")]
    assert names == ["arm/shoulder", "arm/twist"]
    assert scene.find_all("joint", exclude_attachments=True) == []
    assert [a.full_identifier for a in scene.find_all("actuator")] == ["arm/drive"]


def test_find_all_in_a_section_includes_that_section_of_attached_models(scene):
    scene.actuator.add("motor", name="own", joint=scene.worldbody.add("body").add("joint"))
    scene.attach(_arm())
    assert [a.full_identifier for a in scene.actuator.find_all("actuator")] == ["own", "arm/drive"]
    assert [s.full_identifier for s in scene.sensor.find_all("sensor")] == ["arm/angle"]
    assert scene.actuator.find_all("actuator", exclude_attachments=True) == [
        scene.find("actuator", "own")
    ]


def test_find_all_default_leaves_out_attached_models_classes(scene):
    scene.attach(_arm())
    assert [d.dclass for d in scene.find_all("default")] == [None]


def test_frame_and_sections_list_the_attached_models_elements(scene):
    arm = _arm()
    frame = scene.attach(arm)
    assert frame in scene.worldbody.all_children()
    assert frame.all_children() == arm.worldbody.all_children()
    assert frame.all_children()
    for element in arm.actuator.all_children():
        assert element in scene.actuator.all_children()
    assert arm.find("joint", "twist") not in scene.worldbody.all_children()


def test_section_text_includes_attached_models_section(scene):
    arm = _arm()
    scene.attach(arm)
    text = scene.actuator.to_xml_string(pretty_print=False)
    assert text.startswith("<actuator>") and 'name="arm/' in text
    default_text = scene.default.to_xml_string(pretty_print=False)
    assert default_text.startswith('<default><default class="/"')
    assert '<default class="arm/"' in default_text


def test_frame_below_a_body_cannot_hold_a_freejoint(scene):
    frame = scene.worldbody.add("body", name="holder").attach(_arm())
    with pytest.raises(AttributeError):
        frame.add("freejoint")
    frame.add("joint", type="hinge")


def test_references_across_models_by_element_and_scoped_name(scene):
    arm = _arm()
    scene.attach(arm)
    scene.actuator.add("position", name="p1", joint=arm.find("joint", "twist"))
    scene.sensor.add("framepos", name="tip", objtype="site", objname="arm/tip")
    model = _compile(scene)
    assert model.actuator("p1").trnid[0] == model.joint("arm/twist").id
    assert model.sensor("tip").objid == model.site("arm/tip").id


def test_gripper_child_references_resolve_within_its_own_scope(scene):
    arm = _arm()
    arm.worldbody.add("geom", name="floor", size=[0.01], material="skin")
    scene.attach(arm)
    model = _compile(scene)
    assert model.geom("arm/floor").matid == model.material("arm/skin").id


def test_attaching_same_model_twice_is_an_error(scene):
    arm = _arm()
    scene.attach(arm)
    with pytest.raises(ValueError, match="already attached"):
        scene.attach(arm)


def test_attaching_model_to_itself_is_an_error():
    arm = _arm()
    with pytest.raises(ValueError, match="cannot be attached to itself"):
        arm.attach(arm)


def test_attaching_parent_below_its_child_is_an_error(scene):
    arm = _arm()
    scene.attach(arm)
    with pytest.raises(ValueError, match="attached below"):
        arm.find("site", "tip").attach(scene)


def test_models_with_the_same_name_are_renamed_with_a_suffix_on_attach(scene):
    first, second, third = _arm("arm"), _arm("arm"), _arm("arm")
    for arm in (first, second, third):
        scene.attach(arm)
    assert [first.model, second.model, third.model] == ["arm", "arm_1", "arm_2"]
    compiled = mujoco.MjModel.from_xml_string(scene.to_xml_string(), scene.get_assets())
    for prefix in ("arm/", "arm_1/", "arm_2/"):
        assert mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_BODY, prefix) >= 0


def test_renaming_an_attached_model_to_a_sibling_name_is_an_error(scene):
    scene.attach(_arm("left"))
    right = _arm("right")
    scene.attach(right)
    with pytest.raises(ValueError, match="duplicate identifier.*'left'"):
        right.model = "left"


def test_unnamed_frame_joint_is_named_after_its_frame(scene):
    arm = _arm("arm")
    frame = scene.attach(arm)
    first = frame.add("joint", type="slide")
    second = frame.add("joint", type="hinge")
    assert first.full_identifier == "arm/"
    assert scene.find("joint", "arm/") is first
    compiled = mujoco.MjModel.from_xml_string(scene.to_xml_string(), scene.get_assets())
    assert mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_JOINT, "arm/") >= 0
    assert mujoco.mj_name2id(compiled, mujoco.mjtObj.mjOBJ_JOINT, second.full_identifier) >= 0


def test_frame_freejoint_reads_through_named_indexing_by_the_frame_name(scene):
    arm = _arm("arm")
    scene.attach(arm).add("freejoint")
    physics = mjcf.Physics.from_mjcf_model(scene)
    assert physics.named.data.qpos["arm/"].shape == (7,)


def test_conflicting_global_options_are_an_error(scene):
    scene.compiler.angle = "radian"
    arm = _arm()
    arm.compiler.angle = "degree"
    with pytest.raises(ValueError, match="global option <compiler> 'angle'"):
        scene.attach(arm)


def test_child_global_option_applies_when_parent_leaves_it_unset(scene):
    arm = _arm()
    arm.option.timestep = 0.005
    scene.attach(arm)
    assert _compile(scene).opt.timestep == pytest.approx(0.005)


def test_cannot_attach_to_a_geom(scene):
    with pytest.raises(ValueError, match="only be attached to a site, a body or the worldbody"):
        scene.find("geom", "floor").attach(_arm())


def test_detach_removes_child_and_allows_reattaching(scene):
    arm = _arm()
    scene.attach(arm)
    arm.detach()
    assert mjcf.get_attachment_frame(arm) is None
    assert scene.find("joint", "arm/shoulder") is None
    assert "arm/" not in scene.to_xml_string()
    scene.find("site", "mount").attach(arm)
    assert _compile(scene).joint("arm/shoulder").id >= 0


def test_detaching_unattached_model_is_an_error():
    with pytest.raises(RuntimeError, match="not attached"):
        _arm().detach()


def test_changes_in_attached_model_bump_parent_modification_count(scene):
    arm = _arm()
    scene.attach(arm)
    before = scene.modification_count
    arm.find("geom", "limb").rgba = [1, 0, 0, 1]
    assert scene.modification_count > before
    before = scene.modification_count
    arm.detach()
    assert scene.modification_count > before


def test_renaming_attached_model_rescopes_its_names(scene):
    arm = _arm()
    scene.attach(arm)
    arm.model = "left"
    assert arm.find("joint", "shoulder").full_identifier == "left/shoulder"
    assert _compile(scene).joint("left/shoulder").id >= 0


def test_parent_and_root_model_links(scene):
    arm = _arm()
    hand = mjcf.RootElement(model="hand")
    arm.attach(hand)
    scene.attach(arm)
    assert hand.parent_model is arm
    assert hand.root_model is scene
    assert hand.find("joint", "x") is None
    assert arm.find("joint", "shoulder").root is arm


def test_every_full_identifier_finds_its_element(scene):
    arm = _arm()
    arm.worldbody.add("geom", size=[0.01])
    frame = scene.attach(arm)
    free = frame.add("freejoint")
    scene.worldbody.add("site")
    elements = scene.find_all("geom") + scene.find_all("joint") + scene.find_all("site")
    for element in elements + [free]:
        assert scene.find(element.spec.namespace, element.full_identifier) is element
    assert scene.find("body", frame.full_identifier) is frame


def test_enter_scope_returns_attached_model(scene):
    arm = _arm()
    hand = mjcf.RootElement(model="hand")
    arm.attach(hand)
    scene.attach(arm)
    assert scene.enter_scope("arm") is arm
    assert scene.enter_scope("arm/hand") is hand
    assert scene.enter_scope("leg") is None


def test_keyframes_of_attached_models_are_merged_with_scoped_names(scene):
    arm = _arm()
    arm.keyframe.add("key", name="rest", time=2.0)
    scene.keyframe.add("key", name="rest", time=1.0)
    scene.attach(arm)
    model = _compile(scene)
    assert model.key("rest").time[0] == 1.0
    assert model.key("arm/rest").time[0] == 2.0


def test_removing_a_body_detaches_models_attached_inside_it(scene):
    holder = scene.worldbody.add("body", name="holder")
    holder.add("geom", size=[0.1])
    site = holder.add("site", name="slot")
    arm = _arm()
    site.attach(arm)
    holder.remove()
    assert mjcf.get_attachment_frame(arm) is None
    assert scene.find_all("joint") == []
    scene.attach(arm)
    assert _compile(scene).joint("arm/shoulder").id >= 0


def test_skin_bones_follow_the_scoped_body_names(scene):
    from mjcf_test_files import triangle_skin

    creature = mjcf.RootElement(model="creature")
    torso = creature.worldbody.add("body", name="torso")
    torso.add("geom", size=[0.1])
    creature.deformable.add("skin", name="hide", file=mjcf.Asset(triangle_skin("torso"), ".skn"))
    scene.attach(creature)
    model = _compile(scene)
    assert model.skin_bonebodyid[0] == model.body("creature/torso").id
    alone = _compile(creature)
    assert alone.skin_bonebodyid[0] == alone.body("torso").id


def test_root_full_identifier_is_its_scope_prefix(scene):
    arm = _arm("arm")
    hand = _arm("hand")
    scene.attach(arm)
    arm.attach(hand)
    assert scene.full_identifier == ""
    assert arm.full_identifier == "arm/"
    assert hand.full_identifier == "arm/hand/"


def test_frames_may_hold_joints_of_the_same_name_scoped_by_frame():
    scene = mjcf.RootElement(model="scene")
    left = mjcf.RootElement(model="left")
    right = mjcf.RootElement(model="right")
    for model in (left, right):
        model.worldbody.add("geom", size=[0.1])
    joint_left = scene.attach(left).add("joint", name="slide", type="slide")
    joint_right = scene.attach(right).add("joint", name="slide", type="slide")
    assert joint_left.full_identifier == "left/slide/"
    assert scene.find("joint", "right/slide/") is joint_right
    scene.actuator.add("position", name="push", joint=joint_right)
    physics = mjcf.Physics.from_mjcf_model(scene)
    assert physics.model.joint("right/slide/").id == physics.bind(joint_right).element_id
    assert physics.model.actuator("push").trnid[0] == physics.bind(joint_right).element_id


def test_attaching_merges_buffer_sizes_taking_the_larger():
    parent = mjcf.RootElement()
    parent.size.nconmax = 100
    parent.size.memory = "10000"
    child = mjcf.RootElement(model="child")
    child.size.nconmax = 300
    child.size.njmax = 50
    child.size.memory = "1M"
    parent.attach(child)
    assert parent.size.nconmax == 300
    assert parent.size.njmax == 50
    assert parent.size.memory == "1048576"
    assert '<size nconmax="300" memory="1048576" njmax="50"/>' in parent.to_xml_string()


def test_attaching_merges_time_step_taking_the_smaller():
    parent = mjcf.RootElement()
    parent.option.timestep = 0.002
    child = mjcf.RootElement(model="child")
    child.option.timestep = 0.001
    parent.attach(child)
    assert parent.option.timestep == 0.001
    assert mjcf.Physics.from_mjcf_model(parent).model.opt.timestep == 0.001


def test_memory_with_unknown_unit_is_rejected_when_merging():
    parent = mjcf.RootElement()
    parent.size.memory = "10X"
    child = mjcf.RootElement(model="child")
    child.size.memory = "1M"
    with pytest.raises(ValueError, match="memory"):
        parent.attach(child)


def test_section_lists_show_attached_models_elements_after_own(scene):
    arm = _arm()
    scene.actuator.add("motor", name="own", joint=scene.worldbody.add("body").add("joint"))
    scene.attach(arm)
    motors = scene.actuator.motor
    assert [m.name for m in motors] == ["own", "drive"]
    assert motors["arm/drive"] is arm.actuator.motor["drive"]
    with pytest.raises(KeyError):
        motors["arm/missing"]
    assert len(scene.worldbody.body) == 1 + 1  # its own body and the attachment frame
