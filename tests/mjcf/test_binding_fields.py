"""Tests for mujoco_physics.field_layout: which fields a binding of each element kind exposes."""

import mujoco
import pytest

from mujoco_physics import field_layout
from mujoco_physics.field_layout import DATA, FAMILIES, MODEL


def _field(namespace, attribute):
    ref = FAMILIES[namespace].fields[attribute]
    return ref.struct, ref.name


@pytest.mark.parametrize(
    ("namespace", "attribute", "expected"),
    [
        ("geom", "rgba", (MODEL, "geom_rgba")),
        ("geom", "xpos", (DATA, "geom_xpos")),
        ("body", "xpos", (DATA, "xpos")),
        ("body", "mass", (MODEL, "body_mass")),
        ("body", "xfrc_applied", (DATA, "xfrc_applied")),
        ("body", "mocap_pos", (DATA, "mocap_pos")),
        ("joint", "qpos", (DATA, "qpos")),
        ("joint", "qvel", (DATA, "qvel")),
        ("joint", "range", (MODEL, "jnt_range")),
        ("joint", "damping", (MODEL, "dof_damping")),
        ("joint", "armature", (MODEL, "dof_armature")),
        ("joint", "qfrc_applied", (DATA, "qfrc_applied")),
        ("actuator", "ctrl", (DATA, "ctrl")),
        ("actuator", "force", (DATA, "actuator_force")),
        ("actuator", "gear", (MODEL, "actuator_gear")),
        ("actuator", "act", (DATA, "act")),
        ("sensor", "sensordata", (DATA, "sensordata")),
        ("site", "xmat", (DATA, "site_xmat")),
        ("camera", "xpos", (DATA, "cam_xpos")),
        ("camera", "fovy", (MODEL, "cam_fovy")),
        ("light", "diffuse", (MODEL, "light_diffuse")),
        ("tendon", "length", (DATA, "ten_length")),
        ("tendon", "range", (MODEL, "tendon_range")),
        ("equality", "active", (DATA, "eq_active")),
        ("equality", "data", (MODEL, "eq_data")),
        ("key", "qpos", (MODEL, "key_qpos")),
    ],
)
def test_binding_attribute_maps_to_the_mujoco_field(namespace, attribute, expected):
    assert _field(namespace, attribute) == expected


def test_joint_limit_solver_parameters_win_over_dof_friction_ones():
    assert _field("joint", "solref") == (MODEL, "jnt_solref")


@pytest.mark.parametrize("struct", [MODEL, DATA])
def test_every_per_geom_field_is_a_geom_attribute(struct):
    geom_fields = {ref.name for ref in FAMILIES["geom"].fields.values()}
    per_geom = {
        name for name, extent in field_layout.STRUCT_EXTENTS[struct].items() if extent[0] == "ngeom"
    }
    assert per_geom <= geom_fields


def test_every_named_mujoco_object_kind_has_a_family():
    named_kinds = {
        name[len("name_") : -len("adr")]
        for name in dir(mujoco.MjModel)
        if name.startswith("name_") and name.endswith("adr")
    }
    assert len(FAMILIES) == len(named_kinds)


def test_family_namespaces_are_mujoco_object_types():
    for namespace, family in FAMILIES.items():
        assert family.obj_type.name == f"mjOBJ_{namespace.upper()}"


def test_family_counts_are_model_sizes():
    for family in FAMILIES.values():
        assert isinstance(getattr(mujoco.MjModel.from_xml_string("<mujoco/>"), family.count), int)
