"""MjModel fields that only describe appearance: writing them cannot change `mj_forward`.

MuJoCo documents a colour (`rgba`), a material reference (`matid`) and a material's
properties (emission, specular, shininess, reflectance, metallic, roughness and its texture
reference and tiling) as visual properties, read by the renderer. The fields are found in
the installed MuJoCo by those property names: every MjModel array named
`<object>_<property>`, for whichever objects carry them.

Two things can read them during `mj_forward` all the same, so a model that has either
gets no exemptions:

- ray casting skips fully transparent geoms, so a rangefinder's reading depends on geom and
  material colours;
- user sensors and plugins run user code, which may read any field.

`tests/mjcf/test_appearance.py` checks, for the installed MuJoCo and every field listed
here, that perturbing it leaves every MjData array after `mj_forward` bit-identical, and
that a rangefinder does see a geom's colour.
"""

from collections.abc import Iterable

import mujoco

from mjcf.binding import compiled_field
from mujoco_physics.field_layout import MODEL_EXTENTS

_APPEARANCE_PROPERTIES = frozenset(
    (
        "rgba",
        "matid",
        "emission",
        "specular",
        "shininess",
        "reflectance",
        "metallic",
        "roughness",
        "texid",
        "texuniform",
        "texrepeat",
    )
)

APPEARANCE_FIELDS = frozenset(
    name for name in MODEL_EXTENTS if name.rpartition("_")[2] in _APPEARANCE_PROPERTIES
)

# Sensors whose values MuJoCo computes by ray casting or by running user code.
_SENSORS_READING_APPEARANCE = frozenset(
    (
        int(mujoco.mjtSensor.mjSENS_RANGEFINDER),
        int(mujoco.mjtSensor.mjSENS_USER),
        int(mujoco.mjtSensor.mjSENS_PLUGIN),
    )
)


def forward_neutral_fields(model: mujoco.MjModel) -> frozenset[str]:
    """The MjModel fields of `model` whose values `mj_forward` does not read.

    `APPEARANCE_FIELDS`, or no field at all when `model` has plugins, user sensors or
    rangefinders (see the module docstring).
    """
    if model.nplugin or not _SENSORS_READING_APPEARANCE.isdisjoint(model.sensor_type.tolist()):
        return frozenset()
    return APPEARANCE_FIELDS


def changes_are_forward_neutral(changes: Iterable, neutral_fields: frozenset[str]) -> bool:
    """Whether every (element, XML attribute name) change compiles only into a field of
    `neutral_fields`; False for an attribute that is not one MjModel field of its element."""
    for element, xml_name in changes:
        ref = compiled_field(element, xml_name)
        if ref is None or ref.name not in neutral_fields:
            return False
    return True
