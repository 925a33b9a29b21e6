"""field_layout: array sizes read from mujoco.introspect, also where it gives none."""

import mujoco
import numpy as np
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


_SCENE = """
<mujoco>
  <custom><text name="note" data="hello"/></custom>
  <worldbody>
    <body><joint/><geom size="0.1"/><geom type="box" size="0.1 0.2 0.3"/></body>
  </worldbody>
</mujoco>
"""


def _public_values(struct) -> dict:
    return {name: getattr(struct, name) for name in dir(struct) if not name.startswith("_")}


def test_model_fields_list_exactly_the_numeric_arrays_and_numbers_an_mjmodel_has():
    model = mujoco.MjModel.from_xml_string(_SCENE)
    values = _public_values(model)
    fields = field_layout.MODEL_FIELDS
    numeric_arrays = {
        name
        for name, value in values.items()
        if isinstance(value, np.ndarray) and value.dtype.kind in "fiub" and name != "plugin_attr"
    }
    assert set(fields.arrays) == numeric_arrays
    assert set(fields.scalars) == {n for n, v in values.items() if isinstance(v, (int, float))}
    assert model.geom_size.shape == (2, 3) and "geom_size" in fields.arrays
    assert {"nq", "ngeom", "nbuffer"} <= set(fields.scalars)


def test_model_fields_keep_text_buffers_and_nested_structs_apart_from_arrays():
    model = mujoco.MjModel.from_xml_string(_SCENE)
    fields = field_layout.MODEL_FIELDS
    assert {"names", "paths", "text_data", "plugin_attr"} == set(fields.texts)
    assert b"hello" in bytes(model.text_data)
    assert set(fields.structs) == {"opt", "vis", "stat"}
    assert not set(fields.texts) & set(fields.arrays)


def test_data_fields_list_exactly_the_arrays_and_numbers_an_mjdata_has():
    data = mujoco.MjData(mujoco.MjModel.from_xml_string(_SCENE))
    values = _public_values(data)
    fields = field_layout.DATA_FIELDS
    assert set(fields.arrays) == {n for n, v in values.items() if isinstance(v, np.ndarray)}
    assert set(fields.scalars) == {n for n, v in values.items() if isinstance(v, (int, float))}
    # Contacts are an array of structs, read through their own list type.
    assert "contact" not in fields.arrays and {"qpos", "energy"} <= set(fields.arrays)
