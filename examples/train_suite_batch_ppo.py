"""Trains PPO (Stable-Baselines3) on a Control Suite task batched, within a wall-clock budget.

The training episodes are `--num-envs` worlds of `suite_batch` (dm_control's own suite task,
each world bit for bit the episode of `suite.load` seeded alike) through Gymnasium's
`make_vec` of the task's Shimmy-style id (`suite_batch.gym`) and
`composer.rl.sb3_batch.Sb3BatchVecEnv`, with flat observations. Before training and then
every `--eval-every` seconds, the deterministic policy plays one whole episode (the suite's
1,000 control steps) in each of 8 evaluation worlds, seeded apart from the training ones;
the script prints their mean return. When the budget is spent it writes the learning curve
to OUT/learning_curve.csv (wall-clock seconds, env steps, mean evaluation return), and to
OUT/learning_curve.png with matplotlib, and the policy to OUT/ppo_TASK.zip.

Needs dm_control (`pip install dm-control --no-deps scipy`) and the extra [sb3] (with the CPU
build of torch: `pip install torch==2.13.0`, then `pip install -e '.[sb3]'`).

Usage: python examples/train_suite_batch_ppo.py [--task cartpole-swingup] [--minutes 6]
  [--num-envs 64] [--out runs/train_suite_batch] [--seed 0] [--eval-every 30] [--smoke]

--smoke trains for one rollout and evaluates 20 steps (seconds; for CI).
"""

import argparse
import csv
import pathlib
import sys
import time

import gymnasium
import numpy as np
from gymnasium.vector import AutoresetMode

try:
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback

    from composer.rl.sb3_batch import Sb3BatchVecEnv
except ImportError as error:
    sys.exit(f"{error}\nThis example needs the extra [sb3]: pip install -e '.[sb3]'")

try:
    import suite_batch.gym  # noqa: F401  (registers the suite's ids)
except ImportError as error:
    sys.exit(f"{error}\nThis example needs dm_control: pip install dm-control --no-deps scipy")

EVAL_WORLDS = 8
# The evaluation worlds' seeds start here (the training worlds' at --seed).
EVAL_SEED = 1_000_000


def _batch(task: str, num_envs: int) -> Sb3BatchVecEnv:
    vector_env = gymnasium.make_vec(
        suite_batch.gym.env_id(*task.split("-", 1)),
        num_envs=num_envs,
        autoreset_mode=AutoresetMode.SAME_STEP,
    )
    return Sb3BatchVecEnv(vector_env, flatten_observations=True)


def evaluate(model: PPO, env: Sb3BatchVecEnv, steps: int) -> float:
    """The mean return of the deterministic policy over one episode of every world (or
    `steps` control steps, if fewer)."""
    env.seed(EVAL_SEED)
    observations = env.reset()
    returns = np.zeros(env.num_envs)
    running = np.ones(env.num_envs, bool)
    for _ in range(steps):
        actions, _ = model.predict(observations, deterministic=True)
        observations, rewards, dones, _ = env.step(actions)
        returns += np.where(running, rewards, 0.0)
        running &= ~dones
        if not running.any():
            break
    return float(returns.mean())


class Budget(BaseCallback):
    """Stops training when the wall-clock budget is spent; evaluates every `every` s."""

    def __init__(self, seconds: float, every: float, evaluate_now):
        super().__init__()
        self._end = time.perf_counter() + seconds
        self._every = every
        self._next = time.perf_counter() + every
        self._evaluate_now = evaluate_now

    def _on_step(self) -> bool:
        now = time.perf_counter()
        if now >= self._next:
            self._next = now + self._every
            self._evaluate_now(self.num_timesteps)
        return now < self._end


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="cartpole-swingup")
    parser.add_argument("--minutes", type=float, default=6.0)
    parser.add_argument("--num-envs", type=int, default=64)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/train_suite_batch"))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--eval-every", type=float, default=30.0)
    parser.add_argument("--smoke", action="store_true")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    env = _batch(args.task, args.num_envs)
    env.seed(args.seed)
    eval_env = _batch(args.task, EVAL_WORLDS)
    eval_steps = 20 if args.smoke else 1000
    n_steps = 8 if args.smoke else 256
    model = PPO(
        "MlpPolicy",
        env,
        n_steps=n_steps,
        batch_size=min(2048, n_steps * args.num_envs),
        n_epochs=10,
        learning_rate=3e-4,
        gamma=0.99,
        gae_lambda=0.95,
        seed=args.seed,
        policy_kwargs={"net_arch": [64, 64]},
        verbose=0,
    )
    start = time.perf_counter()
    curve = []

    def evaluate_now(env_steps: int) -> None:
        mean_return = evaluate(model, eval_env, eval_steps)
        seconds = time.perf_counter() - start
        curve.append((seconds, env_steps, mean_return))
        print(f"{seconds:7.1f} s  {env_steps:>9,} env steps  mean return {mean_return:8.1f}")

    evaluate_now(0)
    budget = 5.0 if args.smoke else args.minutes * 60
    total = n_steps * args.num_envs if args.smoke else 10**9
    model.learn(total_timesteps=total, callback=Budget(budget, args.eval_every, evaluate_now))
    evaluate_now(model.num_timesteps)
    with open(args.out / "learning_curve.csv", "w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(["seconds", "env_steps", "mean_return"])
        writer.writerows(curve)
    model.save(args.out / f"ppo_{args.task}.zip")
    try:
        import matplotlib

        matplotlib.use("Agg")
        from matplotlib import pyplot
    except ImportError:
        print("matplotlib is not installed: no learning_curve.png")
    else:
        seconds, _, returns = zip(*curve)
        pyplot.plot(seconds, returns, marker="o")
        pyplot.xlabel("wall-clock seconds")
        pyplot.ylabel(f"mean return, {EVAL_WORLDS} evaluation episodes")
        pyplot.title(f"PPO on {args.task}, {args.num_envs} batched worlds")
        pyplot.savefig(args.out / "learning_curve.png", dpi=100)
    env.close()
    eval_env.close()


if __name__ == "__main__":
    main()
