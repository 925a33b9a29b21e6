"""The MuJoCo releases this project supports, and clear errors where a release lacks a feature.

`MINIMUM_VERSION` is the floor (`mujoco_physics.version`): `check_version` (run when
`mujoco_physics` or `mjcf` is imported) turns an older install into one ImportError instead of
an AttributeError from deep inside. Within the
supported range everything that differs between releases (enums, schema, struct fields) is
read from the installed library, so a feature the installed release lacks is simply absent.
The tables below only name the release that introduced such a feature, so that the error
for using it, and the reason a test of it is skipped, say which MuJoCo to upgrade to.
"""

from __future__ import annotations

import mujoco

# The floor and its check live in the engine layer; re-exported here, where tools read them.
from mujoco_physics.version import MINIMUM_VERSION, check_version, version_tuple  # noqa: F401

#: "tag.name" -> the first release whose XML reader has attribute or child element `name`
#: in `<tag>` or in the elements nested in `<tag>` ("sensor.interval": every sensor).
MJCF_SINCE: dict[str, str] = {
    "body.sleep": "3.4.0",
    "flag.sleep": "3.4.0",
    "sensor.interval": "3.5.0",
    "sensor.delay": "3.5.0",
    "sensor.nsample": "3.5.0",
    "sensor.interp": "3.5.0",
    "actuator.delay": "3.5.0",
    "camera.projection": "3.5.0",
    "equality.flexstrain": "3.6.0",
    "actuator.dcmotor": "3.7.0",
    "actuator.orientation": "3.11.0",
    "geom.adhesion": "3.11.0",
    "actuator.pid": "3.12.0",
    "joint.springyield": "4.0.0",
    "geom.castshadow": "4.0.0",
}

#: `Physics.bind` attribute, as "family.attribute" -> the first release with its field.
BINDING_SINCE: dict[str, str] = {
    "body.awake": "3.4.0",
    "sensor.interval": "3.5.0",
    "sensor.delay": "3.5.0",
    "actuator.delay": "3.5.0",
    "camera.projection": "3.5.0",
    "actuator.armature": "3.7.0",
    "actuator.damping": "3.7.0",
    "geom.xquat": "4.0.0",
    "site.xquat": "4.0.0",
    "body.xiquat": "4.0.0",
}


def _missing(feature: str, since: str | None, installed: str | None) -> str:
    installed = mujoco.__version__ if installed is None else installed
    if since is None or version_tuple(since) <= version_tuple(installed):
        return ""
    return f"{feature} needs mujoco>={since} (installed: mujoco {installed})"


def missing_mjcf(path: str, name: str, installed: str | None = None) -> str:
    """Why attribute or child `name` of the element at schema `path` is missing, or ''.

    Args:
      path: the element's tags from the root, '/'-separated ("mujoco/sensor/touch").
      name: the attribute or child tag asked for.
      installed: the MuJoCo version to judge (default: the imported one).

    Returns:
      '' unless a release newer than `installed` introduced `name` there, so that a
      mistyped or misplaced name keeps the caller's own message; else a sentence.
    """
    for tag in reversed(path.split("/")):
        since = MJCF_SINCE.get(f"{tag}.{name}")
        if since is not None:
            return _missing(f"MJCF {name!r} in <{tag}>", since, installed)
    return ""


def missing_binding(namespace: str, attribute: str, installed: str | None = None) -> str:
    """Why `Physics.bind` attribute `attribute` of a `namespace` element is missing, or ''.

    '' unless a release newer than `installed` (default: the imported mujoco) introduced it.
    """
    since = BINDING_SINCE.get(f"{namespace}.{attribute}")
    return _missing(f"{namespace} attribute {attribute!r}", since, installed)
