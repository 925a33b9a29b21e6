"""How a MuJoCo compile error is described: the offending element's name and XML line are
added to MuJoCo's message (real MuJoCo messages, hand-written XML)."""

import mujoco
import pytest

from mjcf.physics import _describe_compile_error


def _describe(xml: str) -> str:
    with pytest.raises(ValueError) as raised:
        mujoco.MjModel.from_xml_string(xml)
    return _describe_compile_error(str(raised.value), xml)


def _mujoco_message(xml: str) -> str:
    with pytest.raises(ValueError) as raised:
        mujoco.MjModel.from_xml_string(xml)
    return str(raised.value).strip()


def test_element_name_from_mujoco_wins_over_other_names_on_the_line():
    xml = (
        '<mujoco><worldbody><body name="b"><joint name="j" range="1 -1" limited="true"/>'
        '<geom size="1"/></body></worldbody></mujoco>'
    )
    assert _describe(xml) == (
        f"MuJoCo could not compile the MJCF model at element 'j': {_mujoco_message(xml)}"
        f"\nOffending XML: {xml}"
    )


def test_name_is_read_from_the_line_when_mujoco_gives_none():
    xml = (
        '<mujoco><worldbody><geom name="a" size="1"/><geom name="a" size="1"/></worldbody></mujoco>'
    )
    assert "Element name" not in _mujoco_message(xml)
    if "line" not in _mujoco_message(xml):
        pytest.skip(f"mujoco {mujoco.__version__} reports no XML line for a repeated name")
    assert _describe(xml) == (
        f"MuJoCo could not compile the MJCF model at element 'a': {_mujoco_message(xml)}"
        f"\nOffending XML: {xml}"
    )


def test_error_on_the_last_line_quotes_it():
    xml = '<mujoco><worldbody>\n<geom type="mesh" mesh="nope"/></worldbody></mujoco>'
    assert _describe(xml).endswith(
        '\nOffending XML: <geom type="mesh" mesh="nope"/></worldbody></mujoco>'
    )


def test_unnamed_element_is_not_given_a_name():
    xml = '<mujoco><worldbody>\n<geom type="mesh" mesh="nope"/>\n</worldbody></mujoco>'
    assert _describe(xml).startswith("MuJoCo could not compile the MJCF model: Error: mesh")


def _line_of_length(length: int) -> str:
    # Padded with spaces inside the tag, which MuJoCo's (length-limited) message never
    # quotes, so the message keeps its line number on every release.
    start, end = '<geom type="mesh" mesh="nope"', "/>"
    return start + " " * (length - len(start) - len(end)) + end


def test_a_line_of_500_characters_is_quoted_whole():
    line = _line_of_length(500)
    described = _describe(f"<mujoco><worldbody>\n{line}\n</worldbody></mujoco>")
    assert described.endswith(f"\nOffending XML: {line}")


def test_a_longer_line_is_cut_to_500_characters():
    line = _line_of_length(501)
    described = _describe(f"<mujoco><worldbody>\n{line}\n</worldbody></mujoco>")
    assert described.endswith(f"\nOffending XML: {line[:500]} ...")


def test_a_line_number_outside_the_xml_quotes_no_line():
    # MuJoCo numbers lines from 1; a line 0 (or past the end) must not quote another line.
    xml = '<mujoco>\n  <worldbody/>\n  <geom name="last"/>\n</mujoco>'
    for number in (0, 5):
        description = _describe_compile_error(f"Error: bad value\nline {number}", xml)
        assert "Offending XML" not in description, number
