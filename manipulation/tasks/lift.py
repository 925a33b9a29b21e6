"""Lift tasks: pick a prop up off the table."""

import numpy as np

from composer import initializers
from composer.utils import rewards
from manipulation.props import Duplo2x4, LargeBox, Prop
from manipulation.tasks import base, registry
from manipulation.tasks import task_constants as tc
from manipulation.tasks.observation_settings import ObservationSettings


class Lift(base.ManipulationTask):
    """Lift a prop lying at a random place on the table.

    The reward rises linearly with the height of the prop's lowest corner above the table,
    from 0 on the table to 1 at `lift_height`, and is 0 while the hand does not touch the
    prop (a prop knocked into the air earns nothing).

    Args:
      obs_settings: which observables to enable; with features, the prop's pose and
        velocity ('<prop>/position', ...).
      prop: the prop to lift; it must have `vertices`, sites at its corners.
      rest_height: the height of the prop's origin when it rests on the table.
      lift_height: the height (m) of the lowest corner that earns the full reward.
    """

    def __init__(
        self,
        obs_settings: ObservationSettings,
        prop: Prop,
        rest_height: float,
        lift_height: float = tc.LIFT_HEIGHT,
    ):
        super().__init__(obs_settings)
        self._prop = prop
        self._lift_height = lift_height
        self.arena.add_free_entity(prop)
        self._enable_features(prop)
        self._watch_touches([prop])
        self._prop_placer = initializers.PropPlacer(
            [prop], position=base.table_positions(rest_height), quaternion=base.random_yaw()
        )
        self._vertex_heights = None
        self._site_xpos = None

    @property
    def prop(self) -> Prop:
        return self._prop

    @property
    def lift_height(self) -> float:
        """The height (m) of the prop's lowest corner that earns the full reward."""
        return self._lift_height

    def after_compile(self, physics, random_state) -> None:
        super().after_compile(physics, random_state)
        # The heights of the prop's corners in the flattened site_xpos.
        vertex_ids = np.asarray(physics.bind(self._prop.vertices).element_id)
        self._vertex_heights = (3 * vertex_ids + 2).astype(np.intp)
        self._site_xpos = self._data.site_xpos.reshape(-1)

    def initialize_episode(self, physics, random_state) -> None:
        super().initialize_episode(physics, random_state)
        self._prop_placer(physics, random_state)

    def get_reward(self, physics) -> float:
        height = float(np.minimum.reduce(self._site_xpos.take(self._vertex_heights)))
        if height <= 0.0:
            # The prop lies on the table, where the reward is 0: skip the work (most steps).
            return 0.0
        progress = rewards.tolerance(
            height,
            bounds=(self._lift_height, np.inf),
            margin=self._lift_height,
            sigmoid="linear",
            value_at_margin=0.0,
        )
        if progress == 0.0 or not self._hand_touches():
            return 0.0
        return progress


def lift_brick(obs_settings: ObservationSettings) -> Lift:
    """Lift a Duplo-style brick."""
    return Lift(obs_settings, Duplo2x4(), rest_height=0.0)


def lift_large_box(obs_settings: ObservationSettings) -> Lift:
    """Lift an 18 cm, 1.3 kg box, too large to hold in a pinch grip."""
    # dm_control's suite leaves this box's model unnamed, which scopes its observables as
    # 'unnamed_model/...'; naming it so keeps the suite's observation keys.
    box = LargeBox(name="unnamed_model")
    return Lift(obs_settings, box, rest_height=LargeBox.HALF_SIZE)


registry.add("lift_brick", lift_brick)
registry.add("lift_large_box", lift_large_box)
