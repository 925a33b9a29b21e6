"""Lift with domain randomisation: the brick's friction, colour and mass drawn per episode."""

import mjcf
from composer import variation
from composer.variation import colors, distributions, noises
from composer.variation.variation_broadcaster import VariationBroadcaster
from manipulation.props import Duplo2x4
from manipulation.tasks import registry
from manipulation.tasks.lift import Lift
from manipulation.tasks.observation_settings import ObservationSettings

# The factors (low, high) that scale the brick's frictions and its mass at every episode.
FRICTION_FACTORS = (0.5, 1.5)
MASS_FACTORS = (0.5, 2.0)
# The brick's colour: any hue, saturation and value drawn from these bounds.
SATURATIONS = (0.5, 1.0)
VALUES = (0.5, 1.0)


class RandomisedLift(Lift):
    """`Lift` of a prop whose friction, colour and mass are drawn at every episode.

    Before the episode's compile (`initialize_episode_mjcf`, an `MJCFVariator`), every geom
    of the prop gets its frictions scaled by one factor of `FRICTION_FACTORS` and one colour
    (a hue, a saturation in `SATURATIONS` and a value in `VALUES`). As the episode starts
    (`initialize_episode`, a `PhysicsVariator`, before the prop is placed), the prop's body
    gets its mass and its inertia scaled by one factor of `MASS_FACTORS`, as a uniformly
    denser or lighter prop of the same shape has. Each draw is relative to the prop as built.
    All three are attributes a compiled model takes without a recompile, so the task runs
    batched, each world drawing its own (`composer.batch.variations`).

    Args: as `Lift`.
    """

    def __init__(self, obs_settings: ObservationSettings, prop, rest_height: float, **kwargs):
        super().__init__(obs_settings, prop, rest_height, **kwargs)
        friction = VariationBroadcaster(distributions.Uniform(*FRICTION_FACTORS))
        colour = VariationBroadcaster(
            colors.HsvVariation(
                distributions.Uniform(0.0, 1.0),
                distributions.Uniform(*SATURATIONS),
                distributions.Uniform(*VALUES),
            )
        )
        self._mjcf_variator = variation.MJCFVariator()
        for geom in prop.mjcf_model.find_all("geom"):
            self._mjcf_variator.bind_attributes(
                geom,
                friction=noises.Multiplicative(friction.get_proxy()),
                rgba=colour.get_proxy(),
            )
        mass = VariationBroadcaster(distributions.Uniform(*MASS_FACTORS))
        self._physics_variator = variation.PhysicsVariator()
        self._physics_variator.bind_attributes(
            mjcf.get_attachment_frame(prop.mjcf_model),
            mass=noises.Multiplicative(mass.get_proxy()),
            inertia=noises.Multiplicative(mass.get_proxy()),
        )

    def initialize_episode_mjcf(self, random_state) -> None:
        super().initialize_episode_mjcf(random_state)
        self._mjcf_variator.apply_variations(random_state)

    def initialize_episode(self, physics, random_state) -> None:
        self._physics_variator.apply_variations(physics, random_state)
        super().initialize_episode(physics, random_state)


def lift_brick_randomised(obs_settings: ObservationSettings) -> RandomisedLift:
    """Lift a Duplo-style brick of random friction, colour and mass."""
    return RandomisedLift(obs_settings, Duplo2x4(), rest_height=0.0)


registry.add("lift_brick_randomised", lift_brick_randomised, vision=False)
