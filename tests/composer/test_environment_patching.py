"""composer.Environment resets that patch the compiled model instead of recompiling it."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from composer_scene import ReachTask, assert_same_episodes, play_episodes

import composer
import mjcf
from mjcf.patching import compiled_model


class VariedTask(ReachTask):
    """Before every episode: a random box colour, floor friction and joint friction loss
    (values that patch), all drawn from the environment's random stream."""

    def __init__(self):
        super().__init__()
        self.after_compile_calls = 0

    def initialize_episode_mjcf(self, random_state):
        self.box.geom.rgba = [*random_state.uniform(size=3), 1]
        ground = self.arena.mjcf_model.find("geom", "ground")
        ground.friction = [random_state.uniform(0.3, 1.5), 0.005, 0.0001]
        for joint in self.arm.joints:
            joint.frictionloss = random_state.uniform(0.0, 0.5)

    def after_compile(self, physics, random_state):
        self.after_compile_calls += 1
        # Consumes the random stream, so a missed or extra call would shift everything after.
        random_state.uniform()


class MovingTask(ReachTask):
    """Before every episode: a goal site, a welded post (a body without joints), the arm's
    upper body (on a hinge) and the arm's tip site moved and turned, all drawn from the
    environment's random stream (poses that patch)."""

    def __init__(self):
        super().__init__()
        worldbody = self.arena.mjcf_model.worldbody
        self.goal = worldbody.add("site", name="goal", pos=[0.3, 0, 0.01], size=[0.02])
        self.post = worldbody.add("body", name="post", pos=[0.6, 0.2, 0])
        self.post.add("geom", type="box", size=[0.02, 0.02, 0.2], pos=[0, 0, 0.2])

    def initialize_episode_mjcf(self, random_state):
        self.goal.pos = [*random_state.uniform(-0.4, 0.4, size=2), 0.01]
        self.post.pos = [*random_state.uniform(0.5, 0.7, size=2), 0]
        self.post.quat = [1, 0, 0, random_state.uniform(-1, 1)]
        self.arm.mjcf_model.find("body", "upper").pos = [0, 0, random_state.uniform(0.4, 0.6)]
        self.arm.tip.quat = [1, random_state.uniform(-1, 1), 0, 0]


@pytest.mark.patches_from_3_17
def test_moved_sites_and_bodies_patch_without_compiling_and_bit_identically(compiles):
    patched_env = composer.Environment(MovingTask(), random_state=3)
    compiled_env = composer.Environment(MovingTask(), random_state=3, patch_compiled_model=False)
    compiles.clear()
    patched = play_episodes(patched_env, 6, 10)
    assert compiles == []  # every reset patched
    compiled = play_episodes(compiled_env, 6, 10)
    assert len(compiles) == 6  # dm_control's way: a compile per episode
    assert_same_episodes(patched, compiled)
    # The viewer's framing follows the moved things, as a recompile's does.
    for name in ("center", "extent", "meaninertia"):
        np.testing.assert_array_equal(
            getattr(patched_env.physics.model.stat, name),
            getattr(compiled_env.physics.model.stat, name),
        )


def test_twenty_seeded_episodes_are_bit_identical_with_patching_on_and_off():
    patched_env = composer.Environment(VariedTask(), random_state=3)
    compiled_env = composer.Environment(VariedTask(), random_state=3, patch_compiled_model=False)
    patched, compiled = play_episodes(patched_env, 20, 10), play_episodes(compiled_env, 20, 10)
    assert len(patched) == 20 * 11
    assert_same_episodes(patched, compiled)
    assert patched_env.task.after_compile_calls == compiled_env.task.after_compile_calls == 21


def test_a_reset_that_changes_only_patchable_values_does_not_compile(monkeypatch, compiles):
    env = composer.Environment(VariedTask(), random_state=3)
    compiles.clear()  # counts from here on
    for _ in range(5):
        env.reset()
    assert compiles == []


def test_patched_values_are_what_bind_reads_and_survive_episode_writes():
    task = VariedTask()
    env = composer.Environment(task, random_state=3)
    env.reset()
    ground = task.arena.mjcf_model.find("geom", "ground")
    friction = env.physics.bind(ground).friction
    friction[:] = 9.0
    env.reset()
    np.testing.assert_array_equal(env.physics.bind(ground).friction, ground.friction)
    np.testing.assert_array_equal(
        env.physics.bind(task.box.geom).rgba, task.box.geom.rgba.astype(np.float32)
    )
    np.testing.assert_array_equal(
        env.physics.bind(task.arm.joints).frictionloss,
        [joint.frictionloss for joint in task.arm.joints],
    )


def test_turning_patching_off_recompiles_every_changed_model(monkeypatch, compiles):
    env = composer.Environment(VariedTask(), random_state=3, patch_compiled_model=False)
    compiles.clear()  # counts from here on
    for _ in range(3):
        env.reset()
    assert len(compiles) == 3


def test_a_change_that_is_not_patchable_recompiles(monkeypatch, compiles):
    task = VariedTask()
    env = composer.Environment(task, random_state=3)
    compiles.clear()  # counts from here on
    task.box.geom.pos = [0.01, 0, 0]
    env.reset()
    assert len(compiles) == 1
    np.testing.assert_array_equal(env.physics.bind(task.box.geom).pos, [0.01, 0, 0])


class Brick(composer.Entity):
    """A toy brick whose mass comes from its geoms: walls, a massless lid, knobs of the
    default class 'knob' (a cylinder whose radius `initialize_episode_mjcf` draws) and a
    massless helper capsule."""

    def _build(self, name="brick"):
        self._model = mjcf.RootElement(model=name)
        knob = self._model.default.add("default", dclass="knob")
        knob.geom.set_attributes(type="cylinder", size=[0.005, 0.002], density=500)
        self.knob_geom = knob.geom
        body = self._model.worldbody
        body.add("geom", name="lid", type="box", size=[0.02, 0.01, 0.001], pos=[0, 0, 0.01], mass=0)
        for side in (-1, 1):
            body.add("geom", type="box", size=[0.02, 0.001, 0.01], pos=[0, side * 0.009, 0])
        for x in (-0.01, 0, 0.01):
            body.add("geom", dclass="knob", pos=[x, 0, 0.012])
        body.add("geom", type="capsule", size=[0.003, 0.002], pos=[0, 0, 0.013], mass=0)

    def initialize_episode_mjcf(self, random_state):
        self.knob_geom.size = [random_state.uniform(0.004, 0.006), 0.002]

    @property
    def mjcf_model(self):
        return self._model


class BrickTask(ReachTask):
    """The reach task with a brick whose knob radius changes every episode."""

    def __init__(self):
        super().__init__()
        self.brick = Brick()
        self.arena.add_free_entity(self.brick)

    def initialize_episode(self, physics, random_state):
        super().initialize_episode(physics, random_state)
        self.brick.set_pose(physics, position=[0.3, 0.3, 0.0105], quaternion=[1, 0, 0, 0])


@pytest.mark.patches_from_3_17
def test_a_default_class_cylinder_radius_drawn_every_episode_patches_bit_identically(
    monkeypatch, compiles
):
    outcomes = []
    update = compiled_model.CompiledModel.update

    def recording(self, root):
        outcomes.append(update(self, root))
        return outcomes[-1]

    monkeypatch.setattr(compiled_model.CompiledModel, "update", recording)
    patched_env = composer.Environment(BrickTask(), random_state=5)
    compiled_env = composer.Environment(BrickTask(), random_state=5, patch_compiled_model=False)
    patched, compiled = play_episodes(patched_env, 20, 10), play_episodes(compiled_env, 20, 10)
    assert_same_episodes(patched, compiled)
    # Both constructions come first, then the patched environment's 20 resets.
    assert outcomes[2:22] == [compiled_model.ModelUpdate.PATCHED] * 20
    compiles.clear()  # counts from here on
    for _ in range(3):
        patched_env.reset()
    assert compiles == []


# A user's task in a new process, the checked-in table pretended to be another release's and
# an empty cache: an MJCFVariator recolours the box and moves the goal, the arm's upper body
# moves, and the ground's friction changes, every episode. Prints the compiles of each reset.
_USERS_TASK_IN_A_NEW_PROCESS = """
import sys
sys.path.insert(0, {scene_folder!r})
from composer_scene import ReachTask
import composer
from composer import variation
from composer.variation import distributions
from mjcf import physics as physics_module
from mjcf.patching import compiled_model, patchable_attributes
patchable_attributes.MUJOCO_VERSION = "0.0.0-elsewhere"
compiles = []
original = physics_module.compile_mjcf_model
def recording(root):
    compiles.append(root)
    return original(root)
physics_module.compile_mjcf_model = compiled_model.compile_mjcf_model = recording

class Task(ReachTask):
    def __init__(self):
        super().__init__()
        goal = self.arena.mjcf_model.worldbody.add("site", name="goal", size=[0.02])
        self.variator = variation.MJCFVariator()
        self.variator.bind_attributes(self.box.geom, rgba=distributions.Uniform([0] * 4, [1] * 4))
        spot = distributions.Uniform([-0.4, -0.4, 0], [0.4, 0.4, 0])
        self.variator.bind_attributes(goal, pos=spot)
        self.variator.bind_attributes(
            self.arena.mjcf_model.find("geom", "ground"),
            friction=distributions.Uniform([0.5, 0.005, 0.0001], [1.5, 0.01, 0.0002]),
        )
        self.variator.bind_attributes(
            self.arm.mjcf_model.find("body", "upper"),
            pos=distributions.Uniform([0, 0, 0.4], [0, 0, 0.6]),
        )

    def initialize_episode_mjcf(self, random_state):
        self.variator.apply_variations(random_state)

env = composer.Environment(Task(), random_state=3)
for _ in range(4):
    compiles.clear()
    env.reset()
    print(len(compiles), end=" ")
"""


@pytest.mark.patches_from_3_17
def test_a_users_task_patches_from_its_second_reset_on_any_release_with_no_command_run(
    tmp_path,
):
    # A RuntimeWarning (a refusal, an unreadable cache) would fail the process.
    code = _USERS_TASK_IN_A_NEW_PROCESS.format(scene_folder=str(Path(__file__).parent))
    runs = [
        subprocess.run(
            [sys.executable, "-W", "error::RuntimeWarning", "-c", code],
            env=dict(os.environ, XDG_CACHE_HOME=str(tmp_path)),
            capture_output=True,
            text=True,
            timeout=120,
        )
        for _ in range(2)
    ]
    assert [run.stderr for run in runs] == ["", ""]
    # The first reset's changes are proven with the compile that a recompile would cost; the
    # proof is cached, so the next process patches from its first reset.
    assert [run.stdout.split() for run in runs] == [["1", "0", "0", "0"], ["0", "0", "0", "0"]]
