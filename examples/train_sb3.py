"""Trains SAC (Stable-Baselines3) on a manipulation task within a wall-clock budget.

The task is `--task`, reach_site_features unless told otherwise (any task with the tag
'features'). The training episodes run in a `composer.gym.ThreadedVectorEnv` seen by SB3
through `composer.rl.sb3` (the extra `[sb3]`), or with `--backend batch` in one batch of
worlds (`composer.batch`, the CPU batch on `mujoco.batch`) through
`composer.rl.sb3_batch`, each world the episodes of the threaded env's sub-environment
seeded alike. Before training, uniformly random actions
play 5 seeded 10 s episodes, the baseline; then every `--eval-every` seconds the
deterministic policy plays the same 5 (in a vector env of their own). The script prints
their mean return and success rate (`info['is_success']` at the episode's end) and, for
reach_site_features, the mean final distance from the pinch site to the target. The
learning rate falls from 1e-3 to 1e-4 over the budget. When the budget is spent it writes
the learning curve to OUT/learning_curve.csv and OUT/learning_curve.png (with
matplotlib), the last policy to OUT/sac_TASK.zip and the one with the best evaluation
return to OUT/best_sac_TASK.zip.

Usage: python examples/train_sb3.py [--task reach_site_features] [--minutes 10]
  [--out runs/train_sb3] [--num-envs 4] [--seed 0] [--eval-every 30]
  [--backend threads|batch] [--smoke]

--smoke trains for a few hundred steps and evaluates once (seconds; for CI).
"""

import argparse
import csv
import functools
import math
import pathlib
import sys
import time
from typing import NamedTuple

import gymnasium
import numpy as np

import manipulation
from composer.gym import GymnasiumEnv
from manipulation import gym_registration
from manipulation.tasks.task_constants import CONTROL_TIMESTEP

try:
    import torch
    from stable_baselines3 import SAC
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.evaluation import evaluate_policy

    from composer.rl.sb3 import make_vec_env
except ImportError as error:
    sys.exit(f"{error}\nThis example needs the extra [sb3]: pip install -e '.[sb3]'")

# The task whose evaluations also report the final distance to the target.
REACH = "reach_site_features"
EVAL_EPISODES = 5
# The evaluation episodes' seeds: EVAL_SEED, ..., EVAL_SEED + 4 (the training envs' are
# --seed onwards).
EVAL_SEED = 1_000_000


class ReachDistance(gymnasium.Wrapper):
    """Adds `info['distance']`: metres from the pinch site to the target after the step."""

    def __init__(self, env: gymnasium.Env):
        super().__init__(env)
        self._composer_env = env.unwrapped.dm_env
        task = self._composer_env.task
        self._pinch, self._target = task.hand.tool_center_point, task.target

    def step(self, action):
        observation, reward, terminated, truncated, info = self.env.step(action)
        # Asked for at every step: a reset may build a new physics.
        physics = self._composer_env.physics
        pinch, target = physics.bind(self._pinch).xpos, physics.bind(self._target).xpos
        info["distance"] = float(np.linalg.norm(pinch - target))
        return observation, reward, terminated, truncated, info


def make_env(task: str, max_episode_steps: int | None = None) -> gymnasium.Env:
    """`task` with flattened observations (45 floats for reach_site_features), and for
    reach_site_features the distance in its infos; with `max_episode_steps`, episodes end
    (truncated) after that many steps."""
    env: gymnasium.Env = GymnasiumEnv(manipulation.load(task), flatten_observations=True)
    if max_episode_steps is not None:
        env = gymnasium.wrappers.TimeLimit(env, max_episode_steps)
    return ReachDistance(env) if task == REACH else env


def make_train_env(args: argparse.Namespace):
    """The training envs of `--backend`, flattened, their episodes ending (truncated) after
    `--train-episode-steps` steps, world or sub-environment i seeded with `--seed` + i."""
    if args.backend == "batch":
        return make_vec_env(
            gym_registration.env_id(args.task),
            args.num_envs,
            seed=args.seed,
            backend="batch",
            flatten_observations=True,
            time_limit=args.train_episode_steps * CONTROL_TIMESTEP,
        )
    return make_vec_env(
        functools.partial(make_env, args.task, args.train_episode_steps),
        args.num_envs,
        seed=args.seed,
    )


class RandomPolicy:
    """Uniformly random actions within the action space's bounds, as SB3's `predict`
    hands them out, drawn from a generator seeded with `seed`."""

    def __init__(self, action_space: gymnasium.spaces.Box, seed: int):
        self._space = action_space
        self._rng = np.random.default_rng(seed)

    def predict(self, observation, state=None, episode_start=None, deterministic=False):
        shape = (len(observation), *self._space.shape)
        return self._rng.uniform(self._space.low, self._space.high, shape), None


class Evaluation(NamedTuple):
    """One point of the learning curve."""

    seconds: float
    env_steps: int
    updates: int
    train_return: float
    eval_return: float
    #: None for a task other than reach_site_features.
    eval_distance: float | None
    eval_success: float


class Score(NamedTuple):
    """Means over the 5 seeded evaluation episodes."""

    episode_return: float
    success: float
    #: The final distance (m) to the target; None for a task other than reach_site_features.
    distance: float | None


def evaluate(model, eval_env) -> Score:
    """Scores `model` (an SB3 model, whose actions are then deterministic, or a
    `RandomPolicy`) over the 5 seeded evaluation episodes."""
    distances: list[float] = []
    successes: list[float] = []

    def read_episode_ends(local_vars, _globals):
        for info, done in zip(local_vars["infos"], local_vars["dones"]):
            if done:
                if "distance" in info:
                    distances.append(info["distance"])
                successes.append(float(info.get("is_success", np.nan)))

    eval_env.seed(EVAL_SEED)
    returns, _ = evaluate_policy(
        model,
        eval_env,
        n_eval_episodes=EVAL_EPISODES,
        deterministic=True,
        return_episode_rewards=True,
        callback=read_episode_ends,
    )
    distance = float(np.mean(distances)) if distances else None
    return Score(float(np.mean(returns)), float(np.mean(successes)), distance)


def wall_clock_schedule(start: float, deadline: float, initial: float, final: float):
    """A learning rate falling linearly from `initial` at `start` to `final` at `deadline`
    (`time.perf_counter()` values): SB3's own schedules follow `total_timesteps`, which a
    wall-clock budget does not know. A constant `initial` for an infinite deadline."""

    def rate(_progress_remaining: float) -> float:
        spent = min(1.0, (time.perf_counter() - start) / (deadline - start))
        return initial + (final - initial) * spent

    return rate


class EvaluateAndStop(BaseCallback):
    """Evaluates every `every` seconds (and at the end) and stops training at `deadline`
    (a `time.perf_counter()` value); prints each evaluation as a row of the table and
    saves the policy of the best evaluation return to `best_path`."""

    def __init__(
        self, eval_env, start: float, deadline: float, every: float, best_path: pathlib.Path
    ):
        super().__init__()
        self._eval_env = eval_env
        self._start = start
        self._deadline = deadline
        self._every = every
        self._next = start + every
        self._best_path = best_path
        self.curve: list[Evaluation] = []
        self.best: Evaluation | None = None

    def _on_step(self) -> bool:
        now = time.perf_counter()
        if now >= self._next or now >= self._deadline:
            self.evaluate()
            self._next = time.perf_counter() + self._every
        return time.perf_counter() < self._deadline

    def evaluate(self) -> None:
        score = evaluate(self.model, self._eval_env)
        buffer = self.model.ep_info_buffer
        train_return = float(np.mean([e["r"] for e in buffer])) if buffer else float("nan")
        point = Evaluation(
            seconds=time.perf_counter() - self._start,
            env_steps=self.model.num_timesteps,
            updates=self.model._n_updates,
            train_return=train_return,
            eval_return=score.episode_return,
            eval_distance=score.distance,
            eval_success=score.success,
        )
        self.curve.append(point)
        if self.best is None or point.eval_return > self.best.eval_return:
            self.best = point
            self.model.save(self._best_path)
        distance = "" if point.eval_distance is None else f" {point.eval_distance:15.3f}"
        print(
            f"{point.seconds:7.0f} {point.env_steps:9d} {point.updates:8d} "
            f"{point.train_return:12.1f} {point.eval_return:11.1f}{distance} "
            f"{point.eval_success:12.1f}",
            flush=True,
        )


def write_curve(curve: list[Evaluation], task: str, out: pathlib.Path) -> None:
    """Writes OUT/learning_curve.csv (without the distance column for a task other than
    reach_site_features), and OUT/learning_curve.png when matplotlib is there."""
    columns = [f for f in Evaluation._fields if not (f == "eval_distance" and task != REACH)]
    with open(out / "learning_curve.csv", "w", newline="") as file:
        writer = csv.writer(file)
        writer.writerow(columns)
        writer.writerows([getattr(point, column) for column in columns] for point in curve)
    try:
        import matplotlib

        matplotlib.use("Agg")
        from matplotlib import pyplot
    except ImportError:
        print(
            "learning_curve.png not written: matplotlib is not installed (pip install matplotlib)"
        )
        return
    minutes = [point.seconds / 60 for point in curve]
    figure, (returns, right) = pyplot.subplots(1, 2, figsize=(10, 4))
    returns.plot(minutes, [p.eval_return for p in curve], marker="o", label="evaluation")
    returns.plot(minutes, [p.train_return for p in curve], label="training episodes")
    returns.set(xlabel="wall-clock minutes", ylabel="return (10 s episode)", ylim=(0, 250))
    returns.legend()
    if task == REACH:
        right.plot(minutes, [p.eval_distance for p in curve], marker="o")
        right.set(ylabel="final distance to target (m)", ylim=(0, None))
    else:
        right.plot(minutes, [p.eval_success for p in curve], marker="o")
        right.set(ylabel="success rate (evaluation)", ylim=(-0.05, 1.05))
    right.set(xlabel="wall-clock minutes")
    figure.suptitle(f"SAC on {task}")
    figure.tight_layout()
    figure.savefig(out / "learning_curve.png", dpi=100)
    pyplot.close(figure)


def main(argv: list[str] | None = None) -> list[Evaluation]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--task", default=REACH, choices=manipulation.get_environments_by_tag("features")
    )
    parser.add_argument("--minutes", type=float, default=10.0, help="wall-clock budget")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/train_sb3"))
    parser.add_argument("--num-envs", type=int, default=4, help="training sub-environments")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--eval-every", type=float, default=30.0, help="seconds")
    parser.add_argument(
        "--train-episode-steps",
        type=int,
        default=100,
        help="training episodes end (truncated) after this many 0.04 s steps; evaluation "
        "episodes last the task's 250",
    )
    parser.add_argument(
        "--backend",
        default="threads",
        choices=("threads", "batch"),
        help="the training envs: a threaded vector env, or one batch of worlds",
    )
    parser.add_argument("--smoke", action="store_true", help="a few hundred steps, for CI")
    args = parser.parse_args(argv)
    if args.num_envs < 1:
        parser.error(f"--num-envs: expected an integer >= 1, got {args.num_envs}")
    if args.minutes <= 0:
        parser.error(f"--minutes: expected a positive number, got {args.minutes}")
    args.out.mkdir(parents=True, exist_ok=True)

    # One thread for torch: the vector env's threads use the other cores.
    torch.set_num_threads(1)
    eval_env = make_vec_env(functools.partial(make_env, args.task), EVAL_EPISODES)
    print(f"SAC on {args.task}, {args.num_envs} training envs, budget {args.minutes:g} min")
    baseline = evaluate(RandomPolicy(eval_env.action_space, args.seed), eval_env)
    print(
        f"random actions: return {baseline.episode_return:.1f}, success rate "
        f"{baseline.success:.1f}"
        + ("" if baseline.distance is None else f", distance {baseline.distance:.3f} m")
    )
    # The budget starts here: the baseline's seconds are not the policy's.
    start = time.perf_counter()
    train_env = make_train_env(args)
    # The smoke run ends after its steps and evaluates once, at the end.
    deadline = math.inf if args.smoke else start + args.minutes * 60
    every = math.inf if args.smoke else args.eval_every
    model = SAC(
        "MlpPolicy",
        train_env,
        # Fast at first; slower towards the end, where a constant 1e-3 can undo a policy.
        learning_rate=wall_clock_schedule(start, deadline, 1e-3, 1e-4),
        buffer_size=300_000,
        learning_starts=100 if args.smoke else 2_000,
        batch_size=256,
        tau=0.01,
        gamma=0.98,
        policy_kwargs=dict(net_arch=[256, 256]),
        seed=args.seed,
        device="cpu",
    )
    best_path = args.out / f"best_sac_{args.task}.zip"
    callback = EvaluateAndStop(eval_env, start, deadline, every, best_path)
    distance = " eval_distance_m" if args.task == REACH else ""
    print(f"seconds env_steps  updates train_return eval_return{distance} eval_success")
    model.learn(total_timesteps=300 if args.smoke else 10**9, callback=callback)
    if args.smoke:
        callback.evaluate()
    write_curve(callback.curve, args.task, args.out)
    model.save(args.out / f"sac_{args.task}.zip")
    train_env.close()
    eval_env.close()
    final, best = callback.curve[-1], callback.best
    print(
        f"final: return {final.eval_return:.1f}, success rate {final.eval_success:.1f} after "
        f"{final.seconds:.0f} s; best: return {best.eval_return:.1f}, success rate "
        f"{best.eval_success:.1f} after {best.seconds:.0f} s ({best_path.name})"
    )
    print(f"wrote {args.out}/learning_curve.csv, the policies and (with matplotlib) the plot")
    return callback.curve


if __name__ == "__main__":
    main()
