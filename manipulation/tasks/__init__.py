"""The tasks of the manipulation suite, one module per family.

Importing this package registers every task family's environments in `registry`.
"""

from manipulation.tasks import lift, lift_randomised, place, reach, reassemble, registry, stack

__all__ = [
    "lift",
    "lift_randomised",
    "place",
    "reach",
    "reassemble",
    "registry",
    "stack",
]
