"""Domain randomisation: variations (lazily sampled values) and the variators that apply them.

Counterpart of `dm_control.composer.variation`: `Variation`, `evaluate`, `MJCFVariator`,
`PhysicsVariator`, and the submodules `distributions`, `noises`, `deterministic`,
`rotations`, `colors`, `math` and `variation_broadcaster`.
"""

from composer.variation import (
    colors,
    deterministic,
    distributions,
    math,
    noises,
    rotations,
    variation_broadcaster,
)
from composer.variation.base import Variation, evaluate
from composer.variation.variators import MJCFVariator, PhysicsVariator

__all__ = [
    "MJCFVariator",
    "PhysicsVariator",
    "Variation",
    "colors",
    "deterministic",
    "distributions",
    "evaluate",
    "math",
    "noises",
    "rotations",
    "variation_broadcaster",
]
