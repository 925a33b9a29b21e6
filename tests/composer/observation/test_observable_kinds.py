"""Tests of each observable kind against a compiled scene (feature and camera observables)."""

import mujoco
import numpy as np
import pytest

import mjcf
from composer.observation import observable, updater

_HEIGHT, _WIDTH = 24, 32


class _Scene:
    """A red ball on a hinge under a downward camera, with a motor and a sensor."""

    def __init__(self):
        self.model = mjcf.RootElement(model="scene")
        self.model.worldbody.add("light", pos=[0, 0, 3])
        self.model.worldbody.add("geom", type="plane", size=[3, 3, 0.1], rgba=[0, 0, 1, 1])
        self.arm = self.model.worldbody.add("body", name="arm", pos=[0, 0, 0.2])
        self.hinge = self.arm.add("joint", name="hinge", type="hinge", axis=[0, 1, 0])
        self.slide = self.arm.add("joint", name="slide", type="slide", axis=[1, 0, 0])
        self.ball = self.arm.add("geom", name="ball", type="sphere", size=[0.1], rgba=[1, 0, 0, 1])
        self.tip = self.arm.add("site", name="tip", pos=[0.1, 0, 0])
        # Straight above the ball once the joints are set below.
        ball_x = 0.25 * np.cos(0.5)
        self.camera = self.model.worldbody.add("camera", name="top", pos=[ball_x, 0, 2])
        self.motor = self.model.actuator.add("motor", joint=self.hinge)
        self.sensor = self.model.sensor.add("framepos", objtype="site", objname=self.tip)
        self.physics = mjcf.Physics.from_mjcf_model(self.model)
        self.physics.bind([self.hinge, self.slide]).qpos = [0.5, 0.25]
        self.physics.forward()


@pytest.fixture(scope="module")
def scene():
    return _Scene()


def test_mjcf_feature_of_one_site_reads_its_position(scene):
    position = observable.MJCFFeature("xpos", scene.tip)(scene.physics)
    # The slide axis turns with the hinge, so the site sits 0.25 + 0.1 along the turned x.
    expected = [0.35 * np.cos(0.5), 0.0, 0.2 - 0.35 * np.sin(0.5)]
    np.testing.assert_allclose(position, expected, atol=1e-9)


def test_mjcf_feature_of_joint_list_reads_each_joint(scene):
    np.testing.assert_allclose(
        observable.MJCFFeature("qpos", [scene.hinge, scene.slide])(scene.physics), [0.5, 0.25]
    )


def test_mjcf_feature_index_selects_from_the_bound_value(scene):
    obs = observable.MJCFFeature("xpos", scene.tip, index=2)
    assert obs(scene.physics) == pytest.approx(0.2 - 0.35 * np.sin(0.5))


def test_indexing_an_mjcf_feature_gives_an_observable_of_that_slice(scene):
    whole = observable.MJCFFeature("xpos", scene.tip, update_interval=3, delay=2)
    sliced = whole[:2]
    assert sliced is not whole
    np.testing.assert_allclose(sliced(scene.physics), [0.35 * np.cos(0.5), 0.0], atol=1e-9)
    assert (sliced.update_interval, sliced.delay) == (3, 2)
    assert whole(scene.physics).shape == (3,)


def test_indexing_an_indexed_mjcf_feature_indexes_the_slice(scene):
    obs = observable.MJCFFeature("qpos", [scene.hinge, scene.slide])[::-1][0]
    assert obs(scene.physics) == pytest.approx(0.25)


def test_mjcf_feature_reads_sensor_data(scene):
    np.testing.assert_allclose(
        observable.MJCFFeature("sensordata", scene.sensor)(scene.physics),
        observable.MJCFFeature("xpos", scene.tip)(scene.physics),
    )


def test_mjcf_feature_rejects_non_elements():
    with pytest.raises(ValueError, match="mjcf.Element.*str"):
        observable.MJCFFeature("xpos", "tip")


def test_mujoco_feature_reads_by_compiled_name(scene):
    np.testing.assert_allclose(
        observable.MujocoFeature("site_xpos", "tip")(scene.physics),
        observable.MJCFFeature("xpos", scene.tip)(scene.physics),
    )


def test_indexing_any_observable_gives_an_observable_of_that_item(scene):
    obs = observable.MujocoFeature("qpos", ["hinge", "slide"], delay=1)
    item = obs[1]
    assert item(scene.physics) == pytest.approx(0.25)
    assert (item.delay, item.enabled) == (1, False)
    generic = observable.Generic(lambda physics: np.arange(6).reshape(2, 3))[:, 1]
    np.testing.assert_array_equal(generic(scene.physics), [1, 4])


def test_indexed_observable_corrupts_the_indexed_value(scene):
    obs = observable.Generic(
        lambda physics: np.array([1.0, 2.0, 3.0]),
        corruptor=lambda value, random_state: value * 10,
    )[1:]
    np.testing.assert_array_equal(obs(scene.physics), [20.0, 30.0])


def test_mujoco_feature_name_may_be_a_callable(scene):
    obs = observable.MujocoFeature("qpos", lambda: ["slide"])
    np.testing.assert_allclose(obs(scene.physics), [0.25])


def test_mjcf_camera_rejects_elements_that_are_not_cameras(scene):
    with pytest.raises(ValueError, match="<camera>.*<site>"):
        observable.MJCFCamera(scene.tip)


def test_mjcf_camera_renders_the_red_ball_below_it(scene):
    image = observable.MJCFCamera(scene.camera, height=_HEIGHT, width=_WIDTH)(scene.physics)
    assert (image.shape, image.dtype) == ((_HEIGHT, _WIDTH, 3), np.uint8)
    red, green, blue = image[_HEIGHT // 2, _WIDTH // 2].astype(int)
    assert red > 50 and red > 3 * max(green, blue)


def test_mjcf_camera_depth_is_the_distance_to_the_ball_top(scene):
    camera = observable.MJCFCamera(scene.camera, height=_HEIGHT, width=_WIDTH, depth=True)
    depth = camera(scene.physics)
    assert (depth.shape, depth.dtype) == ((_HEIGHT, _WIDTH, 1), np.float32)
    ball_top = scene.physics.bind(scene.ball).xpos[2] + 0.1
    assert depth[_HEIGHT // 2, _WIDTH // 2, 0] == pytest.approx(2.0 - ball_top, abs=0.02)


def test_mjcf_camera_segmentation_labels_the_ball_geom(scene):
    camera = observable.MJCFCamera(scene.camera, height=_HEIGHT, width=_WIDTH, segmentation=True)
    labels = camera(scene.physics)
    assert labels.shape == (_HEIGHT, _WIDTH, 2)
    ball_id = scene.physics.bind(scene.ball).element_id
    assert labels[_HEIGHT // 2, _WIDTH // 2, 0] == ball_id


def test_mujoco_camera_by_name_matches_mjcf_camera(scene):
    by_name = observable.MujocoCamera("top", height=_HEIGHT, width=_WIDTH)(scene.physics)
    by_element = observable.MJCFCamera(scene.camera, height=_HEIGHT, width=_WIDTH)(scene.physics)
    np.testing.assert_array_equal(by_name, by_element)


def test_mujoco_camera_with_unknown_name_is_an_error(scene):
    with pytest.raises(ValueError, match="'nowhere'"):
        observable.MujocoCamera("nowhere")(scene.physics)


def _enabled(obs):
    obs.enabled = True
    return obs


@pytest.mark.parametrize("strip", [False, True])
def test_spec_and_observation_agree_for_every_kind(scene, strip):
    observables = {
        "generic": _enabled(observable.Generic(lambda physics: physics.data.time)),
        "mujoco_feature": _enabled(observable.MujocoFeature("xpos", "arm", buffer_size=2)),
        "mjcf_feature": _enabled(observable.MJCFFeature("qpos", [scene.hinge, scene.slide])),
        "mjcf_camera": _enabled(observable.MJCFCamera(scene.camera, height=8, width=12)),
        "depth": _enabled(
            observable.MJCFCamera(scene.camera, height=8, width=12, depth=True, buffer_size=2)
        ),
        "segmentation": _enabled(
            observable.MujocoCamera("top", height=8, width=12, segmentation=True)
        ),
        "mean_of_feature": _enabled(
            observable.MJCFFeature("xpos", scene.tip, buffer_size=3, aggregator="mean")
        ),
    }
    obs_updater = updater.Updater(observables, 2, strip_singleton_buffer_dim=strip)
    obs_updater.reset(scene.physics, np.random.RandomState(0))
    specs = obs_updater.observation_spec()
    obs_updater.prepare_for_next_control_step()
    obs_updater.update()
    obs_updater.update()
    observation = obs_updater.get_observation()
    assert list(specs) == list(observation) == list(observables)
    for name, spec in specs.items():
        spec.validate(observation[name])


def _lowest(physics):
    return np.zeros(1)


class _Opaque:
    """A callable without a `__qualname__` attribute of its own."""

    def __call__(self, physics):
        return np.zeros(1)

    def __getattribute__(self, name):
        if name == "__qualname__":
            raise AttributeError(name)
        return object.__getattribute__(self, name)

    def __repr__(self):
        return "opaque"


def test_reprs_name_the_kind_and_what_is_observed(scene):
    # What a user sees when printing `task.observables` while debugging.
    assert repr(observable.Generic(_lowest)) == "<Generic observable of _lowest>"
    assert repr(observable.Generic(_Opaque())) == "<Generic observable of opaque>"
    feature = observable.MJCFFeature("xpos", scene.tip)
    assert repr(feature) == f"<MJCFFeature observable 'xpos' of {scene.tip!r}>"
    assert repr(feature[0][1:]) == (
        f"<MJCFFeature observable 'xpos'[0][slice(1, None, None)] of {scene.tip!r}>"
    )
    assert repr(observable.Generic(_lowest)[0]) == "<Generic observable of _lowest>[0]"
    assert repr(observable.MujocoFeature("qpos", "hinge")) == (
        "<MujocoFeature observable qpos['hinge']>"
    )


class _Plain(observable.Observable):
    def _callable(self, physics):
        return lambda: np.zeros(1)


def test_repr_of_a_user_subclass_names_the_subclass():
    assert repr(_Plain(1, None, None, None, None)) == "<_Plain observable>"


def _with_options(obs):
    return (obs.update_interval, obs.buffer_size, obs.delay, obs.aggregator, obs.corruptor)


def _double(value, random_state):
    return 2 * value


_OPTIONS = dict(update_interval=3, buffer_size=4, delay=2, aggregator="max", corruptor=_double)


@pytest.mark.parametrize("kind", ["mjcf_feature", "generic"])
def test_indexing_keeps_every_option_of_the_observable(scene, kind):
    if kind == "mjcf_feature":
        obs = observable.MJCFFeature("xpos", scene.tip, **_OPTIONS)
    else:
        obs = observable.Generic(lambda physics: np.ones(3), **_OPTIONS)
    assert _with_options(obs[1:]) == _with_options(obs)
    assert _with_options(obs[1:]) == (3, 4, 2, obs.aggregator, _double)


def test_updater_follows_a_mujoco_feature_named_by_a_callable(scene):
    # The updater gathers plain features from MuJoCo's arrays; a callable name is read
    # through the callable at every sample instead.
    names = ["slide"]
    obs = _enabled(observable.MujocoFeature("qpos", lambda: names))
    obs_updater = updater.Updater({"joint": obs})
    obs_updater.reset(scene.physics, np.random.RandomState(0))
    np.testing.assert_allclose(obs_updater.get_observation()["joint"], [[0.25]])
    names[0] = "hinge"
    obs_updater.prepare_for_next_control_step()
    obs_updater.update()
    np.testing.assert_allclose(obs_updater.get_observation()["joint"], [[0.5]])


@pytest.mark.parametrize("kind", ["mjcf", "mujoco"])
def test_camera_defaults_are_dm_controls(scene, kind):
    # dm_control's defaults: a 240x320 RGB image sampled every step; buffer and delay left
    # to the updater's defaults.
    if kind == "mjcf":
        camera = observable.MJCFCamera(scene.camera)
    else:
        camera = observable.MujocoCamera("top")
    spec = camera.array_spec
    assert (spec.shape, spec.dtype) == ((240, 320, 3), np.uint8)
    assert (camera.update_interval, camera.buffer_size, camera.delay) == (1, None, None)
    assert (camera.depth, camera.segmentation) == (False, False)
    assert camera(scene.physics).shape == (240, 320, 3)


@pytest.mark.parametrize(
    ("name", "expected"),
    [("mean", [2.0, 20.0]), ("sum", [6, 60]), ("min", [1, 10]), ("max", [3, 30])],
)
@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.int64])
def test_named_aggregators_reduce_the_buffer_axis_for_every_dtype(name, expected, dtype):
    buffer = np.array([[1, 10], [2, 20], [3, 30]], dtype)
    aggregator = observable.Generic(lambda physics: 0, aggregator=name).aggregator
    result = aggregator(buffer)
    assert result.shape == (2,)
    np.testing.assert_allclose(result, expected)


@pytest.mark.parametrize("kind", ["mjcf_feature", "mujoco_feature", "mjcf_camera", "mujoco_camera"])
def test_constructor_options_are_kept(scene, kind):
    if kind == "mjcf_feature":
        obs = observable.MJCFFeature("qpos", scene.hinge, **_OPTIONS)
    elif kind == "mujoco_feature":
        obs = observable.MujocoFeature("qpos", "hinge", **_OPTIONS)
    elif kind == "mjcf_camera":
        obs = observable.MJCFCamera(scene.camera, height=8, width=12, **_OPTIONS)
    else:
        obs = observable.MujocoCamera("top", height=8, width=12, **_OPTIONS)
    assert _with_options(obs)[:3] == (3, 4, 2)
    assert obs.aggregator(np.array([[1.0], [5.0]])).tolist() == [5.0]
    assert obs.corruptor is _double


def test_mujoco_feature_samples_every_step_by_default():
    assert observable.MujocoFeature("qpos", "hinge").update_interval == 1


def test_mujoco_camera_accepts_a_camera_id(scene):
    by_name = observable.MujocoCamera("top", height=8, width=12)(scene.physics)
    by_id = observable.MujocoCamera(0, height=8, width=12)(scene.physics)
    np.testing.assert_array_equal(by_id, by_name)


def _red_pixels(image):
    return int(np.sum((image[..., 0] > 150) & (image[..., 1] < 80)))


@pytest.mark.parametrize("kind", ["mjcf_camera", "mujoco_camera"])
def test_camera_scene_option_and_render_flags_reach_the_renderer(scene, kind):
    def camera(**_OPTIONS):
        if kind == "mjcf_camera":
            return observable.MJCFCamera(scene.camera, height=24, width=32, **_OPTIONS)
        return observable.MujocoCamera("top", height=24, width=32, **_OPTIONS)

    plain = camera()(scene.physics)
    assert _red_pixels(plain) > 0
    # Hiding geom group 0 hides the red ball (and the floor).
    hidden = mujoco.MjvOption()
    hidden.geomgroup[0] = 0
    assert _red_pixels(camera(scene_option=hidden)(scene.physics)) == 0
    wireframe = camera(render_flag_overrides={"wireframe": True})(scene.physics)
    assert not np.array_equal(wireframe, plain)
    np.testing.assert_array_equal(camera()(scene.physics), plain)


def test_mjcf_camera_error_for_a_non_element_names_the_observable():
    with pytest.raises(ValueError) as raised:
        observable.MJCFCamera("top")
    assert str(raised.value) == "MJCFCamera: expected an mjcf.Element, got str: 'top'"


def test_a_one_pixel_camera_is_allowed_and_zero_is_not(scene):
    pixel = observable.MujocoCamera("top", height=1, width=1)
    assert pixel(scene.physics).shape == (1, 1, 3)
    with pytest.raises(ValueError, match="option 'height' must be an integer >= 1; got 0"):
        observable.MujocoCamera("top", height=0, width=1)


@pytest.mark.parametrize("elements", ["hinge", ["hinge"]], ids=["one", "list"])
def test_mjcf_feature_error_for_a_non_element_names_the_feature(elements):
    with pytest.raises(ValueError) as raised:
        observable.MJCFFeature("qpos", elements)
    assert str(raised.value) == "MJCFFeature('qpos'): expected an mjcf.Element, got str: 'hinge'"


def test_unknown_aggregator_name_is_a_key_error_listing_the_names():
    with pytest.raises(KeyError) as raised:
        observable.Generic(lambda physics: 0, aggregator="average")
    assert "unknown name 'average'; expected one of ['max', 'mean', 'median', 'min', 'sum']" in str(
        raised.value
    )


def test_aggregator_that_is_not_a_name_or_callable_is_a_type_error_saying_what_is_allowed():
    with pytest.raises(TypeError) as raised:
        observable.Generic(lambda physics: 0, aggregator=3)
    assert "aggregator: expected a name from ['max', 'mean', 'median', 'min', 'sum'], a " in str(
        raised.value
    )
    assert str(raised.value).endswith("a callable or None, got 3")
