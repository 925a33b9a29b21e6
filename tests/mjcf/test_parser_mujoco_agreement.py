"""The parser reads attribute text as MuJoCo's own XML reader does (found by the fuzzer)."""

import mujoco
import numpy as np
import pytest

import mjcf


def _compile(body: str) -> mujoco.MjModel:
    return mjcf.Physics.from_mjcf_model(mjcf.from_xml_string(f"<mujoco>{body}</mujoco>")).model.ptr


def _rejected(body: str) -> str:
    with pytest.raises(ValueError) as error:
        _compile(body)
    return str(error.value)


@pytest.mark.parametrize("blank", ["", " ", "\n"])
def test_blank_number_attribute_is_unset(blank):
    model = _compile(f"<worldbody><geom pos='{blank}' condim='{blank}' size='1'/></worldbody>")
    np.testing.assert_array_equal(model.geom_pos[0], [0, 0, 0])
    assert model.geom_condim[0] == 3


def test_empty_name_and_empty_reference_are_unset():
    model = _compile("<worldbody><geom name='' material='' size='1'/></worldbody>")
    assert model.ngeom == 1 and model.geom_matid[0] == -1


def test_empty_model_name_is_unset():
    assert mjcf.from_xml_string("<mujoco model=''/>").model == "unnamed_model"


def test_empty_class_reference_is_an_error_naming_the_attribute():
    assert "'childclass'" in _rejected("<worldbody><body childclass=''/></worldbody>")


@pytest.mark.parametrize(("text", "expected"), [("0x10", 16.0), ("0x1p3", 8.0), ("INF", np.inf)])
def test_float_text_is_read_like_strtod(text, expected):
    assert _compile(f"<worldbody><geom size='{text}'/></worldbody>").geom_size[0][0] == expected


@pytest.mark.parametrize("text", ["1e400", "-1.8e308"])
def test_float_beyond_a_double_is_rejected(text):
    assert "too large for a double" in _rejected(f"<worldbody><geom size='{text}'/></worldbody>")


@pytest.mark.parametrize("text", ["1_0", "1d3"])
def test_float_in_python_only_syntax_is_rejected(text):
    assert "expected a float" in _rejected(f"<worldbody><geom size='{text}'/></worldbody>")


@pytest.mark.parametrize("text", ["3.0", "1e2", "0x3", "inf", "1e400"])
def test_int_attribute_takes_decimal_digits_only(text):
    message = _rejected(f"<worldbody><geom condim='{text}' size='1'/></worldbody>")
    assert f"attribute 'condim': expected an int, got {text!r}" in message


def test_int_beyond_32_bits_is_rejected():
    message = _rejected("<worldbody><geom condim='2147483648' size='1'/></worldbody>")
    assert "too large for a 32-bit int" in message


def test_keyword_text_is_case_sensitive():
    assert "got 'Sphere'" in _rejected("<worldbody><geom type='Sphere' size='1'/></worldbody>")


def test_reference_to_world_names_the_world_body():
    model = _compile(
        "<worldbody><body name='b'><geom size='1'/></body></worldbody>"
        "<contact><exclude body1='world' body2='b'/></contact>"
    )
    assert model.nexclude == 1
    assert model.exclude_signature[0] == 1  # world body 0, body 1


@pytest.mark.parametrize(
    "body",
    [
        "<default><geom size='1'/><geom size='2'/></default>",
        "<worldbody><body><inertial mass='1' pos='0 0 0'/><inertial mass='2' pos='0 0 0'/>"
        "</body></worldbody>",
        "<worldbody><body><freejoint/><freejoint/><geom size='1'/></body></worldbody>",
    ],
)
def test_a_unique_child_given_twice_is_rejected(body):
    assert "may hold only one" in _rejected(body)


def test_repeated_top_level_sections_are_merged():
    model = _compile("<option timestep='0.1'/><option gravity='0 0 1'/>")
    assert model.opt.timestep == 0.1 and list(model.opt.gravity) == [0, 0, 1]


def test_top_level_default_class_cannot_be_renamed():
    assert "cannot be renamed" in _rejected("<default class='mine'/>")


@pytest.mark.parametrize(
    "asset",
    ["<material rgba='1 0 0 1'/>", "<texture type='2d' builtin='checker' width='8' height='8'/>"],
)
def test_nameless_asset_that_mujoco_needs_named_is_rejected(asset):
    assert "empty name" in _rejected(f"<asset>{asset}</asset>")


def test_nameless_skybox_texture_is_accepted():
    asset = "<texture type='skybox' builtin='gradient' width='8' height='8'/>"
    assert _compile(f"<asset>{asset}</asset>").ntex == 1


@pytest.mark.parametrize("dclass", ["main", ""])
def test_top_level_default_may_name_its_class_main_or_nothing(dclass):
    model = _compile(
        f"<default class='{dclass}'><geom size='0.5'/></default><worldbody><geom/></worldbody>"
    )
    assert model.geom_size[0][0] == 0.5


def test_nesting_up_to_mujocos_limit_compiles():
    depth = 496  # with <mujoco>, <worldbody> and a leaf geom: 499 levels
    text = "<worldbody>" + "<body><geom size='0.1'/>" * depth + "</body>" * depth + "</worldbody>"
    assert _compile(text).nbody == depth + 1


def test_nesting_beyond_mujocos_limit_is_a_value_error():
    depth = 497
    text = "<worldbody>" + "<body><geom size='0.1'/>" * depth + "</body>" * depth + "</worldbody>"
    assert "MuJoCo reads at most 499" in _rejected(text)


def test_a_model_built_too_deep_in_python_is_a_value_error_when_written():
    root = mjcf.RootElement()
    body = root.worldbody
    for _ in range(3000):
        body = body.add("body")
    with pytest.raises(ValueError, match="nest too deeply"):
        root.to_xml_string()


def test_contact_pair_friction_takes_five_floats():
    model = _compile(
        "<worldbody><geom name='a' size='1'/><geom name='b' size='1'/></worldbody>"
        "<contact><pair geom1='a' geom2='b' friction='1 2 3 4 5'/></contact>"
    )
    np.testing.assert_array_equal(model.pair_friction[0], [1, 2, 3, 4, 5])


@pytest.mark.parametrize(("shortcut", "bias_type"), [("position", 1), ("intvelocity", 1)])
def test_empty_actuator_shortcut_in_a_default_class_sets_its_actuators(shortcut, bias_type):
    body = (
        f"<default><{shortcut}/></default>"
        "<worldbody><body><joint name='j'/><geom size='0.1'/></body></worldbody>"
        "<actuator><general joint='j' ctrlrange='-1 1'/></actuator>"
    )
    try:
        mujoco.MjModel.from_xml_string(f"<mujoco>{body}</mujoco>")
    except ValueError as error:
        # Some releases (3.10, for one) give an empty <intvelocity/> default an invalid actrange:
        # the shortcut is still applied, so the model is rejected here too.
        assert "actrange" in _rejected(body), error
        return
    model = _compile(body)
    assert model.actuator_biastype[0] == bias_type  # mjBIAS_AFFINE, as MuJoCo reads it
