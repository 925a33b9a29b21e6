"""RayVectorEnv on a real multi-node Ray cluster (`ray.cluster_utils.Cluster`: a head and
two worker nodes, each its own raylet, on this machine), and on a local Ray that dies.

Marked `ray` (deselect with -m "not ray"); skipped when Ray is not installed. Every
cluster and Ray started here is shut down by a finalizer, also when a test fails.
"""

import functools
import pathlib
import time

import gymnasium
import numpy as np
import pytest
from gym_scene import CounterEnv
from ray_actors import wait_until_dead

from composer.gym import RayVectorEnv

pytestmark = pytest.mark.ray

_HERE = pathlib.Path(__file__).resolve().parent
_REPO = _HERE.parents[2]
# The actors' processes import gym_scene (pickled by reference) and this checkout's composer.
_RUNTIME_ENV = {"env_vars": {"PYTHONPATH": f"{_HERE}:{_REPO}"}}
# Short bounded waits: a start or call that cannot succeed fails in seconds.
_TIMEOUTS = {"start_timeout": 20.0, "call_timeout": 20.0}


@pytest.fixture
def ray(request):
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install -e '.[ray]')")
    # Another module's Ray, if any, is not this test's.
    ray.shutdown()
    request.addfinalizer(ray.shutdown)
    return ray


@pytest.fixture
def make_cluster(ray, request):
    """Returns `make(cpus_per_worker)`: starts a head (no CPUs, so actors land on the
    workers) and two worker nodes, connects this process to it, and returns the
    `Cluster`. A finalizer disconnects and shuts the cluster down."""
    from ray.cluster_utils import Cluster

    def make(cpus_per_worker):
        cluster = Cluster(
            initialize_head=True, head_node_args={"num_cpus": 0, "include_dashboard": False}
        )
        request.addfinalizer(cluster.shutdown)
        request.addfinalizer(ray.shutdown)
        for _ in range(2):
            cluster.add_node(num_cpus=cpus_per_worker)
        cluster.wait_for_nodes()
        ray.init(address=cluster.address, runtime_env=_RUNTIME_ENV)
        return cluster

    return make


def _counters(lengths):
    return [functools.partial(CounterEnv, length) for length in lengths]


def _node_of(ray, actor):
    return ray.get(
        actor.__ray_call__.remote(lambda _: ray.get_runtime_context().get_node_id()), timeout=30
    )


def _worker_node(cluster, node_id):
    (node,) = [node for node in cluster.worker_nodes if node.node_id == node_id]
    return node


def _wait_for_free_cpus(ray, cpus):
    deadline = time.monotonic() + 30
    while ray.available_resources().get("CPU", 0) < cpus and time.monotonic() < deadline:
        time.sleep(0.1)
    return ray.available_resources().get("CPU", 0)


def test_actors_spread_over_nodes_and_a_removed_node_s_actors_restart_on_the_other(
    ray, make_cluster
):
    cluster = make_cluster(cpus_per_worker=2)
    # Four actors of a quarter CPU would all fit on one node: spreading is a choice.
    envs = RayVectorEnv(
        _counters([6, 6, 6, 6]), envs_per_actor=1, num_cpus_per_actor=0.25, **_TIMEOUTS
    )
    try:
        placed = [_node_of(ray, actor) for actor in envs.actors]
        assert sorted(placed.count(node.node_id) for node in cluster.worker_nodes) == [2, 2]
        zeros = np.zeros((4, 1))
        envs.reset(seed=0)
        envs.step(zeros)
        removed = placed[3]
        lost = [k for k, node in enumerate(placed) if node == removed]
        survivor = next(node for node in placed if node != removed)
        cluster.remove_node(_worker_node(cluster, removed))
        observations, rewards, terminated, truncated, infos = envs.step(zeros)
        # The other node's sub-envs lose nothing; the lost ones end with their last
        # observation.
        kept = [k for k in range(4) if k not in lost]
        assert observations[kept, 0].tolist() == [100 * k + 2 for k in kept]
        assert observations[lost, 0].tolist() == [100 * k + 1 for k in lost]
        assert rewards.tolist() == [0.0 if k in lost else 2.0 for k in range(4)]
        assert terminated.tolist() == [False] * 4
        assert truncated.tolist() == [k in lost for k in range(4)]
        assert infos["_restarted"].tolist() == [k in lost for k in range(4)]
        assert envs.restarts == [int(k in lost) for k in range(4)]
        assert [_node_of(ray, actor) for actor in envs.actors] == [survivor] * 4
        # The run goes on: the new sub-envs start new episodes (a new CounterEnv at 0).
        observations, *_ = envs.step(zeros)
        assert observations[:, 0].tolist() == [0 if k in lost else 100 * k + 3 for k in range(4)]
        observations, *_ = envs.step(zeros)
        assert observations[:, 0].tolist() == [1 if k in lost else 100 * k + 4 for k in range(4)]
        actors = envs.actors
    finally:
        envs.close()
    for actor in actors:
        wait_until_dead(ray, actor)
    assert _wait_for_free_cpus(ray, 2) == 2


def test_a_lost_actor_with_no_free_cpu_left_raises_timeout_error_and_closes(ray, make_cluster):
    cluster = make_cluster(cpus_per_worker=1)
    envs = RayVectorEnv(_counters([6, 6]), envs_per_actor=1, start_timeout=3, call_timeout=20)
    try:
        placed = [_node_of(ray, actor) for actor in envs.actors]
        actors = envs.actors
        envs.reset(seed=0)
        cluster.remove_node(_worker_node(cluster, placed[1]))
        expected = (
            r"the Ray actors of sub-environment 1 did not start within start_timeout=3 s; "
            r"each needs 1 CPU on one node, and the cluster reports 0 of 1 CPUs free on "
            r"2 live node\(s\)"
        )
        with pytest.raises(TimeoutError, match=expected):
            envs.step(np.zeros((2, 1)))
        assert envs.closed
        with pytest.raises(gymnasium.error.ClosedEnvironmentError):
            envs.step(np.zeros((2, 1)))
    finally:
        envs.close()
    wait_until_dead(ray, actors[0])
    assert _wait_for_free_cpus(ray, 1) == 1


@pytest.fixture
def local_ray(ray, request, monkeypatch):
    """No Ray in this process, and RAY_ADDRESS naming a cluster that is gone (as a killed
    run leaves Ray's pointer to its cluster behind). A finalizer shuts down whatever
    Ray the test started."""
    monkeypatch.setenv("RAY_ADDRESS", "127.0.0.1:9")
    return ray


def test_address_none_starts_a_new_local_ray_whatever_a_dead_cluster_left(local_ray):
    envs = RayVectorEnv(
        [functools.partial(gymnasium.make, "CartPole-v1")] * 2, envs_per_actor=1, **_TIMEOUTS
    )
    try:
        observations, _ = envs.reset(seed=0)
        assert observations.shape == (2, 4)
        assert local_ray.get_runtime_context().gcs_address != "127.0.0.1:9"
    finally:
        envs.close()


def test_steps_after_the_local_raylet_died_raise_timeout_error_within_the_bounds(local_ray):
    local_ray.init(address="local", num_cpus=2, include_dashboard=False, runtime_env=_RUNTIME_ENV)
    envs = RayVectorEnv(_counters([1000, 1000]), envs_per_actor=1, start_timeout=3, call_timeout=3)
    try:
        envs.reset(seed=0)
        local_ray._private.worker.global_worker.node.kill_raylet()
        # The actors may answer a few more steps before Ray notices that they are gone;
        # then, by how far Ray got, a replacement never starts, dies starting, or a call
        # gets no reply.
        expected = "did not start within start_timeout=3 s|died while starting|no reply within"
        with pytest.raises((TimeoutError, RuntimeError), match=expected):
            for _ in range(1000):
                envs.step(np.zeros((2, 1)))
                time.sleep(0.05)
        assert envs.closed
    finally:
        envs.close()
