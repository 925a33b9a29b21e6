"""Variators and PropPlacer driven by a composer.Environment, as a task would use them."""

import numpy as np
import pytest

import composer
import mjcf
from composer import variation
from composer.initializers import PropPlacer
from composer.variation import colors, distributions, noises, rotations


class _Box(composer.Entity):
    def _build(self, name):
        self._model = mjcf.RootElement(model=name)
        self.geom = self._model.worldbody.add(
            "geom", name="geom", type="box", size=[0.05, 0.05, 0.05], mass=0.2
        )

    @property
    def mjcf_model(self):
        return self._model


class _ClutterTask(composer.Task):
    """Boxes with randomised sizes and colours, dropped into a small square each episode."""

    def __init__(self, num_boxes, region_half_width):
        self._arena = composer.Arena()
        self._arena.mjcf_model.worldbody.add("geom", type="plane", size=[2, 2, 0.1])
        self.boxes = [_Box(f"box{i}") for i in range(num_boxes)]
        for box in self.boxes:
            self._arena.add_free_entity(box)
        self._mjcf_variator = variation.MJCFVariator()
        self._physics_variator = variation.PhysicsVariator()
        for box in self.boxes:
            self._mjcf_variator.bind_attributes(
                box.geom, size=noises.Multiplicative(distributions.Uniform(0.8, 1.2))
            )
            self._physics_variator.bind_attributes(
                box.geom, rgba=colors.HsvVariation(distributions.Uniform(), 0.8, 0.8)
            )
        half = region_half_width
        self._placer = PropPlacer(
            self.boxes,
            position=distributions.Uniform([-half, -half, 0.1], [half, half, 0.1]),
            quaternion=rotations.QuaternionFromAxisAngle([0, 0, 1], distributions.Uniform(0, 3)),
            max_attempts_per_prop=50,
        )

    @property
    def root_entity(self):
        return self._arena

    def initialize_episode_mjcf(self, random_state):
        self._mjcf_variator.apply_variations(random_state)

    def initialize_episode(self, physics, random_state):
        self._physics_variator.apply_variations(physics, random_state)
        self._placer.initialize_episode(physics, random_state)

    def get_reward(self, physics):
        return 0.0


def _penetrations(physics):
    physics.forward()
    data = physics.data.ptr
    return int(np.sum(data.contact.dist < 0))


def test_each_episode_recompiles_new_sizes_and_colours_and_places_boxes_apart():
    task = _ClutterTask(num_boxes=4, region_half_width=0.3)
    env = composer.Environment(task, random_state=0)
    sizes, colours = [], []
    for _ in range(3):
        env.reset()
        physics = env.physics
        sizes.append(np.array(physics.bind(task.boxes[0].geom).size))
        colours.append(np.array(physics.bind(task.boxes[0].geom).rgba))
        assert _penetrations(physics) == 0
    assert not np.allclose(sizes[0], sizes[1]) and not np.allclose(sizes[1], sizes[2])
    assert not np.allclose(colours[0], colours[1])
    assert all(np.all((0.04 <= size) & (size <= 0.06)) for size in sizes)


def test_impossible_placement_fails_reset_after_the_allowed_attempts():
    # Nearly, not exactly, the same spot for every box: mujoco 3.9.0's box-box collider
    # finds 9 contacts for exactly concentric boxes and stops with a FatalError.
    task = _ClutterTask(num_boxes=3, region_half_width=0.01)
    env = composer.Environment(task, random_state=0, max_reset_attempts=2)
    with pytest.raises(composer.EpisodeInitializationError, match="no non-penetrating pose"):
        env.reset()
