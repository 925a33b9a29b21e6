"""RootElement.attribute_changes_since: which attribute values changed since a count."""

import pytest

import mjcf


@pytest.fixture
def model():
    root = mjcf.RootElement(model="scene")
    body = root.worldbody.add("body", name="body")
    body.add("geom", name="ball", type="sphere", size=[0.1])
    root.default.add("default", dclass="heavy").geom.density = 3000
    return root


def test_nothing_changed_gives_an_empty_record(model):
    assert model.attribute_changes_since(model.modification_count) == ()


def test_setting_values_names_each_element_and_attribute_once(model):
    ball = model.find("geom", "ball")
    count = model.modification_count
    ball.rgba = [1, 0, 0, 1]
    ball.friction = [0.5, 0.01, 0.001]
    ball.rgba = [0, 1, 0, 1]
    assert model.attribute_changes_since(count) == ((ball, "friction"), (ball, "rgba"))


def test_changes_before_the_count_are_left_out(model):
    ball = model.find("geom", "ball")
    ball.rgba = [1, 0, 0, 1]
    count = model.modification_count
    ball.friction = [0.5, 0.01, 0.001]
    assert model.attribute_changes_since(count) == ((ball, "friction"),)


def test_in_place_writes_unsetting_and_set_attributes_are_recorded(model):
    ball = model.find("geom", "ball")
    ball.rgba = [1, 0, 0, 1]
    count = model.modification_count
    ball.rgba[0] = 0.5
    del ball.size
    ball.set_attributes(margin=0.01, gap=0.001)
    assert set(model.attribute_changes_since(count)) == {
        (ball, "rgba"),
        (ball, "size"),
        (ball, "margin"),
        (ball, "gap"),
    }


def test_a_default_class_template_change_is_recorded_on_the_template(model):
    template = model.find("default", "heavy").geom
    count = model.modification_count
    template.density = 500
    assert model.attribute_changes_since(count) == ((template, "density"),)


@pytest.mark.parametrize(
    "change",
    [
        lambda root: root.worldbody.add("site", name="marker"),
        lambda root: root.find("body", "body").remove(),
        lambda root: root.attach(mjcf.RootElement(model="child")),
    ],
    ids=["add", "remove", "attach"],
)
def test_a_structural_change_gives_none(model, change):
    count = model.modification_count
    model.find("geom", "ball").rgba = [1, 0, 0, 1]
    change(model)
    assert model.attribute_changes_since(count) is None


def test_values_after_a_structural_change_are_recorded_again(model):
    model.worldbody.add("site", name="marker")
    count = model.modification_count
    ball = model.find("geom", "ball")
    ball.rgba = [1, 0, 0, 1]
    assert model.attribute_changes_since(count) == ((ball, "rgba"),)


def test_changes_in_an_attached_model_reach_the_parent(model):
    child = mjcf.RootElement(model="child")
    arm = child.worldbody.add("geom", name="arm", type="sphere", size=[0.05])
    model.attach(child)
    parent_count, child_count = model.modification_count, child.modification_count
    arm.rgba = [0, 0, 1, 1]
    assert model.attribute_changes_since(parent_count) == ((arm, "rgba"),)
    assert child.attribute_changes_since(child_count) == ((arm, "rgba"),)


def test_a_count_from_the_future_gives_none(model):
    assert model.attribute_changes_since(model.modification_count + 1) is None


def test_a_freshly_parsed_model_has_no_recorded_changes():
    xml = "<mujoco model='m'><worldbody><geom size='1'/></worldbody></mujoco>"
    root = mjcf.from_xml_string(xml)
    assert root.modification_count == 0
    assert root.attribute_changes_since(0) == ()
