"""mjcf.patching.model_snapshot: the field-by-field struct copy used where MjModel's structs
have no setter (mujoco before 3.16)."""

import mujoco
import numpy as np

from mjcf.patching.model_snapshot import _copy_struct

_SOURCE = """
<mujoco>
  <option timestep="0.004" gravity="0 0 -9" integrator="RK4"/>
  <visual><global fovy="30"/><rgba haze="0.1 0.2 0.3 1"/></visual>
  <statistic extent="7" center="1 2 3"/>
  <worldbody><geom size="0.1"/></worldbody>
</mujoco>
"""


def test_copy_struct_copies_scalars_arrays_and_nested_structs_in_place():
    source = mujoco.MjModel.from_xml_string(_SOURCE)
    target = mujoco.MjModel.from_xml_string(
        "<mujoco><worldbody><geom size='0.1'/></worldbody></mujoco>"
    )
    gravity_view = target.opt.gravity
    _copy_struct(target.opt, source.opt)
    _copy_struct(target.vis, source.vis)
    _copy_struct(target.stat, source.stat)
    assert target.opt.timestep == 0.004
    assert target.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4
    np.testing.assert_array_equal(gravity_view, [0, 0, -9])
    assert target.vis.global_.fovy == 30
    np.testing.assert_allclose(target.vis.rgba.haze, [0.1, 0.2, 0.3, 1])
    assert target.stat.extent == 7
    np.testing.assert_array_equal(target.stat.center, [1, 2, 3])
