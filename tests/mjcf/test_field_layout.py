"""field_layout: array sizes read from mujoco.introspect, also where it gives none."""

import pytest
from mujoco.introspect import ast_nodes

from mujoco_physics import field_layout

_NUMBERS = ast_nodes.PointerType(ast_nodes.ValueType("mjtNum"))


def _field(doc, field_type=_NUMBERS):
    return ast_nodes.StructFieldDecl(name="f", type=field_type, doc=doc)


@pytest.mark.parametrize(
    "doc, extent",
    [
        ("constraint solver reference:frictionloss (nv x mjNREF)", ("nv", "mjNREF")),
        ("detect contact if dist<margin(ngeom x 1)", ("ngeom",)),
        ("global position rel. to sub-com in qpos0 (ncam x 3)", ("ncam", 3)),
        ("net external force; should equal:   (nv x 1)qfrc_applied + J'*xfrc_applied", ("nv",)),
    ],
)
def test_pointer_field_without_extent_takes_the_size_its_doc_states(doc, extent):
    # mujoco 3.3.0's introspect leaves dof_solref, geom_margin and others without extent.
    assert field_layout._extent_from_doc(_field(doc)) == extent


def test_field_whose_doc_states_no_size_has_no_extent():
    assert field_layout._extent_from_doc(_field("main buffer   (nbuffer bytes)")) is None
    scalar = ast_nodes.ValueType("int")
    assert field_layout._extent_from_doc(_field("number of dofs (nv x 1)", scalar)) is None


def test_dof_solref_and_geom_margin_are_known_array_fields():
    assert field_layout.MODEL_EXTENTS["dof_solref"] == ("nv", "mjNREF")
    assert "margin" in field_layout.FAMILIES["geom"].fields
