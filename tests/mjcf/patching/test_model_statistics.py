"""mjcf.patching.model_statistics: the statistics equal those MuJoCo's compiler computes."""

import mujoco
import numpy as np
import pytest

from mjcf.patching import model_statistics

# The statistics are computed for the geom-size patch, in the compiler's order of the
# MuJoCo release the patch table was proven on.

_SCENE = """
<mujoco>
  <worldbody>
    <geom type="plane" size="2 1 0.1"/>
    <site name="mark" pos="0.3 0.2 0.1"/>
    <body name="torso" pos="0 0 0.5">
      <freejoint/>
      <geom type="box" size="0.1 0.05 0.02" pos="0.02 0 0"/>
      <body name="arm" pos="0.1 0 0">
        <joint axis="0 1 0"/>
        <geom type="capsule" size="0.02 0.1" pos="0.1 0 0" euler="0 90 0"/>
        <body name="hand" pos="0.2 0 0">
          <joint type="ball"/>
          <geom type="ellipsoid" size="0.03 0.02 0.01" density="300"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.mark.patches_from_3_17
@pytest.mark.parametrize("xml", [_SCENE, _SCENE.replace('size="2 1 0.1"', 'size="0 0 0.1"')])
def test_statistics_equal_the_compilers_bit_for_bit(xml):
    model = mujoco.MjModel.from_xml_string(xml)
    statistics = model_statistics.compiled_statistics(model, mujoco.MjData(model))
    for name, value in statistics._asdict().items():
        assert np.asarray(value).tobytes() == np.asarray(getattr(model.stat, name)).tobytes(), name


def test_fields_the_model_sets_are_kept():
    model = mujoco.MjModel.from_xml_string(_SCENE)
    statistics = model_statistics.compiled_statistics(model, mujoco.MjData(model))
    statistics = statistics._replace(meanmass=5.0, extent=7.0)
    model_statistics.write_statistics(model, statistics, keep={"extent"})
    assert model.stat.meanmass == 5.0
    assert model.stat.extent != 7.0
