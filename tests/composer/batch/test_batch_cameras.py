"""Camera observables of a batch, rendered by MuJoCo Warp, against the CPU renderer.

A ray tracer and OpenGL are not bit-equal, so these tests compare what a policy sees, in
several worlds in different states (a lift_brick_vision batch after random actions), each
against the CPU renderer drawing the same world's state, with bounds derived as follows.

- Segmentation. Both renderers decide a pixel's geom at the pixel's centre (OpenGL's
  rasterisation rule; the ray through the centre). They can differ only where a silhouette
  passes within a sub-pixel distance of a centre: curved primitives are tessellated by
  OpenGL (`vis.quality.numslices` = 28 slices: a chord error of r (1 - cos(pi/28)), 0.6% of
  the radius) and positions are float32 on the device. Such a pixel borders another geom,
  so every disagreement lies on an edge pixel of the CPU image (one whose 8 neighbours are
  not all its geom), and the agreeing fraction is at least 1 - the edge pixels' fraction.
- Depth. MuJoCo's offscreen buffer is multisampled (`vis.quality.offsamples` = 4), and the
  depth read back is one sample's, up to 0.4 pixel from the centre (the standard 4-sample
  pattern's offsets are 1/8 and 3/8 pixel per axis: sqrt((3/8)^2 + (1/8)^2) < 0.4), where
  the ray tracer samples the centre. So on an interior pixel (its 8 neighbours are its own
  geom in both images) the depths differ by at most 0.4 times the steepest change of the
  CPU depth to a neighbour, plus the float32 resolution of the depth (1e-5 relative).
  Where nothing is hit, both give the far clipping distance, within 1e-3 relative (OpenGL's
  24-bit depth buffer at the far plane).
- Mean colour per geom. On a known scene (below: a matte box facing a directional light
  along the view) the colour is analytic, rgb * (ambient + diffuse), and both renderers
  must give it within 1 level of 255: that is the colour arithmetic (channel order, packing,
  rounding) agreeing. Lighting then differs in one way: OpenGL lights each vertex and
  interpolates (Gouraud), the ray tracer lights each pixel, and neither value leaves the
  range the lighting takes over the face; shadows (OpenGL's) only darken within that range.
  So per geom and channel, the mean colours over its interior pixels differ by at most that
  range, the spread of the CPU image's colours over those pixels, plus 1 level.
"""

import mujoco
import numpy as np
import pytest

import composer
from composer import batch
from composer.observation import observable
from manipulation import batch as manipulation_batch

pytestmark = pytest.mark.warp

SIZE = 64
NUM_ENVS = 3
MSAA_OFFSET = 0.4  # pixels, see the module docstring
DEPTH_RESOLUTION = 1e-5
FAR_RESOLUTION = 1e-3


@pytest.fixture(scope="module")
def worlds():
    """A lift_brick_vision batch after random actions, with an RGB, a depth and a
    segmentation camera on 'front_close', and the CPU renderings of each world's state."""
    env = manipulation_batch.load("lift_brick_vision", NUM_ENVS, seed=5, device="warp-cpu")
    task = env.task.task
    camera = task.root_entity.mjcf_model.find("camera", "front_close")
    for name, kind in (("depth", {"depth": True}), ("segmentation", {"segmentation": True})):
        extra = observable.MJCFCamera(camera, height=SIZE, width=SIZE, **kind)
        extra.enabled = True
        task.task_observables[f"front_close_{name}"] = extra
    task.task_observables["front_close"].height = SIZE
    task.task_observables["front_close"].width = SIZE
    env.close()
    env = batch.BatchEnvironment(task, NUM_ENVS, device="warp-cpu", random_state=5)
    env.reset()
    spec = env.action_spec()
    rng = np.random.RandomState(0)
    for _ in range(12):
        timestep = env.step(rng.uniform(spec.minimum, spec.maximum, (NUM_ENVS, *spec.shape)))
    observation = {key: np.asarray(value)[:, 0] for key, value in timestep.observation.items()}
    host, qpos, qvel = env.physics.host, env.physics.data.qpos, env.physics.data.qvel
    camera_id = host.bind(camera).element_id
    cpu = []
    for world in range(NUM_ENVS):
        host.data.qpos[:], host.data.qvel[:] = np.asarray(qpos[world]), np.asarray(qvel[world])
        mujoco.mj_forward(host.model.ptr, host.data.ptr)
        render = lambda **kind: host.render(SIZE, SIZE, camera_id=camera_id, **kind)  # noqa: E731
        cpu.append(
            {
                "front_close": render(),
                "front_close_depth": render(depth=True),
                "front_close_segmentation": render(segmentation=True),
            }
        )
    assert env.cameras.camera_ids == (camera_id,)
    env.close()
    return observation, cpu, host


def _edges(ids: np.ndarray) -> np.ndarray:
    """True where a pixel's 8 neighbours are not all of its own id."""
    padded = np.pad(ids, 1, mode="edge")
    edge = np.zeros(ids.shape, bool)
    height, width = ids.shape
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            edge |= padded[1 + dy : 1 + dy + height, 1 + dx : 1 + dx + width] != ids
    return edge


def test_images_have_the_cpu_observables_dtypes_and_shapes(worlds):
    observation, _, _ = worlds
    assert observation["front_close"].dtype == np.uint8
    assert observation["front_close"].shape == (NUM_ENVS, SIZE, SIZE, 3)
    assert observation["front_close_depth"].dtype == np.float32
    assert observation["front_close_depth"].shape == (NUM_ENVS, SIZE, SIZE, 1)
    assert observation["front_close_segmentation"].dtype == np.int32
    assert observation["front_close_segmentation"].shape == (NUM_ENVS, SIZE, SIZE, 2)


def test_worlds_in_different_states_see_different_images(worlds):
    observation, _, _ = worlds
    images = observation["front_close"].astype(int)
    assert np.abs(images[0] - images[1]).max() > 0
    assert np.abs(images[1] - images[2]).max() > 0


@pytest.mark.parametrize("world", range(NUM_ENVS))
def test_segmentation_differs_only_on_edge_pixels(worlds, world):
    observation, cpu, _ = worlds
    ours = observation["front_close_segmentation"][world]
    theirs = cpu[world]["front_close_segmentation"]
    np.testing.assert_array_equal(np.unique(ours[..., 1]), np.unique(theirs[..., 1]))
    differ = ours[..., 0] != theirs[..., 0]
    edge = _edges(theirs[..., 0])
    assert not (differ & ~edge).any(), np.argwhere(differ & ~edge)
    assert 1 - differ.mean() >= 1 - edge.mean()


@pytest.mark.parametrize("world", range(NUM_ENVS))
def test_depth_within_the_multisample_bound(worlds, world):
    observation, cpu, host = worlds
    ours = observation["front_close_depth"][world, ..., 0]
    theirs = cpu[world]["front_close_depth"]
    ids = cpu[world]["front_close_segmentation"][..., 0]
    mine = observation["front_close_segmentation"][world, ..., 0]
    interior = ~_edges(ids) & ~_edges(mine) & (ids == mine) & (ids >= 0)
    padded = np.pad(theirs, 1, mode="edge")
    steepest = np.zeros_like(theirs)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            neighbour = padded[1 + dy : 1 + dy + SIZE, 1 + dx : 1 + dx + SIZE]
            steepest = np.maximum(steepest, np.abs(neighbour - theirs))
    bound = MSAA_OFFSET * steepest + DEPTH_RESOLUTION * theirs
    excess = np.abs(ours - theirs) - bound
    assert interior.sum() > SIZE * SIZE / 2
    assert (excess[interior] <= 0).all(), excess[interior].max()
    model = host.model.ptr
    far = model.vis.map.zfar * model.stat.extent
    empty = (ids < 0) & (mine < 0)
    np.testing.assert_allclose(ours[empty], far, rtol=FAR_RESOLUTION)
    np.testing.assert_allclose(theirs[empty], far, rtol=FAR_RESOLUTION)


@pytest.mark.parametrize("world", range(NUM_ENVS))
def test_mean_colour_per_geom_within_its_lighting_range(worlds, world):
    observation, cpu, host = worlds
    ours = observation["front_close"][world].astype(float)
    theirs = cpu[world]["front_close"].astype(float)
    ids = cpu[world]["front_close_segmentation"][..., 0]
    mine = observation["front_close_segmentation"][world, ..., 0]
    interior = ~_edges(ids) & (ids == mine) & (ids >= 0)
    compared = 0
    for geom in np.unique(ids[interior]):
        pixels = interior & (ids == geom)
        if pixels.sum() < 8:
            continue
        spread = theirs[pixels].max(axis=0) - theirs[pixels].min(axis=0)
        difference = np.abs(ours[pixels].mean(axis=0) - theirs[pixels].mean(axis=0))
        name = mujoco.mj_id2name(host.model.ptr, mujoco.mjtObj.mjOBJ_GEOM, int(geom))
        assert (difference <= spread + 1).all(), (name, difference, spread)
        compared += 1
    assert compared >= 3


class _LitBox(composer.Task):
    """A matte box filling the view of a camera, lit by one directional light along the
    camera's axis, without a headlight: every pixel's colour is rgb * (ambient + diffuse)."""

    RGB = np.array([0.8, 0.4, 0.2])
    AMBIENT, DIFFUSE = 0.1, 0.6

    def __init__(self):
        self._arena = composer.Arena()
        model = self._arena.mjcf_model
        model.visual.headlight.active = 0
        model.asset.add("material", name="matte", specular=0, shininess=0, reflectance=0)
        model.worldbody.add(
            "light",
            directional=True,
            pos=[0, 0, 2],
            dir=[0, 0, -1],
            ambient=[self.AMBIENT] * 3,
            diffuse=[self.DIFFUSE] * 3,
            specular=[0, 0, 0],
            castshadow=False,
        )
        model.worldbody.add(
            "geom", type="box", size=[1, 1, 0.1], rgba=[*self.RGB, 1], material="matte"
        )
        self.camera = model.worldbody.add("camera", name="above", pos=[0, 0, 1.5])
        self.image = observable.MJCFCamera(self.camera, height=16, width=16)
        self.image.enabled = True
        self.extra_observables = {}

    @property
    def root_entity(self):
        return self._arena

    @property
    def task_observables(self):
        return {"above": self.image, **self.extra_observables}

    def get_reward(self, physics):
        return 0.0


class _BatchLitBox(batch.BatchTask):
    def initialize_episode(self, physics, mask):
        pass


def test_a_known_scene_has_its_analytic_colour_on_both_renderers():
    expected = 255 * _LitBox.RGB * (_LitBox.AMBIENT + _LitBox.DIFFUSE)
    env = batch.BatchEnvironment(_BatchLitBox(_LitBox()), 2, device="warp-cpu")
    ours = np.asarray(env.reset().observation["above"])[:, 0].astype(float)
    env.close()
    cpu = composer.Environment(_LitBox()).reset().observation["above"][0].astype(float)
    np.testing.assert_allclose(ours, np.broadcast_to(expected, ours.shape), atol=1)
    np.testing.assert_allclose(cpu, np.broadcast_to(expected, cpu.shape), atol=1)


def test_a_scene_option_is_refused_naming_the_observable():
    task = _LitBox()
    task.image.scene_option = mujoco.MjvOption()
    with pytest.raises(ValueError, match="observable 'above': option scene_option="):
        batch.BatchEnvironment(_BatchLitBox(task), 2, device="warp-cpu")


def test_one_camera_at_two_sizes_is_refused_naming_both_observables():
    task = _LitBox()
    small = observable.MJCFCamera(task.camera, height=8, width=8)
    small.enabled = True
    task.extra_observables["small"] = small
    with pytest.raises(ValueError, match="'small': camera .* at 8x8 here and at 16x16 by 'above'"):
        batch.BatchEnvironment(_BatchLitBox(task), 2, device="warp-cpu")


def test_a_disabled_camera_is_not_rendered():
    task = _LitBox()
    task.image.enabled = False
    env = batch.BatchEnvironment(_BatchLitBox(task), 2, device="warp-cpu")
    assert env.cameras is None
    assert "above" not in env.reset().observation
    env.close()
