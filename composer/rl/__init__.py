"""Adapters between composer environments and training libraries.

Each adapter is a module of its own that imports its library, an optional extra, when it
is imported: `composer.rl.sb3` (Stable-Baselines3 on the threaded and Ray vector envs, the
extra `[sb3]`) and `composer.rl.rsl_rl` (rsl_rl on the batched MuJoCo Warp environments,
the extra `[rsl_rl]`). Neither `import composer` nor `import composer.rl` imports any
training library.
"""
