"""Trains rsl_rl's PPO on the batched reach task (MuJoCo Warp) and saves its learning curve.

    python examples/train_rsl_rl.py [--minutes 10] [--num-envs 4096] [--device cuda:0]
    python examples/train_rsl_rl.py --smoke        # 2 iterations on 8 worlds (CI)

Needs the extras [warp] and [rsl_rl] (and torch; without a GPU, its CPU build). Every
`--eval-every` iterations the deterministic policy runs one full episode in 32 seeded
worlds of a separate batch (with `--smoke`, an episode of 0.4 s, 10 control steps: the
task's 250 take minutes on Warp's CPU device); the script prints the mean return and the
mean final distance between the hand's pinch site and the target, and writes them to
`OUT/curve.csv` and `OUT/curve.png` (with matplotlib). On a GPU, thousands of worlds step
at once; on Warp's CPU device the same code runs, slowly.
"""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path

import numpy as np
import torch
from rsl_rl.runners import OnPolicyRunner

import manipulation.batch
from composer.rl.rsl_rl import RslRlVecEnv
from manipulation.tasks.task_constants import TIME_LIMIT

TASK = "reach_site_features"
EVAL_WORLDS = 32
SMOKE_EVAL_SECONDS = 0.4


def train_config(steps_per_env: int) -> dict:
    """rsl_rl's PPO settings: MLP actor and critic, as its locomotion examples use."""
    model = {
        "class_name": "MLPModel",
        "hidden_dims": [256, 128, 64],
        "activation": "elu",
        "obs_normalization": True,
    }
    return {
        "num_steps_per_env": steps_per_env,
        "save_interval": 10**9,
        "obs_groups": {"actor": ["policy"], "critic": ["policy"]},
        "actor": {**model, "distribution_cfg": {"class_name": "GaussianDistribution"}},
        "critic": model,
        "algorithm": {
            "class_name": "PPO",
            "learning_rate": 1e-3,
            "num_learning_epochs": 5,
            "num_mini_batches": 4,
            "entropy_coef": 0.005,
            "gamma": 0.99,
            "lam": 0.95,
            "desired_kl": 0.01,
        },
    }


def evaluate(policy, device: str, seed: int, seconds: float) -> tuple[float, float]:
    """Mean return and mean final pinch-to-target distance of one episode of `seconds` per
    world."""
    env = RslRlVecEnv(
        manipulation.batch.load(
            TASK,
            EVAL_WORLDS,
            seed=seed,
            device=device,
            array_type="torch",
            autoreset_mode="same_step",
            time_limit=seconds,
        )
    )
    returns = torch.zeros(EVAL_WORLDS, device=env.device)
    observations = env.get_observations()
    with torch.inference_mode():
        for _ in range(env.max_episode_length):
            observations, rewards, _, _ = env.step(policy(observations))
            returns += rewards
            last = env.unwrapped.final_observation
    distance = torch.linalg.vector_norm(
        last["jaco_arm/jaco_hand/pinch_site_pos"].reshape(EVAL_WORLDS, 3)
        - last["target_position"].reshape(EVAL_WORLDS, 3),
        dim=1,
    )
    env.close()
    return float(returns.mean()), float(distance.mean())


def save_curve(rows: list[dict], out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "curve.csv", "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: wrote curve.csv only (pip install matplotlib)")
        return
    figure, left = plt.subplots(figsize=(6, 3.5))
    seconds = [row["seconds"] for row in rows]
    left.plot(seconds, [row["return"] for row in rows], "o-", color="tab:blue")
    left.set_xlabel("wall time (s)")
    left.set_ylabel("evaluation return", color="tab:blue")
    right = left.twinx()
    right.plot(seconds, [row["distance_m"] for row in rows], "s--", color="tab:red")
    right.set_ylabel("final distance (m)", color="tab:red")
    left.set_title(f"rsl_rl PPO on batched {TASK}")
    figure.tight_layout()
    figure.savefig(out / "curve.png", dpi=120)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0, help="wall-time budget")
    parser.add_argument("--num-envs", type=int, default=4096)
    parser.add_argument("--steps-per-env", type=int, default=24)
    parser.add_argument("--eval-every", type=int, default=20, help="iterations")
    parser.add_argument("--device", default=None, help="Warp device (default: CUDA if any)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("rsl_rl_reach"))
    parser.add_argument(
        "--smoke", action="store_true", help="2 iterations on 8 worlds, a 0.4 s evaluation"
    )
    args = parser.parse_args()
    eval_seconds = TIME_LIMIT  # the task's own 10 s episodes
    if args.smoke:
        args.num_envs, args.steps_per_env, args.eval_every, args.minutes = 8, 8, 2, 0.0
        eval_seconds = SMOKE_EVAL_SECONDS
    torch.manual_seed(args.seed)
    env = RslRlVecEnv(
        manipulation.batch.load(
            TASK,
            args.num_envs,
            seed=args.seed,
            device=args.device,
            array_type="torch",
            autoreset_mode="same_step",
        )
    )
    device = str(env.device)
    runner = OnPolicyRunner(env, train_config(args.steps_per_env), log_dir=None, device=device)
    print(f"{args.num_envs} worlds on {device}; {env.num_actions} actions")
    print(f"{'iteration':>9}  {'seconds':>8}  {'env steps/s':>11}  {'return':>7}  {'dist (m)':>8}")
    rows, start, iterations, first = [], time.perf_counter(), 0, True
    while first or time.perf_counter() - start < args.minutes * 60:
        runner.learn(args.eval_every, init_at_random_ep_len=first)
        first = False
        iterations += args.eval_every
        elapsed = time.perf_counter() - start
        mean_return, distance = evaluate(
            runner.get_inference_policy(device=device),
            device,
            seed=1000 + args.seed,
            seconds=eval_seconds,
        )
        rate = iterations * args.steps_per_env * args.num_envs / elapsed
        rows.append(
            {
                "iteration": iterations,
                "seconds": round(elapsed, 1),
                "env_steps_per_s": round(rate),
                "return": round(mean_return, 2),
                "distance_m": round(distance, 4),
            }
        )
        print(f"{iterations:9d}  {elapsed:8.1f}  {rate:11.0f}  {mean_return:7.1f}  {distance:8.3f}")
    env.close()
    save_curve(rows, args.out)
    print(f"wrote {args.out / 'curve.csv'}")


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    main()
