"""`mjlib`: MuJoCo's functions, which the `mujoco` module holds (`mjlib.mj_step`)."""

import mujoco

mjlib = mujoco
