"""composer.Environment resets that copy the data of the last reset instead of recomputing it."""

import mujoco
import pytest
from composer_scene import ReachTask, assert_same_episodes, play_episodes

import composer

# What the first forward of a reset computes, read by the task before it sets the state.
_READ_AT_RESET = ("qacc", "efc_force", "xpos", "sensordata")


def _reset_values(data: mujoco.MjData) -> dict[str, bytes]:
    values = {name: getattr(data, name).tobytes() for name in _READ_AT_RESET}
    values["contact.pos"] = data.contact.pos.tobytes()
    return values


def _fresh_reset(model: mujoco.MjModel) -> mujoco.MjData:
    """What a reset computes for `model`: `mj_resetData`, then forward without actuation."""
    data = mujoco.MjData(model)
    mujoco.mj_resetData(model, data)
    flags = model.opt.disableflags
    model.opt.disableflags = flags | mujoco.mjtDisableBit.mjDSBL_ACTUATION
    mujoco.mj_forward(model, data)
    model.opt.disableflags = flags
    return data


class RecordingTask(ReachTask):
    """Varies the box's colour before every episode, and with `vary_contacts` also the
    softness of the floor's contacts (`solref`), which the box's contact forces at the
    reset state depend on. Records what the reset left in the data, before setting it."""

    def __init__(self, vary_contacts: bool):
        super().__init__()
        self.vary_contacts = vary_contacts
        self.records = []
        self.fresh_records = []  # what mj_resetData and a forward give, on new data

    def initialize_episode_mjcf(self, random_state):
        self.box.geom.rgba = [*random_state.uniform(size=3), 1]
        if self.vary_contacts:
            ground = self.arena.mjcf_model.find("geom", "ground")
            ground.solref = [random_state.uniform(0.02, 0.2), 1.0]

    def initialize_episode(self, physics, random_state):
        data = physics.data.ptr
        self.records.append(_reset_values(data))
        self.fresh_records.append(_reset_values(_fresh_reset(physics.model.ptr)))
        super().initialize_episode(physics, random_state)


@pytest.mark.parametrize("vary_contacts", [False, True])
def test_resets_read_and_play_as_resets_that_recompile(vary_contacts):
    reused = composer.Environment(RecordingTask(vary_contacts), random_state=5)
    compiled = composer.Environment(
        RecordingTask(vary_contacts), random_state=5, patch_compiled_model=False
    )
    reused_values = play_episodes(reused, 6, 5, seed=1)
    compiled_values = play_episodes(compiled, 6, 5, seed=1)
    assert reused.task.records == reused.task.fresh_records == compiled.task.records
    # The contact softness reaches what the reset computed: the records tell episodes apart.
    assert (len({r["qacc"] for r in reused.task.records}) > 1) == vary_contacts
    assert_same_episodes(reused_values, compiled_values)


@pytest.mark.patches_from_3_17
def test_when_only_colours_change_resets_copy_the_data_instead_of_a_forward(
    monkeypatch, physics_resets
):
    env = composer.Environment(RecordingTask(vary_contacts=False), random_state=5)
    env.reset()
    env.reset()  # the data is kept from a model's second reset on
    physics_resets.clear()  # counts from here on
    for _ in range(4):
        env.reset()
    assert physics_resets == []


def test_a_change_that_forward_reads_resets_afresh(monkeypatch, physics_resets):
    env = composer.Environment(RecordingTask(vary_contacts=True), random_state=5)
    env.reset()
    physics_resets.clear()  # counts from here on
    for _ in range(4):
        env.reset()
    assert len(physics_resets) == 4


class SoftensAfterCompile(RecordingTask):
    """Softens the floor's contacts through `physics.bind` after every compile."""

    def after_compile(self, physics, random_state):
        ground = self.arena.mjcf_model.find("geom", "ground")
        physics.bind(ground).solref = [random_state.uniform(0.02, 0.2), 1.0]


def test_an_after_compile_hook_makes_every_reset_start_afresh(monkeypatch, physics_resets):
    env = composer.Environment(SoftensAfterCompile(vary_contacts=False), random_state=5)
    compiled = composer.Environment(
        SoftensAfterCompile(vary_contacts=False), random_state=5, patch_compiled_model=False
    )
    play_episodes(compiled, 6, 5, seed=1)
    physics_resets.clear()  # counts from here on
    play_episodes(env, 6, 5, seed=1)
    # Per episode: the reset context the hooks run in (as in dm_control), and the episode's.
    assert len(physics_resets) == 2 * 6
    assert env.task.records == env.task.fresh_records == compiled.task.records


class SoftensEveryEpisode(RecordingTask):
    """Softens the floor's contacts through `physics.bind` at the start of every episode."""

    def initialize_episode(self, physics, random_state):
        super().initialize_episode(physics, random_state)
        ground = self.arena.mjcf_model.find("geom", "ground")
        physics.bind(ground).solref = [random_state.uniform(0.02, 0.2), 1.0]


def test_without_recompiling_every_episode_resets_see_the_last_episodes_writes():
    env = composer.Environment(
        SoftensEveryEpisode(vary_contacts=False),
        random_state=5,
        recompile_mjcf_every_episode=False,
    )
    play_episodes(env, 6, 5, seed=1)
    assert env.task.records == env.task.fresh_records
    assert len({record["qacc"] for record in env.task.records}) == 6
