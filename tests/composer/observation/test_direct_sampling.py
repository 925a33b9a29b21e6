"""Direct sampling: observables whose values live in MuJoCo arrays are gathered, not called.

Every test compares against the same observables with an identity corruptor, which rules
direct sampling out, so the observations must be identical.
"""

import collections

import numpy as np
import pytest

import mjcf
from composer.observation import observable, updater
from composer.observation.observable import base

_SUB_STEPS = 5


class _Scene:
    """A hinge-and-slide arm with a tip site and sensor, and a free ball, under gravity."""

    def __init__(self):
        self.model = mjcf.RootElement(model="scene")
        self.model.option.timestep = 0.005
        self.model.worldbody.add("geom", type="plane", size=[3, 3, 0.1])
        arm = self.model.worldbody.add("body", name="arm", pos=[0, 0, 0.5])
        self.hinge = arm.add("joint", name="hinge", type="hinge", axis=[0, 1, 0], damping=0.1)
        self.slide = arm.add("joint", name="slide", type="slide", axis=[1, 0, 0], damping=1)
        arm.add("geom", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.03])
        self.tip = arm.add("site", name="tip", pos=[0.3, 0, 0])
        self.ball = self.model.worldbody.add("body", name="ball", pos=[0.5, 0.5, 0.3])
        self.ball.add("freejoint")
        self.ball.add("geom", type="sphere", size=[0.05])
        self.sensor = self.model.sensor.add("framepos", objtype="site", objname=self.tip)
        self.model.actuator.add("motor", joint=self.hinge)
        self.physics = mjcf.Physics.from_mjcf_model(self.model)


def _observables(scene, corrupted=False):
    """Observables of every kind that can be sampled directly, and some that cannot."""
    options = {"corruptor": lambda value, random_state: value} if corrupted else {}
    joints = [scene.hinge, scene.slide]
    observables = collections.OrderedDict(
        joints_qpos=observable.MJCFFeature("qpos", joints, **options),
        # Rows out of order: the binding gathers them into a buffer, which is not live.
        reversed_qpos=observable.MJCFFeature("qpos", joints[::-1], **options),
        joints_qvel_every_3=observable.MJCFFeature("qvel", joints, update_interval=3, **options),
        tip=observable.MJCFFeature("xpos", scene.tip, **options),
        tip_xy=observable.MJCFFeature("xpos", scene.tip, index=slice(0, 2), **options),
        tip_z=observable.MJCFFeature("xpos", scene.tip, index=2, **options),
        ball_rotation=observable.MJCFFeature("xmat", scene.ball, **options),
        ball_velocity=observable.MJCFFeature("cvel", scene.ball, **options),
        sensor=observable.MJCFFeature("sensordata", scene.sensor, **options),
        named_tip=observable.MujocoFeature("site_xpos", "tip", **options),
        tip_history=observable.MJCFFeature("xpos", scene.tip, buffer_size=2, **options),
        tip_xz_of_slice=observable.MJCFFeature("xpos", scene.tip, **options)[::2],
        named_tip_y=observable.MujocoFeature("site_xpos", "tip", **options)[1],
        named_ball_quat_xyz=observable.MujocoFeature("xquat", "ball", **options)[1:],
    )
    for obs in observables.values():
        obs.enabled = True
    return observables


def _updater(observables, strip=False):
    return updater.Updater(observables, _SUB_STEPS, strip_singleton_buffer_dim=strip)


def _run(scene, updaters, control_steps, between_steps=None):
    """Steps the scene under random torques; returns each updater's observations."""
    physics = scene.physics
    random_state = np.random.RandomState(0)
    for each in updaters:
        each.reset(physics, np.random.RandomState(1))
    observations = [[each.get_observation()] for each in updaters]
    for _ in range(control_steps):
        physics.set_control(random_state.uniform(-1, 1, size=1))
        for each in updaters:
            each.prepare_for_next_control_step()
        for _ in range(_SUB_STEPS):
            physics.step()
            if between_steps is not None:
                between_steps(physics)
            for each in updaters:
                each.update()
        for each, seen in zip(updaters, observations):
            seen.append(each.get_observation())
    return observations


def _assert_same_observations(first, second):
    assert len(first) == len(second)
    for one, other in zip(first, second):
        assert list(one) == list(other)
        for name in one:
            assert one[name].dtype == other[name].dtype, name
            np.testing.assert_array_equal(one[name], other[name], err_msg=name)


@pytest.mark.parametrize("strip", [False, True])
def test_directly_sampled_observations_equal_those_of_the_observables_callables(strip):
    scene = _Scene()
    direct = _updater(_observables(scene), strip)
    called = _updater(_observables(scene, corrupted=True), strip)
    direct_seen, called_seen = _run(scene, [direct, called], control_steps=8)
    _assert_same_observations(direct_seen, called_seen)


def test_mjcf_and_mujoco_features_that_read_views_have_live_sources():
    scene = _Scene()
    observables = _observables(scene)
    live = [name for name, obs in observables.items() if obs.live_source(scene.physics)]
    assert set(live) == {
        "joints_qpos",
        "joints_qvel_every_3",
        "tip",
        "tip_xy",
        "ball_rotation",
        "ball_velocity",
        "sensor",
        "named_tip",
        "tip_history",
        "tip_xz_of_slice",
        "named_tip_y",
        "named_ball_quat_xyz",
    }


def test_live_source_holds_the_observed_value():
    scene = _Scene()
    scene.physics.step(3)
    for name, obs in _observables(scene).items():
        source = obs.live_source(scene.physics)
        if source is not None:
            array, indices = source
            np.testing.assert_array_equal(array[indices], obs(scene.physics), err_msg=name)


def test_corruptor_rules_out_a_live_source():
    scene = _Scene()
    obs = observable.MJCFFeature("xpos", scene.tip, corruptor=lambda v, random_state: v)
    assert obs.live_source(scene.physics) is None


def test_observations_after_a_binding_write_show_the_state_written():
    # A write through a binding leaves derived quantities stale until the next forward();
    # sampling must run it, as reading through the binding does.
    scene = _Scene()
    direct = _updater(_observables(scene))

    def move_the_arm(physics):
        physics.bind(scene.hinge).qpos = physics.bind(scene.hinge).qpos + 0.01

    (direct_seen,) = _run(scene, [direct], control_steps=2, between_steps=move_the_arm)
    scene.physics.forward()
    np.testing.assert_array_equal(direct_seen[-1]["tip"][0], scene.physics.bind(scene.tip).xpos)
    np.testing.assert_array_equal(direct_seen[-1]["sensor"][0], scene.physics.bind(scene.tip).xpos)


def test_options_changed_between_episodes_take_effect():
    scene = _Scene()
    observables = _observables(scene)
    direct = _updater(observables)
    direct.reset(scene.physics, np.random.RandomState(1))
    observables["tip"].corruptor = lambda value, random_state: value + 1.0
    observables["joints_qpos"].buffer_size = 3
    direct.reset(scene.physics, np.random.RandomState(1))
    observation = direct.get_observation()
    np.testing.assert_array_equal(observation["tip"][0], scene.physics.bind(scene.tip).xpos + 1)
    assert observation["joints_qpos"].shape == (3, 2)


def _single(obs):
    obs.enabled = True
    return {"only": obs}


def test_a_corruptor_set_between_episodes_is_applied():
    # Only the corruptor changes, on the one observable there is.
    scene = _Scene()
    observables = _single(observable.MJCFFeature("xpos", scene.tip))
    direct = _updater(observables)
    _run(scene, [direct], control_steps=1)[0][-1]
    observables["only"].corruptor = lambda value, random_state: value + 1.0
    observation = _run(scene, [direct], control_steps=1)[0][-1]
    np.testing.assert_array_equal(observation["only"][0], scene.physics.bind(scene.tip).xpos + 1)


def test_an_observable_replaced_between_episodes_is_the_one_read():
    scene = _Scene()
    observables = _single(observable.MJCFFeature("qpos", [scene.hinge, scene.slide]))
    direct = _updater(observables)
    _run(scene, [direct], control_steps=1)[0][-1]
    observables.update(_single(observable.MJCFFeature("qpos", [scene.slide, scene.slide])))
    observation = _run(scene, [direct], control_steps=1)[0][-1]
    slide = scene.physics.bind(scene.slide).qpos[0]
    assert slide != 0
    np.testing.assert_array_equal(observation["only"], [[slide, slide]])


@pytest.mark.parametrize("change", ["enable_one_more", "disable_one"])
def test_observables_enabled_or_disabled_between_episodes_are_observed_accordingly(change):
    scene = _Scene()
    observables = _observables(scene)
    observables["extra_tip"] = observable.MJCFFeature("xpos", scene.tip)
    direct = _updater(observables)
    _run(scene, [direct], control_steps=1)[0][-1]
    if change == "enable_one_more":
        observables["extra_tip"].enabled = True
    else:
        observables["tip"].enabled = False
    observation = _run(scene, [direct], control_steps=1)[0][-1]
    tip = scene.physics.bind(scene.tip).xpos
    assert ("extra_tip" in observation) is (change == "enable_one_more")
    assert ("tip" in observation) is (change == "enable_one_more")
    for name in ("extra_tip", "tip"):
        if name in observation:
            np.testing.assert_array_equal(observation[name][0], tip)


def test_later_episodes_observe_as_the_first_does():
    scene = _Scene()
    direct = _updater(_observables(scene))
    called = _updater(_observables(scene, corrupted=True))
    first = _run(scene, [direct, called], control_steps=3)
    second = _run(scene, [direct, called], control_steps=3)
    _assert_same_observations(*first)
    _assert_same_observations(*second)


def test_physics_reloaded_between_episodes_is_the_one_observed():
    scene = _Scene()
    direct = _updater(_observables(scene))
    direct.reset(scene.physics, np.random.RandomState(1))
    scene.physics.reload_from_mjcf_model(scene.model)
    direct.reset(scene.physics, np.random.RandomState(1))
    direct.prepare_for_next_control_step()
    for _ in range(_SUB_STEPS):
        scene.physics.step()
        direct.update()
    ball_velocity = scene.physics.bind(scene.ball).cvel
    assert np.any(ball_velocity != 0)
    np.testing.assert_array_equal(direct.get_observation()["ball_velocity"][0], ball_velocity)


def test_view_source_locates_a_strided_view_of_a_mujoco_array():
    physics = _Scene().physics
    physics.step(2)
    xmat = physics.data.ptr.xmat
    z_axes = xmat[:, 2::3]
    flat, indices = base.view_source(z_axes)
    assert flat.shape == (xmat.size,)
    np.testing.assert_array_equal(flat[indices], z_axes)


@pytest.mark.parametrize(
    "value",
    [np.zeros(3), np.zeros((2, 3))[:, 1], 1.5, [1.0, 2.0]],
    ids=["numpy_owned", "view_of_numpy_owned", "float", "list"],
)
def test_view_source_is_none_for_memory_numpy_owns_and_for_non_arrays(value):
    assert base.view_source(value) is None


def _foreign_floats(size):
    """A float64 array over memory NumPy does not own, as MuJoCo's arrays are."""
    return np.frombuffer(bytearray(8 * size), np.float64)


def test_view_source_of_a_reinterpreted_view_is_none():
    assert base.view_source(_foreign_floats(4).view(np.int64)) is None


def test_view_source_of_a_view_between_elements_is_none():
    root = _foreign_floats(4)
    straddling = np.ndarray((2,), np.float64, buffer=root, offset=4)
    assert base.view_source(straddling) is None


def test_view_source_of_foreign_memory_gives_its_element_indices():
    root = _foreign_floats(6)
    flat, indices = base.view_source(root.reshape(2, 3)[:, 1:])
    assert flat.shape == (6,)
    assert indices.tolist() == [[1, 2], [4, 5]]


def test_view_source_of_a_copy_is_none():
    physics = _Scene().physics
    assert base.view_source(physics.data.ptr.xpos[1].copy()) is None


class _CountedFeature(observable.MJCFFeature):
    """An MJCFFeature that counts the calls of its observation callable."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.calls = 0

    def _callable(self, physics):
        read = super()._callable(physics)

        def counted():
            self.calls += 1
            return read()

        return counted


class _ClockWithWriter(observable.Observable):
    """Physics time, with a writer; counts the calls of its observation callable."""

    def __init__(self):
        super().__init__(1, None, None, None, None)
        self.calls = 0

    def _callable(self, physics):
        def read():
            self.calls += 1
            return np.array([physics.data.time])

        return read

    def _writer(self, physics, out):
        def write():
            out[0] = physics.data.time

        return write


def test_observables_read_from_mujoco_memory_or_written_are_sampled_without_calls():
    # A gathered live source and an observable with a writer: neither is called while
    # stepping, and both observe what the physics holds.
    scene = _Scene()
    feature = _CountedFeature("qpos", [scene.hinge, scene.slide])
    bodies = _CountedFeature("xpos", [scene.model.find("body", "arm"), scene.ball])
    clock = _ClockWithWriter()
    observables = {"feature": feature, "bodies": bodies, "clock": clock}
    for obs in observables.values():
        obs.enabled = True
    direct = _updater(observables)
    direct.reset(scene.physics, np.random.RandomState(1))
    calls_at_reset = feature.calls, bodies.calls, clock.calls
    for _ in range(3):
        direct.prepare_for_next_control_step()
        scene.physics.set_control([0.5])
        for _ in range(_SUB_STEPS):
            scene.physics.step()
            direct.update()
    observation = direct.get_observation()
    assert (feature.calls, bodies.calls, clock.calls) == calls_at_reset
    qpos = scene.physics.bind([scene.hinge, scene.slide]).qpos
    assert qpos[0] != 0
    np.testing.assert_array_equal(observation["feature"], [qpos])
    np.testing.assert_array_equal(observation["clock"], [[scene.physics.data.time]])
    np.testing.assert_array_equal(
        observation["bodies"],
        [scene.physics.bind([scene.model.find("body", "arm"), scene.ball]).xpos],
    )


def test_features_of_two_arrays_of_one_size_read_each_its_own_array():
    # qpos and qvel of a single hinge are both one float64: gathered from different arrays.
    model = mjcf.RootElement()
    body = model.worldbody.add("body")
    hinge = body.add("joint", type="hinge", axis=[0, 1, 0])
    body.add("geom", type="capsule", fromto=[0, 0, 0, 0.3, 0, 0], size=[0.03])
    physics = mjcf.Physics.from_mjcf_model(model)
    observables = {
        "qpos": observable.MJCFFeature("qpos", hinge),
        "qvel": observable.MJCFFeature("qvel", hinge),
    }
    for obs in observables.values():
        obs.enabled = True
    direct = updater.Updater(observables, 2)
    direct.reset(physics, np.random.RandomState(1))
    direct.prepare_for_next_control_step()
    physics.bind(hinge).qvel = 1.5
    physics.forward()
    for _ in range(2):
        physics.step()
        direct.update()
    observation = direct.get_observation()
    np.testing.assert_array_equal(observation["qpos"], [physics.bind(hinge).qpos])
    np.testing.assert_array_equal(observation["qvel"], [physics.bind(hinge).qvel])
    assert observation["qpos"][0] != observation["qvel"][0]


def test_an_integer_model_field_is_observed_with_its_dtype():
    scene = _Scene()
    geom = scene.model.find_all("geom")[0]
    obs = observable.MJCFFeature("contype", geom)
    obs.enabled = True
    direct = _updater({"contype": obs})
    observation = _run(scene, [direct], control_steps=1)[0][-1]["contype"]
    assert observation.dtype == scene.physics.bind(geom).contype.dtype == np.int32
    np.testing.assert_array_equal(observation, [1])


class _TimeWithSource(observable.Observable):
    """Physics time as a (1,) array; `source(physics)` is what `_live_source` returns."""

    def __init__(self, source):
        super().__init__(1, None, None, None, None)
        self._source = source

    def _callable(self, physics):
        return lambda: np.array([physics.data.time])

    def _live_source(self, physics):
        return self._source(physics)


@pytest.mark.parametrize(
    "source",
    [
        lambda physics: (np.zeros((1, 1)), np.array([0])),
        lambda physics: (np.zeros(1, np.float32), np.array([0])),
        lambda physics: (np.zeros(3), np.array([0, 1])),
        lambda physics: (np.zeros(3), np.array([0.0])),
        lambda physics: (np.zeros(3), np.array([3])),
        lambda physics: (np.zeros(3), np.array([-1])),
        lambda physics: ([0.0], np.array([0])),
    ],
    ids=["2d_array", "other_dtype", "other_shape", "float_indices", "past_end", "negative", "list"],
)
def test_an_unusable_live_source_is_ignored_and_the_observable_called(source):
    # The source arrays hold zeros; the observable's value, the physics time, is not zero.
    scene = _Scene()
    direct = _updater(_single(_TimeWithSource(source)))
    observation = _run(scene, [direct], control_steps=1)[0][-1]
    assert observation["only"].tolist() == [[scene.physics.data.time]]


def test_a_live_source_of_integers_is_gathered_with_its_dtype():
    scene = _Scene()
    foreign = np.frombuffer(bytearray(12), np.int32)

    class Counter(observable.Observable):
        def _callable(self, physics):
            return lambda: foreign[1:2].copy()

        def _live_source(self, physics):
            return foreign, np.array([1])

    obs = Counter(1, None, None, None, None)
    obs.enabled = True
    direct = _updater({"count": obs})
    direct.reset(scene.physics, np.random.RandomState(1))
    direct.prepare_for_next_control_step()
    foreign[1] = 7
    for _ in range(_SUB_STEPS):
        scene.physics.step()
        direct.update()
    observation = direct.get_observation()["count"]
    assert observation.dtype == np.int32
    assert observation.tolist() == [[7]]


def test_an_update_interval_changed_between_episodes_changes_when_it_samples():
    # Two features of one array share a gather while their intervals agree. Once one samples
    # every 2nd sub-step, after 5 sub-steps it shows the value of sub-step 4.
    scene = _Scene()
    observables = {
        "hinge": observable.MJCFFeature("qpos", scene.hinge),
        "slide": observable.MJCFFeature("qpos", scene.slide),
    }
    for obs in observables.values():
        obs.enabled = True
    direct = _updater(observables)
    _run(scene, [direct], control_steps=1)[0][-1]
    observables["slide"].update_interval = 2
    direct.reset(scene.physics, np.random.RandomState(1))
    direct.prepare_for_next_control_step()
    scene.physics.set_control([0.5])
    scene.physics.bind(scene.slide).qvel = 1.0
    scene.physics.forward()
    slides = []
    for _ in range(_SUB_STEPS):
        scene.physics.step()
        slides.append(scene.physics.bind(scene.slide).qpos[0])
        direct.update()
    observation = direct.get_observation()
    assert slides[3] != slides[4]
    assert observation["slide"].tolist() == [[slides[3]]]
    assert observation["hinge"].tolist() == [[scene.physics.bind(scene.hinge).qpos[0]]]
