"""attribute_table: keyword attributes take their words from the installed MuJoCo's enums."""

from mjcf import attribute_table, attribute_types


def test_enum_the_installed_mujoco_lacks_gives_a_plain_string_attribute():
    # mujoco 3.3 has no mjtProjection (camera `projection` came in 3.5).
    missing = attribute_table._enum_words("mjtNoSuchEnum", "mjNOSUCH_")
    assert missing.kind == attribute_types.STRING
