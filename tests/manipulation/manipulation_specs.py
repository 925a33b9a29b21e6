"""The observation keys, shapes and dtypes of dm_control's manipulation suite, per environment,
and of this project's own task, `lift_brick_randomised_features`.

Written from the suite's documented observations (dm_control 1.0.50); every shape has the
leading buffer axis of length 1.
"""

import numpy as np

_F64 = np.dtype(np.float64)

_PROPRIOCEPTION = {
    "jaco_arm/joints_pos": ((1, 6, 2), _F64),
    "jaco_arm/joints_torque": ((1, 6), _F64),
    "jaco_arm/joints_vel": ((1, 6), _F64),
    "jaco_arm/jaco_hand/joints_pos": ((1, 3), _F64),
    "jaco_arm/jaco_hand/joints_vel": ((1, 3), _F64),
    "jaco_arm/jaco_hand/pinch_site_pos": ((1, 3), _F64),
    "jaco_arm/jaco_hand/pinch_site_rmat": ((1, 9), _F64),
}


def _free_prop(name: str) -> dict:
    return {
        f"{name}/angular_velocity": ((1, 3), _F64),
        f"{name}/linear_velocity": ((1, 3), _F64),
        f"{name}/orientation": ((1, 4), _F64),
        f"{name}/position": ((1, 3), _F64),
    }


def _bricks(count: int) -> dict:
    names = ["duplo2x4"] + [f"duplo2x4_{2 * i}" for i in range(1, count)]
    specs = {}
    for name in names:
        specs.update(_free_prop(name))
    return specs


def _order(length: int) -> dict:
    return {"desired_order": ((1, length), _F64)}


_PEDESTAL = {"pedestal/position": ((1, 3), _F64)}

# Observations besides proprioception of each task's '_features' variant.
_FEATURES = {
    "stack_2_bricks": _bricks(2),
    "stack_2_bricks_moveable_base": _bricks(2),
    "stack_3_bricks": _bricks(3),
    "stack_3_bricks_random_order": {**_order(3), **_bricks(3)},
    "stack_2_of_3_bricks_random_order": {**_order(2), **_bricks(3)},
    "reassemble_3_bricks_fixed_order": _bricks(3),
    "reassemble_5_bricks_random_order": {**_order(5), **_bricks(5)},
    "lift_brick": _bricks(1),
    "lift_large_box": _free_prop("unnamed_model"),
    "place_brick": {**_bricks(1), **_PEDESTAL},
    "place_cradle": {**_bricks(1), **_PEDESTAL},
    "reach_duplo": _bricks(1),
    "reach_site": {"target_position": ((1, 3), _F64)},
}

# This project's task beyond dm_control's suite (features only): lift_brick's observations.
_OWN_FEATURES = {"lift_brick_randomised": _bricks(1)}

_NO_VISION = frozenset({"stack_3_bricks_random_order"})
_CAMERA = {"front_close": ((1, 84, 84, 3), np.dtype(np.uint8))}

EXPECTED_SPECS = {}
for _base, _extra in _FEATURES.items():
    EXPECTED_SPECS[f"{_base}_features"] = {**_PROPRIOCEPTION, **_extra}
    if _base not in _NO_VISION:
        EXPECTED_SPECS[f"{_base}_vision"] = {**_CAMERA, **_PROPRIOCEPTION}
for _base, _extra in _OWN_FEATURES.items():
    EXPECTED_SPECS[f"{_base}_features"] = {**_PROPRIOCEPTION, **_extra}

FEATURES_NAMES = tuple(name for name in EXPECTED_SPECS if name.endswith("_features"))
VISION_NAMES = tuple(name for name in EXPECTED_SPECS if name.endswith("_vision"))
EASY_NAMES = (
    "reach_duplo_features",
    "reach_duplo_vision",
    "reach_site_features",
    "reach_site_vision",
)
