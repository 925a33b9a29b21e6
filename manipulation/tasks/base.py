"""ManipulationTask: the arena, arm, hand, timing and observables every task shares."""

import collections

import numpy as np

import composer
from composer import initializers
from composer.observation import observable
from composer.variation import distributions, rotations
from manipulation.arenas import TableArena
from manipulation.arms import JacoArm
from manipulation.hands import JacoHand
from manipulation.models import constants as model_constants
from manipulation.tasks import task_constants as tc
from manipulation.tasks.observation_settings import ObservationSettings

_FRONT_CAMERA = "front_close"


def random_yaw() -> rotations.QuaternionFromAxisAngle:
    """A variation: a rotation about the vertical by a uniformly random angle."""
    return rotations.QuaternionFromAxisAngle(
        axis=(0.0, 0.0, 1.0), angle=distributions.Uniform(-np.pi, np.pi)
    )


def table_positions(rest_height: float) -> distributions.Uniform:
    """A variation: a point of the prop area, `rest_height` (+ a small drop) above the table."""
    (x0, y0), (x1, y1) = tc.PROP_XY_BOUNDS
    z = rest_height + tc.PROP_DROP_HEIGHT
    return distributions.Uniform((x0, y0, z), (x1, y1, z))


def entity_geom_mask(physics, entity) -> np.ndarray:
    """A boolean mask over the compiled geoms: True for the geoms of `entity` (and of the
    entities attached to it)."""
    ids = physics.bind(entity.mjcf_model.find_all("geom")).element_id
    mask = np.zeros(physics.model.ptr.ngeom, dtype=bool)
    mask[ids] = True
    return mask


class ManipulationTask(composer.Task):
    """A Jaco-style arm with its hand on a table, acting every 0.04 s.

    Builds the scene (the arm stands at `ARM_OFFSET` with the hand on its wrist), sets the
    timing (0.002 s physics steps, 20 per control step) and enables the arm's and hand's
    observables; with `obs_settings.camera` it adds the 'front_close' camera images. At the
    start of every episode the pinch site is put at a random point of `tcp_bounds`, pointing
    down. Subclasses add props and implement `get_reward`, whose full value (1) is success.

    Args:
      obs_settings: which observables to enable.
      tcp_bounds: (lower, upper) corners of the box where the pinch site starts.
    """

    def __init__(self, obs_settings: ObservationSettings, tcp_bounds=tc.TCP_BOUNDS):
        self._obs_settings = obs_settings
        self._arena = TableArena()
        self._arm = JacoArm()
        self._hand = JacoHand()
        self._arm.attach(self._hand)
        self._arena.attach_offset(self._arm, model_constants.ARM_OFFSET)
        self.set_timesteps(tc.CONTROL_TIMESTEP, tc.PHYSICS_TIMESTEP)
        self._arm.observables.enable_all()
        self._hand.observables.enable_all()
        self._task_observables = collections.OrderedDict()
        if obs_settings.camera:
            camera = observable.MJCFCamera(
                self._arena.camera(_FRONT_CAMERA),
                height=obs_settings.camera_height,
                width=obs_settings.camera_width,
            )
            camera.enabled = True
            self._task_observables[_FRONT_CAMERA] = camera
        self._tcp_initializer = initializers.ToolCenterPointInitializer(
            self._hand,
            self._arm,
            position=distributions.Uniform(*tcp_bounds),
            quaternion=tc.DOWN_QUATERNION,
        )
        self._touch_watched = ()
        self._data = None
        self._geom_codes = ()

    @property
    def root_entity(self) -> TableArena:
        return self._arena

    @property
    def arena(self) -> TableArena:
        return self._arena

    @property
    def arm(self) -> JacoArm:
        return self._arm

    @property
    def hand(self) -> JacoHand:
        return self._hand

    @property
    def task_observables(self) -> collections.OrderedDict:
        return self._task_observables

    def _add_feature_observable(self, name: str, feature: observable.Observable) -> None:
        """Adds a task observable, enabled when the settings ask for features."""
        feature.enabled = self._obs_settings.features
        self._task_observables[name] = feature

    def _enable_features(self, entity) -> None:
        """Enables `entity`'s observables when the settings ask for features."""
        if self._obs_settings.features:
            entity.observables.enable_all()

    def _watch_touches(self, entities) -> None:
        """Makes `_hand_touches` report contacts between the hand and these entities."""
        self._touch_watched = tuple(entities)

    def after_compile(self, physics, random_state) -> None:
        self._data = physics.data.ptr
        # 1 for the hand's geoms, 2 for the watched entities': a contact between the two
        # is the one pair whose codes multiply to 2.
        codes = np.zeros(physics.model.ptr.ngeom, dtype=np.int8)
        for entity in self._touch_watched:
            codes[entity_geom_mask(physics, entity)] = 2
        codes[entity_geom_mask(physics, self._hand)] = 1
        self._geom_codes = codes.tolist()

    def initialize_episode(self, physics, random_state) -> None:
        self._tcp_initializer(physics, random_state)

    def get_success(self, physics) -> bool:
        """Whether the goal is met: the reward is at its full value, 1. Reach: the pinch
        site within `REACH_RADIUS` of the target; lift: the prop's lowest corner at the
        lift height, in the hand; place, stack and reassemble: every brick within its seat
        tolerance, and (place, stack) let go of."""
        return self.get_reward(physics) >= 1.0

    def _hand_touches(self) -> bool:
        """Whether any hand geom is in contact with a geom of the watched entities."""
        data = self._data
        if data.ncon == 0:
            return False
        # A few dozen contacts at most: a Python loop beats NumPy's per-call overhead.
        codes = self._geom_codes
        for geom1, geom2 in data.contact.geom.tolist():
            if codes[geom1] * codes[geom2] == 2:
                return True
        return False
