"""Tests for MJCFVariator and PhysicsVariator: variations reaching the compiled model."""

import numpy as np
import pytest

import mjcf
from composer import variation
from composer.variation import colors, deterministic, distributions, noises


def _model():
    root = mjcf.RootElement(model="scene")
    body = root.worldbody.add("body", name="ball_body", pos=[0, 0, 1])
    body.add("freejoint", name="ball_joint")
    geom = body.add("geom", name="ball", type="sphere", size=[0.1], mass=2.0)
    return root, body, geom


def test_mjcf_variator_changes_compiled_values_episode_to_episode():
    root, _, geom = _model()
    variator = variation.MJCFVariator()
    variator.bind_attributes(geom, size=noises.Additive(distributions.Uniform(-0.05, 0.05)))
    random_state = np.random.RandomState(0)
    radii = []
    for _ in range(4):
        variator.apply_variations(random_state)
        physics = mjcf.Physics.from_mjcf_model(root)
        radii.append(physics.bind(geom).size[0])
    assert len(set(radii)) == 4
    # Non-cumulative noise is applied to the value written by the user, so it never drifts.
    assert all(0.05 <= radius <= 0.15 for radius in radii)


def test_mjcf_variator_passes_the_user_written_value_as_initial_value():
    root, _, geom = _model()
    seen = []

    class Recorder(variation.Variation):
        def __call__(self, initial_value=None, current_value=None, random_state=None):
            seen.append((np.array(initial_value), np.array(current_value)))
            return current_value * 2

    variator = variation.MJCFVariator()
    variator.bind_attributes(geom, size=Recorder())
    variator.apply_variations(np.random.RandomState(0))
    variator.apply_variations(np.random.RandomState(0))
    np.testing.assert_allclose(seen[1][0], [0.1])
    np.testing.assert_allclose(seen[1][1], [0.2])
    np.testing.assert_allclose(geom.size, [0.4])


def test_mjcf_variator_is_reproducible_from_the_seed():
    root, _, geom = _model()
    variator = variation.MJCFVariator()
    uniform = distributions.Uniform()
    variator.bind_attributes(geom, rgba=colors.RgbVariation(uniform, uniform, uniform))
    variator.apply_variations(np.random.RandomState(3))
    first = np.array(geom.rgba)
    variator.apply_variations(np.random.RandomState(3))
    np.testing.assert_array_equal(geom.rgba, first)


def test_mjcf_variator_sets_constants_and_unbinds_with_none():
    root, body, geom = _model()
    variator = variation.MJCFVariator()
    variator.bind_attributes(geom, mass=5.0, size=deterministic.Constant([0.2]))
    variator.bind_attributes(geom, size=None)
    variator.apply_variations(np.random.RandomState(0))
    assert geom.mass == 5.0
    np.testing.assert_allclose(geom.size, [0.1])


def test_mjcf_variator_clear_removes_all_bindings():
    root, _, geom = _model()
    variator = variation.MJCFVariator()
    variator.bind_attributes(geom, mass=5.0)
    variator.clear()
    variator.apply_variations(np.random.RandomState(0))
    assert geom.mass == 2.0


def test_mjcf_variator_rejects_an_attribute_the_element_does_not_have():
    _, _, geom = _model()
    with pytest.raises(
        AttributeError, match=r"MJCFVariator: <geom name='ball'> has no attribute 'radius'"
    ):
        variation.MJCFVariator().bind_attributes(geom, radius=0.3)


def test_physics_variator_changes_model_values_episode_to_episode():
    root, body, geom = _model()
    physics = mjcf.Physics.from_mjcf_model(root)
    original_mass = physics.bind(body).mass.copy()
    variator = variation.PhysicsVariator()
    variator.bind_attributes(body, mass=noises.Multiplicative(distributions.Uniform(0.5, 1.5)))
    variator.bind_attributes(geom, rgba=colors.GrayVariation(distributions.Uniform()))
    random_state = np.random.RandomState(0)
    masses, colors_seen = [], []
    for _ in range(3):
        variator.apply_variations(physics, random_state)
        masses.append(float(physics.bind(body).mass))
        colors_seen.append(tuple(physics.bind(geom).rgba))
    assert len(set(masses)) == 3 and len(set(colors_seen)) == 3
    assert all(0.5 * original_mass <= mass <= 1.5 * original_mass for mass in masses)
    assert all(rgba[0] == rgba[1] == rgba[2] and rgba[3] == 1.0 for rgba in colors_seen)


def test_physics_variator_writes_data_fields():
    root, body, _ = _model()
    physics = mjcf.Physics.from_mjcf_model(root)
    joint = mjcf.get_freejoint(body)
    variator = variation.PhysicsVariator()
    variator.bind_attributes(
        joint, qpos=deterministic.Constant([0.5, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0])
    )
    variator.apply_variations(physics, np.random.RandomState(0))
    np.testing.assert_allclose(physics.data.qpos, [0.5, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0])


def test_physics_variator_keeps_the_first_seen_value_across_recompiles():
    root, _, geom = _model()
    variator = variation.PhysicsVariator()
    variator.bind_attributes(geom, friction=noises.Multiplicative(2.0))
    for _ in range(2):
        physics = mjcf.Physics.from_mjcf_model(root)
        variator.apply_variations(physics, np.random.RandomState(0))
        np.testing.assert_allclose(physics.bind(geom).friction, [2.0, 0.01, 0.0002])


def test_physics_variator_names_element_and_attribute_it_cannot_bind():
    root, _, geom = _model()
    physics = mjcf.Physics.from_mjcf_model(root)
    variator = variation.PhysicsVariator()
    variator.bind_attributes(geom, radius=0.3)
    with pytest.raises(
        AttributeError, match=r"PhysicsVariator: <geom name='ball'> has no attribute 'radius'"
    ):
        variator.apply_variations(physics, np.random.RandomState(0))
