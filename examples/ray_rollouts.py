"""Collects episodes of a manipulation task with a random policy on Ray; prints throughput.

The sub-environments run in Ray actors (`composer.gym.RayVectorEnv`, the `[ray]` extra).
Without `--address` Ray starts on this machine; with `--address auto` (on a node of a
cluster started with `ray start`) or `--address ray://HEAD:10001` the actors are spread
over the cluster, whose nodes need this project installed too.

Usage: python examples/ray_rollouts.py [--environment NAME] [--episodes N]
  [--num-envs N] [--envs-per-actor N] [--address ADDRESS] [--seed N]
"""

import argparse
import time

import gymnasium
import numpy as np

import manipulation


def collect(envs: gymnasium.vector.VectorEnv, episodes: int, seed: int) -> dict[str, float]:
    """Steps `envs` with uniform random actions until `episodes` episodes have ended.

    Returns:
      'episodes', 'steps' (sub-environment steps), 'seconds', 'steps_per_second' and
      'mean_return' of the ended episodes.
    """
    envs.action_space.seed(seed)
    envs.reset(seed=seed)
    returns = np.zeros(envs.num_envs)
    ended: list[float] = []
    steps = 0
    start = time.perf_counter()
    while len(ended) < episodes:
        _, rewards, terminated, truncated, _ = envs.step(envs.action_space.sample())
        steps += envs.num_envs
        returns += rewards
        for i in np.flatnonzero(terminated | truncated):
            ended.append(float(returns[i]))
            # NEXT_STEP autoreset: the next step resets it and rewards 0.
            returns[i] = 0.0
    seconds = time.perf_counter() - start
    return {
        "episodes": len(ended),
        "steps": steps,
        "seconds": seconds,
        "steps_per_second": steps / seconds,
        "mean_return": float(np.mean(ended)),
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--environment", choices=manipulation.ALL, default="lift_brick_features")
    parser.add_argument("--episodes", type=int, default=8)
    parser.add_argument("--num-envs", type=int, default=4)
    parser.add_argument("--envs-per-actor", type=int, default=None)
    parser.add_argument("--address", default=None, help="Ray cluster; default: local Ray")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    start = time.perf_counter()
    envs = gymnasium.make_vec(
        f"composer/{args.environment}-v0",
        num_envs=args.num_envs,
        vectorization_mode="vector_entry_point",
        backend="ray",
        address=args.address,
        envs_per_actor=args.envs_per_actor,
    )
    print(
        f"{args.environment}: {envs.num_envs} sub-environments in {len(envs.actors)} Ray "
        f"actors ({envs.envs_per_actor} each), started in {time.perf_counter() - start:.1f} s"
    )
    result = collect(envs, args.episodes, args.seed)
    envs.close()
    print(
        f"{result['episodes']} episodes, {result['steps']} steps in {result['seconds']:.1f} s: "
        f"{result['steps_per_second']:.0f} steps/s, mean return {result['mean_return']:.2f}"
    )


if __name__ == "__main__":
    main()
