"""Array attributes written in place (`geom.rgba[3] = 0.5`) update the element."""

import copy

import numpy as np

import mjcf


def _model_with_geom():
    root = mjcf.RootElement(model="arrays")
    geom = root.worldbody.add("geom", name="ball", type="sphere", size=[0.1], rgba=[1, 0, 0, 1])
    return root, geom


def test_item_write_changes_attribute_and_xml():
    root, geom = _model_with_geom()
    root.to_xml_string()
    geom.rgba[3] = 0.5
    np.testing.assert_array_equal(geom.rgba, [1, 0, 0, 0.5])
    assert 'rgba="1 0 0 0.5"' in root.to_xml_string()


def test_item_write_counts_as_modification():
    root, geom = _model_with_geom()
    before = root.modification_count
    geom.rgba[0] = 0.25
    assert root.modification_count > before


def test_slice_write_on_default_class_reaches_compiled_model():
    root, geom = _model_with_geom()
    del geom.rgba
    root.default.geom.rgba = [1, 1, 1, 1]
    physics = mjcf.Physics.from_mjcf_model(root)
    root.default.geom.rgba[:3] = [0.2, 0.3, 0.4]
    physics = mjcf.Physics.from_mjcf_model(root)
    np.testing.assert_allclose(physics.named.model.geom_rgba["ball"], [0.2, 0.3, 0.4, 1])


def test_write_through_view_updates_element():
    root, geom = _model_with_geom()
    head = geom.rgba[:2]
    head[1] = 0.75
    assert 'rgba="1 0.75 0 1"' in geom.to_xml_string()


def test_in_place_ufunc_and_fill_update_element():
    root, geom = _model_with_geom()
    np.multiply(geom.rgba, 0.5, out=geom.rgba)
    assert 'rgba="0.5 0 0 0.5"' in geom.to_xml_string()
    geom.rgba.fill(1)
    assert 'rgba="1 1 1 1"' in geom.to_xml_string()


def test_arithmetic_result_is_plain_array_detached_from_element():
    root, geom = _model_with_geom()
    doubled = geom.rgba * 2
    assert type(doubled) is np.ndarray
    doubled[0] = 7
    np.testing.assert_array_equal(geom.rgba, [1, 0, 0, 1])


def test_array_replaced_by_assignment_no_longer_writes_element():
    root, geom = _model_with_geom()
    old = geom.rgba
    geom.rgba = [0, 1, 0, 1]
    old[0] = 0.5
    np.testing.assert_array_equal(geom.rgba, [0, 1, 0, 1])


def test_copies_do_not_share_written_arrays():
    root, geom = _model_with_geom()
    geom.rgba[0] = 0.5
    clone = copy.deepcopy(root)
    clone.find("geom", "ball").rgba[0] = 0.1
    np.testing.assert_array_equal(geom.rgba, [0.5, 0, 0, 1])
    np.testing.assert_array_equal(clone.find("geom", "ball").rgba, [0.1, 0, 0, 1])


def test_same_array_object_is_returned_on_each_read():
    root, geom = _model_with_geom()
    assert geom.rgba is geom.rgba


def test_in_place_write_after_cached_writes_reaches_nested_element_text():
    root, _ = _model_with_geom()
    body = root.worldbody.add("body", name="b")
    inner = body.add("geom", name="inner", size=[0.2], rgba=[0, 0, 1, 1])
    root.to_xml_string()
    root.to_xml_string()
    root.to_xml_string()
    inner.rgba[1] = 0.5
    assert 'rgba="0 0.5 1 1"' in root.to_xml_string()
    assert 'rgba="0 0.5 1 1"' in body.to_xml_string()


def test_numpy_functions_that_write_in_place_update_element():
    root, geom = _model_with_geom()
    before = root.modification_count
    np.copyto(geom.rgba, [0.1, 0.2, 0.3, 0.4])
    assert 'rgba="0.1 0.2 0.3 0.4"' in geom.to_xml_string()
    assert root.modification_count > before
    np.put(geom.rgba, [3], [1])
    np.putmask(geom.size, geom.size > 0, 0.25)
    assert 'size="0.25" rgba="0.1 0.2 0.3 1"' in geom.to_xml_string()


def test_numpy_functions_that_only_read_leave_element_unmodified():
    root, geom = _model_with_geom()
    before = root.modification_count
    assert float(np.sum(geom.rgba)) == 2.0
    assert np.concatenate([geom.rgba, geom.rgba]).shape == (8,)
    assert root.modification_count == before


def test_writes_that_leave_the_value_as_it_was_are_not_modifications():
    # dm_control's Duplo writes its stud radius in place at every reset, the same value
    # unless the brick varies: nothing a compile sees has changed, so nothing is to patch.
    root, geom = _model_with_geom()
    geom.rgba[0] = 1.0  # the first read swaps in the writable copy; this write keeps 1
    before = root.modification_count
    geom.rgba[3] = 1.0
    geom.size[:] = [0.1]
    np.multiply(geom.rgba, 1.0, out=geom.rgba)
    geom.rgba[1:3].fill(0.0)
    assert root.modification_count == before
    assert root.attribute_changes_since(before) == ()
    geom.rgba[2:].fill(0.5)
    assert root.attribute_changes_since(before) == ((geom, "rgba"),)
    assert 'rgba="1 0 0.5 0.5"' in geom.to_xml_string()
