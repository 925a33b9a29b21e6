"""Bad MJCF inputs, and a runner that feeds each to the pipeline and reports what it raised.

Run as a script (``python bad_input_cases.py DIRECTORY``) it prints one JSON line per case:
its name, the exception type raised (null when it compiled) and the seconds it took. The
test runs it in a subprocess so that a crash or a hang fails the test instead of killing it.
"""

from __future__ import annotations

import json
import os
import random
import sys
import time

#: Exception types a bad input may raise (docs/mujoco_differences.md).
DOCUMENTED = (
    "ValueError",
    "MJCFSyntaxError",
    "FileNotFoundError",
    "IsADirectoryError",
    "PermissionError",
)

_SEED = """<mujoco model="m">
  <asset><mesh name="m" file="mesh.stl"/></asset>
  <worldbody>
    <body name="a" pos="0 0 1"><joint name="j" axis="0 1 0"/>
      <geom name="g" type="capsule" size="0.05 0.2" rgba="1 0 0 1"/></body>
  </worldbody>
  <actuator><motor joint="j" gear="10"/></actuator>
</mujoco>"""


def _nested(depth: int) -> str:
    return "<mujoco><worldbody>" + "<body>" * depth + "</body>" * depth + "</worldbody></mujoco>"


def cases(directory: str) -> dict:
    """Case name -> (how to load: 'string', 'path' or 'physics', the text or path)."""
    rng = random.Random(7)
    found = {}
    seed = _SEED.replace('<asset><mesh name="m" file="mesh.stl"/></asset>', "")
    for _ in range(12):
        cut = rng.randrange(1, len(seed))
        found[f"truncated at {cut}"] = ("string", seed[:cut])
    for index in range(12):
        junk = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 400)))
        found[f"binary junk {index}"] = ("string", junk)
    found["empty"] = ("string", b"")
    found["NUL bytes"] = ("string", b"<mujoco>\x00</mujoco>")
    found["junk after root"] = ("string", seed + "\x01\x02garbage")
    found["huge exponent"] = ("string", seed.replace("0.05 0.2", "1e999999 0.2"))
    found["100k digit number"] = ("string", seed.replace("0.05 0.2", "1" * 100_000 + " 0.2"))
    found["huge int"] = ("string", seed.replace('gear="10"', 'gear="10" group="9' + "9" * 40 + '"'))
    found["nested 496 bodies"] = ("physics", _nested(496))
    found["nested 600 bodies"] = ("string", _nested(600))
    found["nested 100k bodies"] = ("string", _nested(100_000))
    found["100k sibling sites"] = (
        "string",
        "<mujoco><worldbody>" + "<site/>" * 100_000 + "</worldbody></mujoco>",
    )
    found["invalid UTF-8 name"] = (
        "physics",
        seed.encode().replace(b'name="g"', b'name="\xff\xfe"'),
    )
    latin = '<?xml version="1.0" encoding="latin-1"?>' + seed.replace('name="g"', 'name="caf\xe9"')
    found["latin-1 name"] = ("physics", latin.encode("latin-1"))
    found["UTF-16 document"] = ("physics", seed.encode("utf-16"))

    def write(name: str, text: str) -> str:
        path = os.path.join(directory, name)
        with open(path, "w", encoding="utf-8") as handle:
            handle.write(text)
        return path

    write("a.xml", '<mujoco><include file="b.xml"/></mujoco>')
    write("b.xml", '<mujoco><include file="a.xml"/></mujoco>')
    found["cyclic include"] = (
        "path",
        write("cycle.xml", '<mujoco><include file="a.xml"/></mujoco>'),
    )
    found["self include"] = (
        "path",
        write("self.xml", '<mujoco><include file="self.xml"/></mujoco>'),
    )
    found["missing include"] = (
        "path",
        write("inc.xml", '<mujoco><include file="no.xml"/></mujoco>'),
    )
    os.makedirs(os.path.join(directory, "folder.xml"), exist_ok=True)
    found["include of a folder"] = (
        "path",
        write("dir.xml", '<mujoco><include file="folder.xml"/></mujoco>'),
    )
    found["missing mesh file"] = ("path", write("mesh.xml", _SEED))
    os.makedirs(os.path.join(directory, "folder.stl"), exist_ok=True)
    found["mesh file is a folder"] = (
        "path",
        write("meshdir.xml", _SEED.replace("mesh.stl", "folder.stl")),
    )
    with open(os.path.join(directory, "junk.stl"), "wb") as handle:
        handle.write(bytes(range(256)) * 4)
    found["junk mesh file"] = ("path", write("junk.xml", _SEED.replace("mesh.stl", "junk.stl")))
    found["model file missing"] = ("path", os.path.join(directory, "absent.xml"))
    found["model file is a folder"] = ("path", os.path.join(directory, "folder.xml"))
    return found


def _load(how: str, value) -> None:
    import mjcf

    if how == "path":
        mjcf.Physics.from_mjcf_model(mjcf.from_path(value))
    elif how == "physics":
        mjcf.Physics.from_mjcf_model(mjcf.from_xml_string(value))
    else:
        mjcf.from_xml_string(value)


def main() -> None:
    for name, (how, value) in cases(sys.argv[1]).items():
        start = time.perf_counter()
        try:
            _load(how, value)
            raised = None
        except Exception as error:  # noqa: BLE001 - the type is the report
            raised = type(error).__name__
        seconds = time.perf_counter() - start
        print(json.dumps({"case": name, "raised": raised, "seconds": seconds}), flush=True)


if __name__ == "__main__":
    main()
