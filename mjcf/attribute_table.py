"""The type of every MJCF attribute: a compact table keyed by attribute name and tag.

MuJoCo's schema (see `mjcf.schema`) lists which attributes exist; this table adds what
kind of value each one holds. It is keyed by attribute name, with overrides keyed by
element tag where the same name means different things. An attribute the table does not
know is kept as a string, so attributes added by a newer MuJoCo work unchanged.
"""

from __future__ import annotations

import mujoco

from mjcf.attribute_types import (
    Array,
    AttributeType,
    File,
    Identifier,
    Keyword,
    NamePrefix,
    Number,
    Reference,
    String,
)


def _enum_words(enum_name: str, prefix: str, spellings=None, below=None) -> AttributeType:
    """Keyword values from a MuJoCo enum, lowercased as the XML reader spells most of them.

    A string where the installed MuJoCo has no such enum: it then has no attribute that
    takes these words either (the schema says which attributes exist).
    """
    enum = getattr(mujoco, enum_name, None)
    if enum is None:
        return _STRING
    words = []
    for name in dir(enum):
        if not name.startswith(prefix):
            continue
        if below is not None and int(getattr(enum, name)) >= below:
            continue
        word = name[len(prefix) :].lower()
        words.append((int(getattr(enum, name)), (spellings or {}).get(word, word)))
    return Keyword(word for _, word in sorted(words))


_FLOAT = Number(float)
_INT = Number(int)
_STRING = String()
_IDENTIFIER = Identifier()
_FILE = File()
_BOOL = Keyword(("false", "true"))
_AUTO_BOOL = Keyword(("false", "true", "auto"))
_ENABLE = Keyword(("disable", "enable"))


def _floats(low: int = 1, high: int | None = None) -> Array:
    return Array(float, low, high)


def _exact(n: int) -> Array:
    return Array(float, n, n)


def _ints(low: int = 1, high: int | None = None) -> Array:
    return Array(int, low, high)


_GEOM_TYPE = _enum_words("mjtGeom", "mjGEOM_", below=int(mujoco.mjtGeom.mjNGEOMTYPES))
_CAMLIGHT_MODE = _enum_words("mjtCamLight", "mjCAMLIGHT_")

# Attribute name -> type, for every element that has the attribute unless overridden below.
_BY_NAME: dict[str, AttributeType] = {
    "name": _IDENTIFIER,
    "class": Reference("default"),
    "childclass": Reference("default"),
    # Frames and orientations.
    "pos": _exact(3),
    "quat": _exact(4),
    "axisangle": _exact(4),
    "xyaxes": _exact(6),
    "zaxis": _exact(3),
    "euler": _exact(3),
    "fromto": _exact(6),
    "axis": _exact(3),
    "anchor": _exact(3),
    "relpose": _exact(7),
    "refpos": _exact(3),
    "refquat": _exact(4),
    "dir": _exact(3),
    "diaginertia": _exact(3),
    "fullinertia": _exact(6),
    "bindpos": _exact(3),
    "bindquat": _exact(4),
    # Appearance.
    "rgba": _exact(4),
    "rgb1": _exact(3),
    "rgb2": _exact(3),
    "markrgb": _exact(3),
    "texrepeat": _exact(2),
    "emission": _FLOAT,
    "shininess": _FLOAT,
    "reflectance": _FLOAT,
    "metallic": _FLOAT,
    "roughness": _FLOAT,
    "ambient": _exact(3),
    "diffuse": _exact(3),
    "attenuation": _exact(3),
    "cutoff": _FLOAT,
    "exponent": _FLOAT,
    "fovy": _FLOAT,
    "ipd": _FLOAT,
    "resolution": _ints(2, 2),
    "sensorsize": _exact(2),
    "focal": _exact(2),
    "focalpixel": _exact(2),
    "principal": _exact(2),
    "principalpixel": _exact(2),
    # Contact and constraint parameters.
    "size": _floats(1, 3),
    "friction": _floats(1, 3),
    "solref": _floats(1, mujoco.mjNREF),
    "solimp": _floats(1, mujoco.mjNIMP),
    "solreflimit": _floats(1, mujoco.mjNREF),
    "solimplimit": _floats(1, mujoco.mjNIMP),
    "solreffriction": _floats(1, mujoco.mjNREF),
    "solimpfriction": _floats(1, mujoco.mjNIMP),
    "margin": _FLOAT,
    "gap": _FLOAT,
    "solmix": _FLOAT,
    "condim": _INT,
    "contype": _INT,
    "conaffinity": _INT,
    "priority": _INT,
    "group": _INT,
    "fluidcoef": _floats(1, 5),
    "polycoef": _floats(1, 5),
    "torquescale": _FLOAT,
    # Mass and joints.
    "mass": _FLOAT,
    "density": _FLOAT,
    "gravcomp": _FLOAT,
    "range": _exact(2),
    "ref": _FLOAT,
    "springref": _FLOAT,
    "springdamper": _exact(2),
    "armature": _FLOAT,
    "frictionloss": _FLOAT,
    "damping": _floats(1),
    "stiffness": _floats(1),
    "springlength": _floats(1, 2),
    "width": _FLOAT,
    "limited": _AUTO_BOOL,
    "actuatorfrclimited": _AUTO_BOOL,
    "actuatorfrcrange": _exact(2),
    "actuatorgravcomp": _BOOL,
    "user": _floats(0),
    "coef": _FLOAT,
    "divisor": _FLOAT,
    # Actuators.
    "ctrlrange": _exact(2),
    "forcerange": _exact(2),
    "actrange": _exact(2),
    "lengthrange": _exact(2),
    "ctrllimited": _AUTO_BOOL,
    "forcelimited": _AUTO_BOOL,
    "actlimited": _AUTO_BOOL,
    "gear": _floats(1, 6),
    "gainprm": _floats(1, mujoco.mjNGAIN),
    "biasprm": _floats(1, mujoco.mjNBIAS),
    "dynprm": _floats(1, mujoco.mjNDYN),
    "dyntype": _enum_words("mjtDyn", "mjDYN_"),
    "gaintype": _enum_words("mjtGain", "mjGAIN_"),
    "biastype": _enum_words("mjtBias", "mjBIAS_"),
    "actdim": _INT,
    "actearly": _BOOL,
    "cranklength": _FLOAT,
    "kp": _FLOAT,
    "kv": _FLOAT,
    "ki": _FLOAT,
    "dampratio": _FLOAT,
    "inheritrange": _FLOAT,
    "area": _FLOAT,
    "diameter": _FLOAT,
    "gain": _FLOAT,
    "force": _FLOAT,
    "fpmax": _FLOAT,
    "fvmax": _FLOAT,
    "lmin": _FLOAT,
    "lmax": _FLOAT,
    "vmax": _FLOAT,
    "tausmooth": _FLOAT,
    # Sensors.
    "noise": _FLOAT,
    "nsample": _INT,
    # Assets.
    "file": _FILE,
    "fileback": _FILE,
    "filedown": _FILE,
    "filefront": _FILE,
    "fileleft": _FILE,
    "fileright": _FILE,
    "fileup": _FILE,
    "vertex": _floats(0),
    "normal": _floats(0),
    "texcoord": _floats(0),
    "face": _ints(0),
    "vertid": _ints(0),
    "vertweight": _floats(0),
    "elevation": _floats(0),
    "inflate": _FLOAT,
    "fitscale": _FLOAT,
    "scale": _exact(3),
    "nrow": _INT,
    "ncol": _INT,
    "builtin": _enum_words("mjtBuiltin", "mjBUILTIN_"),
    "mark": _enum_words("mjtMark", "mjMARK_"),
    "random": _FLOAT,
    "gridsize": _ints(2, 2),
    "texuniform": _BOOL,
    "hflip": _BOOL,
    "vflip": _BOOL,
    "nchannel": _INT,
    "maxhullvert": _INT,
    "smoothnormal": _BOOL,
    # Bodies.
    "mocap": _BOOL,
    "target": Reference("body"),
    "castshadow": _BOOL,
    "active": _BOOL,
    "directional": _BOOL,
    # Custom, keyframes.
    "data": _STRING,
    "prm": _floats(0),
    "time": _FLOAT,
    "qpos": _floats(0),
    "qvel": _floats(0),
    "act": _floats(0),
    "ctrl": _floats(0),
    "mpos": _floats(0),
    "mquat": _floats(0),
    # References.
    "material": Reference("material"),
    "texture": Reference("texture"),
    "mesh": Reference("mesh"),
    "hfield": Reference("hfield"),
    "joint": Reference("joint"),
    "jointinparent": Reference("joint"),
    "joint1": Reference("joint"),
    "joint2": Reference("joint"),
    "tendon": Reference("tendon"),
    "tendon1": Reference("tendon"),
    "tendon2": Reference("tendon"),
    "site": Reference("site"),
    "site1": Reference("site"),
    "site2": Reference("site"),
    "refsite": Reference("site"),
    "cranksite": Reference("site"),
    "slidersite": Reference("site"),
    "sidesite": Reference("site"),
    "body": Reference("body"),
    "body1": Reference("body"),
    "body2": Reference("body"),
    "subtree1": Reference("body"),
    "subtree2": Reference("body"),
    "geom": Reference("geom"),
    "geom1": Reference("geom"),
    "geom2": Reference("geom"),
    "camera": Reference("camera"),
    "actuator": Reference("actuator"),
    "flex": Reference("flex"),
    "instance": Reference("plugin"),
    "objname": Reference(None, "objtype"),
    "refname": Reference(None, "reftype"),
}

_VISUAL_COLOR = _exact(4)

# Element tag -> {attribute name -> type}; "*" gives the type of every attribute of that tag.
_BY_ELEMENT: dict[str, dict[str, AttributeType]] = {
    "mujoco": {"model": _STRING},
    "default": {"class": _IDENTIFIER},
    "compiler": {
        "angle": Keyword(("radian", "degree")),
        "coordinate": Keyword(("local", "global")),
        "inertiafromgeom": _AUTO_BOOL,
        "autolimits": _BOOL,
        "balanceinertia": _BOOL,
        "boundmass": _FLOAT,
        "boundinertia": _FLOAT,
        "settotalmass": _FLOAT,
        "discardvisual": _BOOL,
        "fusestatic": _BOOL,
        "strippath": _BOOL,
        "alignfree": _BOOL,
        "inertiagrouprange": _ints(2, 2),
        "meshdir": _STRING,
        "texturedir": _STRING,
        "assetdir": _STRING,
    },
    "lengthrange": {"mode": _STRING, "timestep": _FLOAT, "tolrange": _FLOAT},
    "option": {
        "timestep": _FLOAT,
        "impratio": _FLOAT,
        "tolerance": _FLOAT,
        "viscosity": _FLOAT,
        "density": _FLOAT,
        "gravity": _exact(3),
        "wind": _exact(3),
        "magnetic": _exact(3),
        "o_margin": _FLOAT,
        "o_solref": _floats(1, mujoco.mjNREF),
        "o_solimp": _floats(1, mujoco.mjNIMP),
        "o_friction": _floats(1, 5),
        "integrator": _enum_words(
            "mjtIntegrator", "mjINT_", spellings={"euler": "Euler", "rk4": "RK4"}
        ),
        "cone": _enum_words("mjtCone", "mjCONE_"),
        "jacobian": _enum_words("mjtJacobian", "mjJAC_"),
        "solver": _enum_words(
            "mjtSolver", "mjSOL_", spellings={"pgs": "PGS", "cg": "CG", "newton": "Newton"}
        ),
        "iterations": _INT,
        "ls_iterations": _INT,
        "noslip_iterations": _INT,
        "ccd_iterations": _INT,
        "sdf_iterations": _INT,
        "sdf_initpoints": _INT,
        "ls_tolerance": _FLOAT,
        "noslip_tolerance": _FLOAT,
        "ccd_tolerance": _FLOAT,
    },
    "flag": {"*": _ENABLE},
    "size": {"*": _INT, "memory": _STRING},
    "statistic": {"center": _exact(3), "*": _FLOAT},
    "global": {
        "*": _STRING,
        "fovy": _FLOAT,
        "ipd": _FLOAT,
        "azimuth": _FLOAT,
        "elevation": _FLOAT,
        "linewidth": _FLOAT,
        "glow": _FLOAT,
        "offwidth": _INT,
        "offheight": _INT,
        "realtime": _FLOAT,
    },
    "quality": {"*": _INT},
    "headlight": {"*": _exact(3), "active": _INT},
    "map": {"*": _FLOAT},
    "scale": {"*": _FLOAT},
    "rgba": {"*": _VISUAL_COLOR},
    "geom": {"type": _GEOM_TYPE, "size": _floats(1, 3)},
    "site": {"type": _GEOM_TYPE, "size": _floats(1, 3)},
    "joint": {"type": _enum_words("mjtJoint", "mjJNT_")},
    "camera": {"mode": _CAMLIGHT_MODE, "projection": _enum_words("mjtProjection", "mjPROJ_")},
    "light": {
        "mode": _CAMLIGHT_MODE,
        "type": _enum_words("mjtLightType", "mjLIGHT_"),
        "specular": _exact(3),
        "range": _FLOAT,
        "intensity": _FLOAT,
        "bulbradius": _FLOAT,
    },
    "material": {"specular": _FLOAT},
    "texture": {
        "type": _enum_words("mjtTexture", "mjTEXTURE_"),
        "width": _INT,
        "height": _INT,
    },
    "hfield": {"size": _exact(4)},
    "pair": {"friction": _floats(1, 5)},
    "numeric": {"size": _INT, "data": _floats(0)},
    "flexcomp": {"mesh": _STRING, "scale": _exact(3), "count": _ints(3, 3), "spacing": _exact(3)},
    "muscle": {"timeconst": _floats(1, 2), "range": _exact(2), "scale": _FLOAT},
    "mesh": {"builtin": _STRING},
    "position": {"timeconst": _FLOAT},
    "cylinder": {"timeconst": _FLOAT},
    # The sub-model (an `<asset><model>`) to copy from, and the prefix of the copies' names.
    "attach": {"*": _STRING, "model": Reference("model"), "prefix": NamePrefix()},
    "flex": {"body": _STRING, "node": _STRING},
    "layer": {"role": _STRING},
    "tactile": {"geom": Reference("geom"), "mesh": Reference("mesh")},
}


def attribute_type(tag: str, name: str) -> AttributeType:
    """Returns the type of attribute `name` of element `tag`."""
    overrides = _BY_ELEMENT.get(tag)
    if overrides is not None:
        found = overrides.get(name)
        if found is not None:
            return found
        found = overrides.get("*")
        if found is not None:
            return found
    return _BY_NAME.get(name, _STRING)
