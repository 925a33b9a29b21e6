"""Reach tasks: bring the pinch site to a target site, or to a brick on the table."""

import math

from composer import initializers
from composer.observation import observable
from composer.utils import rewards
from composer.variation import distributions
from manipulation.props import Duplo2x4
from manipulation.tasks import base, registry
from manipulation.tasks import task_constants as tc
from manipulation.tasks.observation_settings import ObservationSettings

_TARGET_RGBA = (0.9, 0.2, 0.2, 0.35)


class Reach(base.ManipulationTask):
    """Move the pinch site close to a target.

    The target is a visible sphere that appears at a random point of `target_bounds`, or,
    when a `prop` is given, the centre of that prop, put at a random place on the table.
    The reward is 1 within `REACH_RADIUS` of the target and decays smoothly (Gaussian,
    0.1 at `REACH_MARGIN` beyond it).

    Args:
      obs_settings: which observables to enable; with features, the target site's position
        is observed as 'target_position', or the prop's pose as '<prop>/position' etc.
      prop: a `Duplo2x4` to reach for, or None for a target site.
      target_bounds: (lower, upper) corners of the box where the target site appears.
    """

    def __init__(
        self,
        obs_settings: ObservationSettings,
        prop: Duplo2x4 | None = None,
        target_bounds=tc.REACH_TARGET_BOUNDS,
    ):
        super().__init__(obs_settings)
        self._prop = prop
        self._target_placer = None
        if prop is None:
            self._target = self.arena.mjcf_model.worldbody.add(
                "site",
                name="target",
                type="sphere",
                size=[tc.REACH_RADIUS],
                rgba=_TARGET_RGBA,
                group=0,
            )
            self._target_position = distributions.Uniform(*target_bounds)
            self._add_feature_observable(
                "target_position", observable.MJCFFeature("xpos", self._target)
            )
        else:
            self.arena.add_free_entity(prop)
            self._enable_features(prop)
            self._target = prop.bounding_box
            self._target_placer = initializers.PropPlacer(
                [prop], position=base.table_positions(0.0), quaternion=base.random_yaw()
            )
        self._pinch = None
        self._target_xpos = None

    @property
    def prop(self) -> Duplo2x4 | None:
        """The prop to reach for, or None when the target is a site."""
        return self._prop

    @property
    def target(self):
        """The site the pinch site must reach."""
        return self._target

    def after_compile(self, physics, random_state) -> None:
        super().after_compile(physics, random_state)
        self._pinch = physics.bind(self.hand.tool_center_point).xpos
        self._target_xpos = physics.bind(self._target).xpos

    def initialize_episode(self, physics, random_state) -> None:
        super().initialize_episode(physics, random_state)
        if self._target_placer is None:
            physics.bind(self._target).pos = self._target_position(random_state=random_state)
        else:
            self._target_placer(physics, random_state)

    def get_reward(self, physics) -> float:
        # Three coordinates each: plain floats cost less than NumPy calls. The sums and their
        # order are those of the batch's `vectors.lengths`, so its worlds' rewards are these.
        x, y, z = (self._pinch - self._target_xpos).tolist()
        return rewards.tolerance(
            math.sqrt(x * x + y * y + z * z),
            bounds=(0.0, tc.REACH_RADIUS),
            margin=tc.REACH_MARGIN,
            sigmoid="gaussian",
        )


def reach_site(obs_settings: ObservationSettings) -> Reach:
    """Reach a target site that appears at a random point above the table."""
    return Reach(obs_settings)


def reach_duplo(obs_settings: ObservationSettings) -> Reach:
    """Reach a brick lying at a random place on the table."""
    return Reach(obs_settings, prop=Duplo2x4())


registry.add("reach_site", reach_site, tags=("easy",))
registry.add("reach_duplo", reach_duplo, tags=("easy",))
