"""Place tasks: put a brick on a target on top of a pedestal, and let go of it."""

from composer import initializers
from composer.utils import rewards
from composer.variation import distributions
from manipulation.props import Cradle, Duplo2x4, Pedestal
from manipulation.tasks import base, registry
from manipulation.tasks import task_constants as tc
from manipulation.tasks.observation_settings import ObservationSettings
from manipulation.tasks.seating import SeatErrors

# The brick may start anywhere around the pedestal, which takes up much of the prop area.
_PROP_XY_BOUNDS = ((-0.15, -0.15), (0.15, 0.15))
_MAX_PLACEMENT_ATTEMPTS = 50


class Place(base.ManipulationTask):
    """Put a brick lying on the table onto a target fixed on top of a pedestal.

    The pedestal's top appears at a random point of `PEDESTAL_TOP_BOUNDS` with a random
    yaw; the brick lies at a random place around it. The reward is 1 when the brick rests
    within `tolerance` of its seat on the target and decays smoothly (Gaussian, 0.1 at
    `PLACE_MARGIN` beyond it); it is halved while the hand still touches the brick.

    Args:
      obs_settings: which observables to enable; with features, the brick's pose and
        velocity ('duplo2x4/position', ...) and the pedestal's top ('pedestal/position').
      target: the entity fixed on the pedestal: a `Duplo2x4` to stack the brick on, or
        a `Cradle` to put it in.
    """

    def __init__(self, obs_settings: ObservationSettings, target: Duplo2x4 | Cradle):
        super().__init__(obs_settings)
        self._prop = Duplo2x4(rgba=tc.BRICK_COLOURS[0])
        self._pedestal = Pedestal()
        self._target = target
        self.arena.add_free_entity(self._prop)
        self.arena.attach(self._pedestal)
        self._pedestal.attach(target)
        self._enable_features(self._prop)
        self._enable_features(self._pedestal)
        self._watch_touches([self._prop])
        if isinstance(target, Cradle):
            self._seat_height, self._tolerance = Cradle.SEAT_HEIGHT, tc.CRADLE_TOLERANCE
        else:
            self._seat_height, self._tolerance = Duplo2x4.HEIGHT, tc.SEAT_TOLERANCE
        self._pedestal_placer = initializers.PropPlacer(
            [self._pedestal],
            position=distributions.Uniform(*tc.PEDESTAL_TOP_BOUNDS),
            quaternion=base.random_yaw(),
        )
        (x0, y0), (x1, y1) = _PROP_XY_BOUNDS
        z = tc.PROP_DROP_HEIGHT
        self._prop_placer = initializers.PropPlacer(
            [self._prop],
            position=distributions.Uniform((x0, y0, z), (x1, y1, z)),
            quaternion=base.random_yaw(),
            max_attempts_per_prop=_MAX_PLACEMENT_ATTEMPTS,
        )
        self._seat_error = None

    @property
    def prop(self) -> Duplo2x4:
        """The brick to place."""
        return self._prop

    @property
    def pedestal(self) -> Pedestal:
        return self._pedestal

    @property
    def target(self):
        """The entity on the pedestal the brick goes on (or in)."""
        return self._target

    @property
    def seat_height(self) -> float:
        """The height (m) of the brick's seat above the target's origin."""
        return self._seat_height

    @property
    def seat_tolerance(self) -> float:
        """How far (m) from its seat the brick still earns the full reward."""
        return self._tolerance

    def after_compile(self, physics, random_state) -> None:
        super().after_compile(physics, random_state)
        self._seat_error = SeatErrors(physics, [(self._target, self._prop)], self._seat_height)

    def initialize_episode(self, physics, random_state) -> None:
        super().initialize_episode(physics, random_state)
        # The brick still lies where the last episode left it: it must not block the pedestal.
        self._pedestal_placer(physics, random_state, ignore_contacts_with_entities=[self._prop])
        self._prop_placer(physics, random_state)

    def get_reward(self, physics) -> float:
        placed = rewards.tolerance(
            self._seat_error()[0],
            bounds=(0.0, self._tolerance),
            margin=tc.PLACE_MARGIN,
            sigmoid="gaussian",
        )
        if self._hand_touches():
            return tc.HELD_FACTOR * placed
        return placed


def place_brick(obs_settings: ObservationSettings) -> Place:
    """Stack a brick on a brick fixed on top of a pedestal."""
    return Place(obs_settings, Duplo2x4(rgba=tc.BRICK_COLOURS[1], easy_align=True))


def place_cradle(obs_settings: ObservationSettings) -> Place:
    """Put a brick into a cradle on top of a pedestal."""
    return Place(obs_settings, Cradle())


registry.add("place_brick", place_brick)
registry.add("place_cradle", place_cradle)
