"""Pusher strikes puck: is the batch's drift float32 rounding or a contact difference?

Run: python tools/contact_parity.py (needs the extra [warp]; Warp's CPU device, about a
minute with a warm kernel cache). Prints three tables:

1. How far the puck is from C MuJoCo's float64 rollout, control step by control step
   around the impact, in three rollouts of the same model and controls: C MuJoCo with its
   state rounded to float32 after every physics step, C MuJoCo started from the initial
   state perturbed by one float32 rounding only, and MuJoCo Warp on Warp's CPU device.
2. The contacts and constraints that C MuJoCo and MuJoCo Warp compute for the same state
   (C MuJoCo's, rounded to float32) at the physics step of the impact: per geom pair the
   count, distance, position and normal; the number of constraint rows and the resulting
   accelerations.
3. The error of one physics step from the same (rounded) state, Warp against C MuJoCo,
   before, at and after the impact, next to the error float32 itself makes (C MuJoCo's
   step from the rounded state against its step from the exact one).
4. The puck-floor contact depth one physics step after the impact (the puck tilted by the
   blow), computed by the plane-cylinder formula that C MuJoCo and MuJoCo Warp share, in
   float64 and float32 from the same pose, and in float32 with the rim offset's normal
   component taken from a cross product instead of `axis_z**2 - 1`.

The model, written here as XML, is a push-puck scene like issue 43's: a sphere pusher on
two slide joints driven by velocity servos strikes a free cylinder puck (the size of
docs/own_task.md's) resting on a plane. Its findings are in docs/batch_own_task.md
("Contact parity after an impact") and docs/reports/mujoco_warp_plane_cylinder.md.
"""

import mujoco
import numpy as np

XML = """
<mujoco model="push_puck">
  <option timestep="0.005"/>
  <worldbody>
    <geom name="floor" type="plane" size="1 1 0.05"/>
    <body name="pusher" pos="-0.1 0 0.025">
      <joint name="pusher_x" type="slide" axis="1 0 0"/>
      <joint name="pusher_y" type="slide" axis="0 1 0"/>
      <geom name="pusher" type="sphere" size="0.02" mass="0.5"/>
    </body>
    <body name="puck" pos="0.1 0.015 0.02">
      <freejoint name="puck"/>
      <geom name="puck" type="cylinder" size="0.04 0.02" mass="0.2"/>
    </body>
  </worldbody>
  <actuator>
    <velocity name="pusher_x" joint="pusher_x" kv="20" ctrlrange="-1 1"/>
    <velocity name="pusher_y" joint="pusher_y" kv="20" ctrlrange="-1 1"/>
  </actuator>
</mujoco>
"""
# The pusher's velocity targets (m/s), held for the whole rollout.
CTRL = np.array([0.4, 0.0])
PHYSICS_STEPS = 200
SUB_STEPS = 10  # physics steps per control step (a 50 ms control step)
# The state a physics step reads and writes (time aside); rounded to float32 in rollout B.
STATE = mujoco.mjtState.mjSTATE_PHYSICS
F32 = np.float32


def _model() -> tuple[mujoco.MjModel, mujoco.MjData]:
    model = mujoco.MjModel.from_xml_string(XML)
    data = mujoco.MjData(model)
    data.ctrl[:] = CTRL
    mujoco.mj_forward(model, data)
    return model, data


def _get(model, data) -> np.ndarray:
    state = np.empty(mujoco.mj_stateSize(model, STATE))
    mujoco.mj_getState(model, data, state, STATE)
    return state


def _set(model, data, state) -> None:
    mujoco.mj_setState(model, data, state, STATE)


def _rounded(state: np.ndarray) -> np.ndarray:
    return state.astype(F32).astype(np.float64)


def _c_rollout(model, start: np.ndarray, round_each_step: bool) -> tuple[np.ndarray, int]:
    """qpos after each physics step (PHYSICS_STEPS + 1, nq), and the first physics step
    whose collision finds the pusher touching the puck."""
    data = mujoco.MjData(model)
    data.ctrl[:] = CTRL
    _set(model, data, start)
    pair = {model.geom("pusher").id, model.geom("puck").id}
    qpos, impact = [data.qpos.copy()], -1
    for step in range(PHYSICS_STEPS):
        mujoco.mj_step(model, data)
        if impact < 0 and any({*c.geom} == pair for c in data.contact):
            impact = step
        if round_each_step:
            _set(model, data, _rounded(_get(model, data)))
        qpos.append(data.qpos.copy())
    return np.array(qpos), impact


class _Warp:
    """One world of the model on MuJoCo Warp's CPU device."""

    def __init__(self, model, data):
        import mujoco_warp
        import warp

        warp.config.log_level = warp.LOG_WARNING
        warp.init()
        self.wp, self.mjw = warp, mujoco_warp
        self.device = warp.get_device("cpu")
        with warp.ScopedDevice(self.device):
            self.model = mujoco_warp.put_model(model)
            self.data = mujoco_warp.put_data(model, data, nworld=1, nconmax=16, njmax=64)

    def set_state(self, model, state: np.ndarray) -> None:
        scratch = mujoco.MjData(model)
        scratch.ctrl[:] = CTRL
        _set(model, scratch, state)
        for field in ("qpos", "qvel", "qacc_warmstart", "ctrl"):
            getattr(self.data, field).assign(getattr(scratch, field)[None].astype(F32))

    def forward(self) -> None:
        with self.wp.ScopedDevice(self.device):
            self.mjw.forward(self.model, self.data)

    def step(self) -> None:
        with self.wp.ScopedDevice(self.device):
            self.mjw.step(self.model, self.data)

    def qpos(self) -> np.ndarray:
        return self.data.qpos.numpy()[0].astype(np.float64)

    def qvel(self) -> np.ndarray:
        return self.data.qvel.numpy()[0].astype(np.float64)

    def contacts(self) -> list[dict]:
        n = int(self.data.nacon.numpy()[0])
        c = self.data.contact
        geoms, dist, pos, frame = (
            c.geom.numpy()[:n],
            c.dist.numpy()[:n],
            c.pos.numpy()[:n],
            c.frame.numpy()[:n],
        )
        return [
            {"geoms": tuple(sorted(map(int, geoms[i]))), "dist": float(dist[i]),
             "pos": pos[i].astype(float), "normal": frame[i][0].astype(float)}
            for i in range(n)
        ]  # fmt: skip


def _c_contacts(data) -> list[dict]:
    return [
        {"geoms": tuple(sorted(map(int, c.geom))), "dist": float(c.dist),
         "pos": c.pos.copy(), "normal": c.frame[:3].copy()}
        for c in data.contact
    ]  # fmt: skip


def _puck_position(model, qpos: np.ndarray) -> np.ndarray:
    address = model.jnt_qposadr[model.joint("puck").id]
    return qpos[..., address : address + 3]


def _drift_table(model, start) -> int:
    reference, impact = _c_rollout(model, start, round_each_step=False)
    rounded_each, _ = _c_rollout(model, start, round_each_step=True)
    rounded_once, _ = _c_rollout(model, _rounded(start), round_each_step=False)
    warp = _Warp(model, mujoco.MjData(model))
    warp.set_state(model, start)
    warp_qpos = [warp.qpos()]
    for _ in range(PHYSICS_STEPS):
        warp.step()
        warp_qpos.append(warp.qpos())
    warp_qpos = np.array(warp_qpos)
    print(f"1. The puck's distance (mm) from C MuJoCo float64; impact at physics step {impact}")
    print("| control step | C, float32 state each step | C, start rounded once | MuJoCo Warp |")
    print("|---:|---:|---:|---:|")
    first = impact // SUB_STEPS - 1
    for control in range(first, min(first + 12, PHYSICS_STEPS // SUB_STEPS) + 1):
        row = [control - impact // SUB_STEPS]
        for rollout in (rounded_each, rounded_once, warp_qpos):
            error = _puck_position(
                model, rollout[control * SUB_STEPS] - reference[control * SUB_STEPS]
            )
            row.append(f"{1e3 * np.linalg.norm(error):.3g}")
        print("| " + " | ".join(map(str, row)) + " |")
    return impact


def _state_before(model, start, physics_step: int) -> np.ndarray:
    data = mujoco.MjData(model)
    data.ctrl[:] = CTRL
    _set(model, data, start)
    for _ in range(physics_step):
        mujoco.mj_step(model, data)
    return _get(model, data)


def _forwarded_on_both(model, state):
    """C MuJoCo's data and MuJoCo Warp's, both set to `state` and forwarded."""
    data = mujoco.MjData(model)
    data.ctrl[:] = CTRL
    _set(model, data, state)
    mujoco.mj_forward(model, data)
    warp = _Warp(model, data)
    warp.set_state(model, state)
    warp.forward()
    return data, warp


def _contact_table(model, state) -> None:
    data, warp = _forwarded_on_both(model, state)
    names = {i: model.geom(i).name for i in range(model.ngeom)}
    print("\n2. Contacts at the impact step, same (float32) state: C MuJoCo vs MuJoCo Warp")
    print("| pair | count C / Warp | dist C | dist Warp | max pos diff (m) | max normal diff |")
    print("|---|---:|---:|---:|---:|---:|")
    c_contacts, w_contacts = _c_contacts(data), warp.contacts()
    for pair in sorted({c["geoms"] for c in c_contacts + w_contacts}):
        cs = sorted((c for c in c_contacts if c["geoms"] == pair), key=lambda c: tuple(c["pos"]))
        ws = sorted((c for c in w_contacts if c["geoms"] == pair), key=lambda c: tuple(c["pos"]))
        label = "-".join(names[g] for g in pair)
        if len(cs) != len(ws):
            print(f"| {label} | {len(cs)} / {len(ws)} | | | | |")
            continue
        dpos = max(np.abs(c["pos"] - w["pos"]).max() for c, w in zip(cs, ws))
        dnormal = max(np.abs(c["normal"] - w["normal"]).max() for c, w in zip(cs, ws))
        dists = " ".join(f"{c['dist']:.6g}" for c in cs), " ".join(f"{w['dist']:.6g}" for w in ws)
        counts = f"{len(cs)} / {len(ws)}"
        print(f"| {label} | {counts} | {dists[0]} | {dists[1]} | {dpos:.2g} | {dnormal:.2g} |")
    warp_nefc = int(warp.data.nefc.numpy()[0])
    warp_qacc = warp.data.qacc.numpy()[0]
    scale = max(1.0, np.abs(data.qacc).max())
    print(
        f"\nconstraint rows: C {data.nefc}, Warp {warp_nefc}; qacc max difference "
        f"{np.abs(warp_qacc - data.qacc).max():.3g} (|qacc| up to {np.abs(data.qacc).max():.3g}, "
        f"relative {np.abs(warp_qacc - data.qacc).max() / scale:.2g})"
    )


def _one_step_table(model, start, impact: int) -> None:
    print("\n3. One physics step from the same state: qvel error (m/s, rad/s)")
    print("| physics step | Warp vs C (rounded state) | C rounded vs C exact | ratio |")
    print("|---:|---:|---:|---:|")
    warp = _Warp(model, mujoco.MjData(model))
    for step in (impact - 20, impact - 1, impact, impact + 1, impact + 2, impact + 10):
        exact = _state_before(model, start, step)
        rounded = _rounded(exact)
        after = []
        for state in (exact, rounded):
            data = mujoco.MjData(model)
            data.ctrl[:] = CTRL
            _set(model, data, state)
            mujoco.mj_step(model, data)
            after.append(data.qvel.copy())
        warp.set_state(model, rounded)
        warp.step()
        warp_error = np.abs(warp.qvel() - after[1]).max()
        rounding_error = np.abs(after[1] - after[0]).max()
        ratio = warp_error / rounding_error if rounding_error else np.inf
        print(f"| {step - impact:+d} | {warp_error:.3g} | {rounding_error:.3g} | {ratio:.3g} |")


def _rim_depth(center, axis, radius, half_height, dtype, stable: bool) -> float:
    """The depth of a cylinder's lowest rim point below the plane z = 0, computed as
    plane_cylinder does (or, `stable`, with the rim term from |axis x normal|)."""
    normal = np.array([0.0, 0.0, 1.0], dtype)
    axis = np.asarray(axis, dtype)
    projection = dtype(normal @ axis)
    if projection > 0:
        axis, projection = -axis, -projection
    if stable:
        rim = -dtype(radius) * np.sqrt(np.sum(np.cross(axis, normal) ** 2, dtype=dtype))
    else:
        vec = axis * projection - normal  # its z: axis_z**2 - 1, a cancellation
        vec = vec * (dtype(radius) / np.sqrt(vec @ vec))
        rim = dtype(vec @ normal)
    return float(dtype(center[2]) + projection * dtype(half_height) + rim)


def _formula_table(model, state) -> None:
    data, warp = _forwarded_on_both(model, state)
    puck = model.geom("puck").id
    radius, half_height = model.geom_size[puck][:2]
    c_center, c_axis = data.geom_xpos[puck], data.geom_xmat[puck].reshape(3, 3)[:, 2]
    w_center = warp.data.geom_xpos.numpy()[0][puck]
    w_axis = warp.data.geom_xmat.numpy()[0][puck][:, 2]
    floor = {model.geom("floor").id, puck}
    c_dist = [c["dist"] for c in _c_contacts(data) if {*c["geoms"]} == floor]
    w_dist = [c["dist"] for c in warp.contacts() if {*c["geoms"]} == floor]
    tilt = np.degrees(np.arccos(abs(c_axis[2])))
    print(
        f"\n4. Puck-floor contact depth (m) one physics step after the impact, tilt {tilt:.3g} deg"
    )
    print("| computed by | dist |")
    print("|---|---:|")
    size = (radius, half_height)
    rows = (
        ("C MuJoCo (mj_forward)", c_dist[0]),
        ("MuJoCo Warp (forward)", w_dist[0]),
        ("the formula, float64, C's pose", _rim_depth(c_center, c_axis, *size, np.float64, False)),
        ("the formula, float32, Warp's pose", _rim_depth(w_center, w_axis, *size, F32, False)),
        ("cross-product rim term, float32, Warp's", _rim_depth(w_center, w_axis, *size, F32, True)),
    )
    for label, value in rows:
        print(f"| {label} | {value:.6g} |")


def main() -> None:
    model, data = _model()
    start = _get(model, data)
    impact = _drift_table(model, start)
    _contact_table(model, _rounded(_state_before(model, start, impact)))
    _one_step_table(model, start, impact)
    _formula_table(model, _rounded(_state_before(model, start, impact + 1)))


if __name__ == "__main__":
    main()
