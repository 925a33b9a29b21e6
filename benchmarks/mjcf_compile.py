"""What the mjcf layer adds to compiling a model, as ratios measured in one run.

Scene: a floor arena with six attached sub-models (five limbed "crawlers" with different
mesh and texture assets, one of them carrying an attached gripper), built in Python with
the mjcf API: materials, textures (generated PNG bytes), meshes (generated binary STL as
`mjcf.Asset`), default classes, joints, sites, actuators, sensors and a tendon.

Baseline: `mujoco.MjModel.from_xml_string(xml, assets)` of the scene's own XML and assets
(for the bind row: the direct `data.geom_xpos[ids]` read it stands for), run just before
each measured call. A row's ratio is the median over repetitions of (call / its baseline),
so load that slows a repetition slows both halves of its pair; best-of-N (fastest call /
fastest baseline) is shown too. The cyclic garbage collector is off while the clock runs.

Rows:
  to_xml_string, first call: on a newly built scene (built before the clock starts): what a
    model's first XML costs.
  to_xml_string, one attribute changed: after setting one geom's rgba, in steady state (the
    model has been written since its names last changed, as when episodes vary attributes).
  to_xml_string, unchanged: a repeated call on an unchanged model.
  to_xml_string, named element added: after adding a named site; a change of names makes
    every element's tag be rebuilt.
  from_mjcf_model, first call: `mjcf.Physics.from_mjcf_model` on a newly built scene (XML,
    assets, compile, MjData, forward).
  from_mjcf_model, XML cached: the same again on that unchanged scene.
  from_mjcf_model, one attribute changed: after setting one geom's rgba, in steady state.
  bind(20 geoms).xpos: a repeated `physics.bind(geoms).xpos` read.

Usage (from the repository root): PYTHONPATH=. python benchmarks/mjcf_compile.py [--repeats N]
"""

import argparse
import functools
import gc
import statistics
import struct
import time
import zlib

import mujoco
import numpy as np

import mjcf

_TARGETS = {
    "to_xml_string, first call": 0.5,
    "to_xml_string, one attribute changed": 0.5,
    "to_xml_string, unchanged": 0.5,
    "to_xml_string, named element added": 0.5,
    "from_mjcf_model, first call": 1.6,
    "from_mjcf_model, XML cached": 1.3,
    "from_mjcf_model, one attribute changed": 1.3,
    "bind(20 geoms).xpos": 3.0,
}
_BIND_ROW = "bind(20 geoms).xpos"
_CRAWLERS = 5
_LEGS = 4
_LEG_SEGMENTS = 2
_BIND_GEOMS = 20
_BIND_LOOP = 2000


def _png(width: int, height: int, seed: int) -> bytes:
    """An RGB checker-and-noise PNG, encoded by hand (zlib + CRC chunks)."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:height, 0:width]
    checker = ((x // 8 + y // 8) % 2).astype(np.uint8) * 120
    pixels = np.stack([checker, rng.integers(0, 255, (height, width)), 255 - checker], axis=-1)
    rows = np.concatenate(
        [np.zeros((height, 1), np.uint8), pixels.astype(np.uint8).reshape(height, -1)], axis=1
    )

    def chunk(kind: bytes, payload: bytes) -> bytes:
        body = kind + payload
        return struct.pack(">I", len(payload)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(rows.tobytes()))
        + chunk(b"IEND", b"")
    )


def _prism_stl(sides: int, radius: float, length: float) -> bytes:
    """A closed regular prism along z as a binary STL, like a simple robot link."""
    angles = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    ring = np.stack([radius * np.cos(angles), radius * np.sin(angles)], axis=1)
    bottom = [np.array([px, py, 0.0]) for px, py in ring]
    top = [np.array([px, py, length]) for px, py in ring]
    low_centre, high_centre = np.zeros(3), np.array([0.0, 0.0, length])
    triangles = []
    for i in range(sides):
        j = (i + 1) % sides
        triangles += [
            (bottom[i], bottom[j], top[j]),
            (bottom[i], top[j], top[i]),
            (low_centre, bottom[j], bottom[i]),
            (high_centre, top[i], top[j]),
        ]
    out = [b"\0" * 80, struct.pack("<I", len(triangles))]
    for a, b, c in triangles:
        normal = np.cross(b - a, c - a)
        normal /= np.linalg.norm(normal)
        out.append(struct.pack("<12fH", *normal, *a, *b, *c, 0))
    return b"".join(out)


def _crawler(index: int) -> mjcf.RootElement:
    """A torso with four two-segment legs, a mesh head, sensors and position actuators."""
    model = mjcf.RootElement(model=f"crawler{index}")
    asset = model.asset
    asset.add("texture", name="skin", type="2d", file=mjcf.Asset(_png(32, 32, index), ".png"))
    asset.add("material", name="hide", texture="skin", texrepeat=[2, 2], rgba=[0.9, 0.8, 0.7, 1])
    asset.add("material", name="claw", rgba=[0.2, 0.2, 0.2, 1], specular=0.3)
    asset.add("mesh", name="head", file=mjcf.Asset(_prism_stl(8 + 4 * index, 0.06, 0.08), ".stl"))

    model.default.geom.set_attributes(contype=1, conaffinity=1, friction=[0.9, 0.01, 0.001])
    leg = model.default.add("default", dclass="leg")
    leg.geom.set_attributes(type="capsule", size=[0.02], material="hide")
    leg.joint.set_attributes(type="hinge", damping=0.5, range=[-60, 60])
    leg.add("default", dclass="claw").geom.set_attributes(
        type="sphere", size=[0.015], material="claw"
    )

    torso = model.worldbody.add("body", name="torso", pos=[0, 0, 0.2])
    torso.add("geom", name="core", type="box", size=[0.12, 0.08, 0.04], material="hide")
    torso.add("geom", name="head", type="mesh", mesh="head", pos=[0.13, 0, 0])
    for k in range(6):
        torso.add(
            "geom",
            type="sphere",
            size=[0.012],
            pos=[0.1 * (k % 3 - 1), 0.08 * (k // 3 * 2 - 1), 0.04],
            rgba=[0.1, 0.1, 0.1, 1],
        )
    torso.add("site", name="imu", size=[0.01])
    torso.add("camera", name="eye", pos=[0.2, 0, 0.05], xyaxes=[0, -1, 0, 0, 0, 1])
    for leg_index in range(_LEGS):
        angle = np.pi / 4 + leg_index * np.pi / 2
        direction = np.array([np.cos(angle), np.sin(angle), 0.0])
        parent = torso
        pos = direction * 0.12
        for segment in range(_LEG_SEGMENTS):
            name = f"leg{leg_index}_{segment}"
            body = parent.add("body", name=name, pos=pos, childclass="leg")
            body.add("joint", name=f"{name}_hinge", axis=[-direction[1], direction[0], 0])
            tip = direction * 0.1 + [0, 0, -0.04 * segment]
            body.add("geom", name=f"{name}_bone", fromto=np.concatenate([[0, 0, 0], tip]))
            for k in range(4):
                body.add("geom", dclass="claw", pos=tip * (k + 1) / 5, size=[0.01 + 0.002 * k])
            body.add("geom", dclass="claw", pos=tip)
            body.add("site", name=f"{name}_tip", pos=tip, size=[0.01])
            model.actuator.add(
                "position", name=f"{name}_servo", joint=f"{name}_hinge", kp=20, ctrlrange=[-1, 1]
            )
            model.sensor.add("jointpos", name=f"{name}_angle", joint=f"{name}_hinge")
            parent = body
            pos = tip
        model.sensor.add(
            "touch", name=f"foot{leg_index}", site=f"leg{leg_index}_{_LEG_SEGMENTS - 1}_tip"
        )
    tendon = model.tendon.add("spatial", name="belly", width=0.003)
    tendon.add("site", site="leg0_0_tip")
    tendon.add("site", site="leg2_0_tip")
    model.sensor.add("accelerometer", name="accel", site="imu")
    model.sensor.add("gyro", name="gyro", site="imu")
    return model


def _gripper() -> mjcf.RootElement:
    """A two-finger gripper with slide joints and a mesh palm."""
    model = mjcf.RootElement(model="gripper")
    model.asset.add("mesh", name="palm", file=mjcf.Asset(_prism_stl(12, 0.04, 0.03), ".stl"))
    model.default.add("default", dclass="finger").geom.set_attributes(
        type="box", size=[0.005, 0.01, 0.03], rgba=[0.6, 0.6, 0.7, 1]
    )
    palm = model.worldbody.add("body", name="palm")
    palm.add("geom", type="mesh", mesh="palm")
    for side in (-1, 1):
        finger = palm.add("body", name=f"finger{side + 1}", pos=[0.02 * side, 0, 0.03])
        finger.add(
            "joint", name=f"slide{side + 1}", type="slide", axis=[side, 0, 0], range=[0, 0.02]
        )
        for k in range(5):
            finger.add("geom", dclass="finger", pos=[0, 0, 0.01 * k])
        finger.add("site", name=f"pad{side + 1}", size=[0.005])
    model.actuator.add("position", name="grip", joint="slide0", kp=50, ctrlrange=[0, 0.02])
    model.equality.add("joint", joint1="slide0", joint2="slide2")
    return model


def build_scene() -> mjcf.RootElement:
    """The benchmark scene: floor arena + five crawlers (one with a gripper on top)."""
    arena = mjcf.RootElement(model="arena")
    arena.option.timestep = 0.004
    arena.asset.add(
        "texture",
        name="grid",
        type="2d",
        builtin="checker",
        width=64,
        height=64,
        rgb1=[0.2, 0.3, 0.4],
        rgb2=[0.1, 0.2, 0.3],
    )
    arena.asset.add("material", name="grid", texture="grid", texrepeat=[4, 4])
    arena.worldbody.add("geom", name="floor", type="plane", size=[4, 4, 0.1], material="grid")
    arena.worldbody.add("light", name="sun", pos=[0, 0, 3], dir=[0, 0, -1])
    for k in range(12):
        arena.worldbody.add(
            "geom", type="box", size=[0.05, 0.05, 0.05], pos=[-1 + k * 0.2, 1.5, 0.05]
        )
    crawlers = [_crawler(i) for i in range(_CRAWLERS)]
    crawlers[0].find("body", "torso").add("site", name="mount", pos=[0, 0, 0.05]).attach(_gripper())
    for i, crawler in enumerate(crawlers):
        frame = arena.worldbody.attach(crawler)
        frame.pos = [i * 0.6 - 1.2, 0, 0]
        frame.add("freejoint")
    return arena


def _time(function) -> float:
    """Seconds `function()` takes; what it returns is freed after the clock stops.

    As in `timeit`, the cyclic garbage collector is off while the clock runs, so that
    collecting garbage left by earlier repetitions does not land in a random measurement.
    """
    gc.disable()
    try:
        start = time.perf_counter()
        result = function()
        elapsed = time.perf_counter() - start
    finally:
        gc.enable()
    del result
    return elapsed


def _scene_size(xml: str, assets: dict) -> str:
    model = mujoco.MjModel.from_xml_string(xml, assets)
    return (
        f"{model.nbody} bodies, {model.ngeom} geoms, {model.njnt} joints, {model.nmesh} meshes, "
        f"{model.ntex} textures, {model.nmat} materials, {model.nu} actuators, "
        f"{model.nsensor} sensors"
    )


def _measure_model_layer(scene: mjcf.RootElement, repeats: int) -> dict[str, list]:
    """(time, baseline compile time just before it) samples of each model-layer row."""
    xml, assets = scene.to_xml_string(), scene.get_assets()
    rows = {name: [] for name in _TARGETS if name != _BIND_ROW}
    probe = scene.find("geom", "crawler3/leg2_1_bone")
    torso = scene.find("body", "crawler2/torso")
    compile_scene = functools.partial(mjcf.Physics.from_mjcf_model, scene)

    def baseline() -> float:
        return _time(lambda: mujoco.MjModel.from_xml_string(xml, assets))

    def sample(row: str, base: float, function) -> None:
        rows[row].append((_time(function), base))

    # Each measured call follows what precedes it in user code (build or change, then
    # write); each is paired with the baseline compile run just before that. The changes to
    # `scene` are measured in steady state, as in episodes that vary attributes: the model
    # has been written since its last change of names.
    for repeat in range(repeats):
        base = baseline()
        sample("to_xml_string, first call", base, build_scene().to_xml_string)
        base = baseline()
        probe.rgba = [repeat / repeats, 0.5, 0.5, 1]
        sample("to_xml_string, one attribute changed", base, scene.to_xml_string)
        sample("to_xml_string, unchanged", base, scene.to_xml_string)
        base = baseline()
        probe.rgba = [0.5, repeat / repeats, 0.5, 1]
        sample("from_mjcf_model, one attribute changed", base, compile_scene)
        base = baseline()
        added = torso.add("site", name=f"probe{repeat}", size=[0.01])
        sample("to_xml_string, named element added", base, scene.to_xml_string)
        added.remove()
        for settle in range(2):
            probe.rgba = [0.5, 0.5, settle, 1]
            scene.to_xml_string()
        base = baseline()
        compile_fresh = functools.partial(mjcf.Physics.from_mjcf_model, build_scene())
        sample("from_mjcf_model, first call", base, compile_fresh)
        sample("from_mjcf_model, XML cached", baseline(), compile_fresh)
    return rows


def _measure_bind(scene: mjcf.RootElement, repeats: int) -> list:
    """(binding read time, direct read time just before it) samples, per read."""
    physics = mjcf.Physics.from_mjcf_model(scene)
    all_geoms = scene.find_all("geom")
    geoms = all_geoms[:: len(all_geoms) // _BIND_GEOMS][:_BIND_GEOMS]
    ids = np.array([physics.model.name2id(g.full_identifier, "geom") for g in geoms])
    data = physics.data.ptr

    def direct():
        for _ in range(_BIND_LOOP):
            _ = data.geom_xpos[ids]

    def bound():
        for _ in range(_BIND_LOOP):
            _ = physics.bind(geoms).xpos

    bound()  # The first bind builds the binding; the repeated reads are what is measured.
    samples = []
    for _ in range(repeats):
        base = _time(direct)
        samples.append((_time(bound) / _BIND_LOOP, base / _BIND_LOOP))
    return samples


def run(repeats: int) -> dict[str, float]:
    """Measures every row and prints the table; returns each row's ratio."""
    scene = build_scene()
    xml, assets = scene.to_xml_string(), scene.get_assets()
    print(f"Scene: {_scene_size(xml, assets)}; {len(xml) // 1024} KiB of XML, {len(assets)} assets")
    table = [
        (name, samples, 1e3, "ms") for name, samples in _measure_model_layer(scene, repeats).items()
    ]
    table.append((_BIND_ROW, _measure_bind(scene, repeats), 1e6, "us"))
    compiles = [base for _, samples, _, _ in table[:-1] for _, base in samples]
    directs = [base for _, base in table[-1][1]]
    print(
        f"Baseline: compile {statistics.median(compiles) * 1e3:.2f} ms (median of "
        f"{len(compiles)}); direct geom_xpos[ids] read {statistics.median(directs) * 1e6:.2f} us"
    )
    print()
    header = ("row", "median", "ratio", "best-of-N", "target")
    print("{:38s} {:>10s} {:>6s} {:>9s} {:>6s}  result".format(*header))
    ratios = {}
    for name, samples, scale, unit in table:
        calls = [call for call, _ in samples]
        ratio = statistics.median(call / base for call, base in samples)
        best = min(calls) / min(base for _, base in samples)
        target = _TARGETS[name]
        ratios[name] = ratio
        print(
            f"{name:38s} {statistics.median(calls) * scale:7.2f} {unit} {ratio:5.2f}x "
            f"{best:8.2f}x {target:5.2f}x  {'PASS' if ratio <= target else 'MISS'}"
        )
    return ratios


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=40)
    run(parser.parse_args().repeats)


if __name__ == "__main__":
    main()
