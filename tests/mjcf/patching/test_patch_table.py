"""mjcf.patching.patch_table: which proofs apply on the installed MuJoCo, kept in a cache
file that concurrent processes share."""

import fcntl
import json
import subprocess
import sys
import textwrap
import threading
import warnings

import mujoco
import pytest

import mjcf
from mjcf.patching import patch_table, patchable_attributes
from mjcf.patching.patch_context import ON_ELEMENT, PatchContext

_SCENE = """
<mujoco>
  <worldbody>
    <body name="ball" pos="0 0 1">
      <freejoint/>
      <geom name="ball" type="sphere" size="0.1" rgba="1 0 0 1"/>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture
def unproven_release(monkeypatch, tmp_path):
    """The checked-in table claims another release, and the user's cache directory is a
    fresh temporary folder; returns that folder."""
    monkeypatch.setattr(patchable_attributes, "MUJOCO_VERSION", "0.0.0")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    return tmp_path


def _patches_a_colour() -> bool:
    root = mjcf.from_xml_string(_SCENE)
    physics = mjcf.Physics.from_mjcf_model(root)
    count = root.modification_count
    root.find("geom", "ball").rgba = [0, 1, 0, 1]
    return physics.apply_attribute_changes(root.attribute_changes_since(count))


def _cache_file(folder):
    return folder / "mujoco-composer" / "patch_proof" / f"mujoco-{mujoco.__version__}.json"


def test_the_cache_file_is_one_per_mujoco_release_under_xdg_cache_home(monkeypatch, tmp_path):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    expected = tmp_path / "xdg" / "mujoco-composer" / "patch_proof" / "mujoco-4.0.1.json"
    assert patch_table.cache_path("4.0.1") == expected


def test_the_cache_file_is_under_dot_cache_without_xdg_cache_home(monkeypatch, tmp_path):
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))
    expected = tmp_path / ".cache" / "mujoco-composer" / "patch_proof" / "mujoco-3.3.0.json"
    assert patch_table.cache_path("3.3.0") == expected


def test_the_checked_in_table_applies_on_the_release_it_was_proven_on(monkeypatch):
    monkeypatch.setattr(patchable_attributes, "MUJOCO_VERSION", mujoco.__version__)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = patch_table.current()
    assert table.proven is patchable_attributes.PROVEN
    assert table.source == "mjcf/patching/patchable_attributes.py"


def _context(attribute: str) -> PatchContext:
    return PatchContext("geom", attribute, ON_ELEMENT, False, ("no springdamper",))


def test_a_release_with_no_proof_patches_at_first_use_silently_and_caches_the_proof(
    unproven_release,
):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = patch_table.current()
        assert table.source == "none"
        assert table.proven == {}
        assert _patches_a_colour()
    record = json.loads(_cache_file(unproven_release).read_text(encoding="utf-8"))
    [proof] = record["contexts"]
    assert (proof["tag"], proof["attribute"], proof["where"]) == ("geom", "rgba", "element")
    assert proof["set_const"] is False
    assert [model.split(" ")[0] for model in proof["models"]] == ["unnamed_model"]


def test_a_cached_corpus_proof_for_the_installed_release_gives_its_pair_verdicts(
    unproven_release,
):
    patch_table.write_cache({("geom", "rgba"): False}, {("geom", "pos"): "body_ipos"})
    assert _cache_file(unproven_release).exists()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        table = patch_table.current()
        assert _patches_a_colour()
    assert table.proven == {("geom", "rgba"): False}
    assert table.refused == {("geom", "pos"): "body_ipos"}
    assert table.source == str(_cache_file(unproven_release))
    # The colour needed no proof at first use.
    assert json.loads(_cache_file(unproven_release).read_text())["contexts"] == []


def _assert_ignored_then_replaced(path, match: str) -> None:
    with pytest.warns(RuntimeWarning, match=match) as caught:
        table = patch_table.current()
        assert table.proven == {} and table.contexts == {}
        assert _patches_a_colour()
    assert len(caught) == 1
    assert str(path) in str(caught[0].message)
    record = json.loads(path.read_text(encoding="utf-8"))
    assert record["mujoco"] == mujoco.__version__
    assert [proof["attribute"] for proof in record["contexts"]] == ["rgba"]


def test_a_corrupt_cache_file_is_ignored_with_a_warning_naming_it_and_replaced(
    unproven_release,
):
    path = _cache_file(unproven_release)
    path.parent.mkdir(parents=True)
    path.write_text('{"format": 2, "mujoco": ', encoding="utf-8")
    _assert_ignored_then_replaced(path, "ignoring the cached patch proof")


def test_a_cache_file_with_malformed_pairs_is_ignored_with_a_warning(unproven_release):
    patch_table.write_cache({("geom", "rgba"): False}, {})
    path = _cache_file(unproven_release)
    record = json.loads(path.read_text(encoding="utf-8"))
    record["proven"] = [["geom"]]
    path.write_text(json.dumps(record), encoding="utf-8")
    _assert_ignored_then_replaced(path, "ignoring the cached patch proof")


def test_a_cache_file_proven_on_another_mujoco_release_is_ignored(unproven_release):
    patch_table.write_cache({("geom", "rgba"): False}, {})
    path = _cache_file(unproven_release)
    record = json.loads(path.read_text(encoding="utf-8"))
    record["mujoco"] = "9.9.9"
    path.write_text(json.dumps(record), encoding="utf-8")
    _assert_ignored_then_replaced(
        path, rf"it was proven on mujoco 9\.9\.9, the installed one is {mujoco.__version__}"
    )


def test_a_cache_file_proven_by_another_version_of_the_project_is_ignored(unproven_release):
    patch_table.write_cache({("geom", "rgba"): False}, {})
    path = _cache_file(unproven_release)
    record = json.loads(path.read_text(encoding="utf-8"))
    record["project"] = "0.0.1-older"
    path.write_text(json.dumps(record), encoding="utf-8")
    _assert_ignored_then_replaced(path, r"proven by mujoco-composer 0\.0\.1-older")


def test_a_cache_file_of_an_older_format_is_ignored_naming_its_format(unproven_release):
    # What a user upgrading from a version that cached pair verdicts only (format 1) meets.
    path = _cache_file(unproven_release)
    path.parent.mkdir(parents=True)
    record = {"format": 1, "mujoco": mujoco.__version__, "proven": [["geom", "rgba", False]]}
    path.write_text(json.dumps(record), encoding="utf-8")
    _assert_ignored_then_replaced(path, r"proofs of format 1 \(another version of mujoco-composer")


def test_a_proof_made_in_another_process_is_read_before_proving_again(unproven_release):
    assert patch_table.current().contexts == {}
    subprocess.run(
        [sys.executable, "-c", _RECORDER.format(writer=0, count=1)],
        check=True,
        env={"XDG_CACHE_HOME": str(unproven_release), "PATH": ""},
    )
    assert patch_table.current().contexts == {}  # read once per process ...
    assert _context("w0-0") in patch_table.refresh().contexts  # ... and again before a proof


# A process that records `count` proofs of made-up contexts, one write each.
_RECORDER = textwrap.dedent(
    """
    from mjcf.patching import patch_table
    from mjcf.patching.patch_context import ON_ELEMENT, PatchContext
    for number in range({count}):
        context = PatchContext("geom", "w{writer}-%d" % number, ON_ELEMENT, False,
                               ("no springdamper",))
        patch_table.record({{context: False}}, {{}}, "writer {writer}")
    """
)


def test_concurrent_writers_lose_no_proof_and_readers_never_see_half_a_file(unproven_release):
    writers, count = 4, 15
    path = _cache_file(unproven_release)
    half_read: list[str] = []
    done = threading.Event()

    def read_while_written():
        while not done.is_set():
            try:
                text = path.read_text(encoding="utf-8")
            except FileNotFoundError:
                continue
            try:
                json.loads(text)
            except ValueError:
                half_read.append(text)

    reader = threading.Thread(target=read_while_written)
    reader.start()
    try:
        processes = [
            subprocess.Popen(
                [sys.executable, "-c", _RECORDER.format(writer=writer, count=count)],
                env={"XDG_CACHE_HOME": str(unproven_release), "PATH": ""},
            )
            for writer in range(writers)
        ]
        assert [process.wait(timeout=120) for process in processes] == [0] * writers
    finally:
        done.set()
        reader.join()
    assert half_read == []
    record = json.loads(path.read_text(encoding="utf-8"))
    written = sorted(proof["attribute"] for proof in record["contexts"])
    assert written == sorted(f"w{w}-{n}" for w in range(writers) for n in range(count))


def test_a_cache_file_locked_too_long_keeps_the_proof_in_the_process_with_a_warning(
    unproven_release, monkeypatch
):
    monkeypatch.setattr(patch_table, "LOCK_TIMEOUT", 0.2)
    path = _cache_file(unproven_release)
    path.parent.mkdir(parents=True)
    with open(path.with_name(path.name + ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        with pytest.warns(RuntimeWarning, match="stayed locked by another process") as caught:
            patch_table.record({_context("rgba"): False}, {}, "held")
    assert str(path) in str(caught[0].message)
    assert not path.exists()
    assert patch_table.current().contexts[_context("rgba")].models == ("held",)
