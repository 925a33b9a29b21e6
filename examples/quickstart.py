"""Loads a manipulation task, runs one episode and prints how it went and how long it took.

The policy is the scripted Cartesian controller of `scripted_control.py` for the tasks it
solves (reach_site_features, lift_brick_features) and uniform random actions otherwise.

Usage: python examples/quickstart.py [--environment NAME] [--seed N]
"""

import argparse
import time

import numpy as np
from scripted_control import POLICIES

import manipulation

_STEPS_PER_SECOND = 25


def _random_policy(env, seed: int):
    """Returns a policy drawing actions uniformly within the action bounds."""
    spec, random_state = env.action_spec(), np.random.RandomState(seed)

    def policy(timestep):
        del timestep  # Random actions ignore the observations.
        return random_state.uniform(spec.minimum, spec.maximum)

    return policy


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--environment", choices=manipulation.ALL, default="reach_site_features")
    parser.add_argument("--seed", type=int, default=42)
    args = parser.parse_args()

    start = time.perf_counter()
    env = manipulation.load(args.environment, seed=args.seed)
    load_time = time.perf_counter() - start
    start = time.perf_counter()
    timestep = env.reset()
    reset_time = time.perf_counter() - start

    if args.environment in POLICIES:
        policy, policy_name = POLICIES[args.environment](env), "scripted controller"
    else:
        policy, policy_name = _random_policy(env, args.seed), "random actions"

    rewards, step_time = [], 0.0
    while not timestep.last():
        action = policy(timestep)
        start = time.perf_counter()
        timestep = env.step(action)
        step_time += time.perf_counter() - start
        rewards.append(timestep.reward)

    print(f"{args.environment} (seed {args.seed}), {policy_name}")
    print(f"  steps: {len(rewards)}, return: {sum(rewards):.2f}")
    print(f"  mean reward over the last second: {np.mean(rewards[-_STEPS_PER_SECOND:]):.3f}")
    print(
        f"  load: {load_time * 1e3:.1f} ms, reset: {reset_time * 1e3:.2f} ms, "
        f"step: {step_time / len(rewards) * 1e3:.3f} ms (mean)"
    )


if __name__ == "__main__":
    main()
