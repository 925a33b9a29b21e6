"""Renders the docs' task gallery: `python -m tools.docs.gallery OUT` writes OUT/gallery.md.

It also writes one PNG per manipulation task next to it, OUT/<name>.png.

Each image is the `front_far` camera's view of the task right after `reset()` with seed 0,
rendered from the real environment; each task's section lists its observation and action
specs as the environment reports them.
"""

import dataclasses
import os
import pathlib
import sys
import time

os.environ.setdefault("MUJOCO_GL", "egl")

from PIL import Image  # noqa: E402

import manipulation  # noqa: E402  (the GL backend is chosen when mujoco is imported)

IMAGE_HEIGHT, IMAGE_WIDTH = 300, 400
_CAMERA = "front_close"
# Shown smaller than rendered, so that the observation table fits beside the picture.
_SHOWN_WIDTH = 256
_SEED = 0


@dataclasses.dataclass(frozen=True)
class SpecRow:
    """One row of a spec table: a name, a shape, a dtype and (for actions) the bounds."""

    name: str
    shape: tuple[int, ...]
    dtype: str
    minimum: float | None = None
    maximum: float | None = None


@dataclasses.dataclass(frozen=True)
class TaskEntry:
    """What the gallery shows of one task."""

    name: str
    summary: str
    tags: tuple[str, ...]
    image_file: str
    observations: tuple[SpecRow, ...]
    actions: tuple[SpecRow, ...]


def _tags_by_name() -> dict[str, tuple[str, ...]]:
    tags: dict[str, list[str]] = {name: [] for name in manipulation.ALL}
    for tag in manipulation.TAGS:
        for name in manipulation.get_environments_by_tag(tag):
            tags[name].append(tag)
    return {name: tuple(found) for name, found in tags.items()}


def render_task(name: str, out: pathlib.Path, tags: tuple[str, ...] = ()) -> TaskEntry:
    """Loads task `name`, resets it with seed 0, writes `out/<name>.png`, returns its entry."""
    env = manipulation.load(name, seed=_SEED)
    env.reset()
    image_file = f"{name}.png"
    image = env.physics.render(IMAGE_HEIGHT, IMAGE_WIDTH, camera_id=_CAMERA)
    Image.fromarray(image).save(out / image_file)
    action_spec = env.action_spec()
    action_names = action_spec.name.split("\t")
    actions = tuple(
        SpecRow(
            action_names[i],
            (),
            action_spec.dtype.name,
            float(action_spec.minimum[i]),
            float(action_spec.maximum[i]),
        )
        for i in range(action_spec.shape[0])
    )
    observations = tuple(
        SpecRow(key, tuple(spec.shape), spec.dtype.name)
        for key, spec in env.observation_spec().items()
    )
    summary = (type(env.task).__doc__ or "").strip().splitlines()[0]
    env.close()
    return TaskEntry(name, summary, tags, image_file, observations, actions)


def _breakable(name: str) -> str:
    """`name` with zero-width spaces after underscores, so captions wrap between words."""
    return name.replace("_", "_\u200b")


def _observation_table(rows: tuple[SpecRow, ...]) -> list[str]:
    lines = ["| observation | shape | dtype |", "|---|---|---|"]
    lines += [f"| `{row.name}` | {row.shape} | {row.dtype} |" for row in rows]
    return lines


def _action_table(rows: tuple[SpecRow, ...]) -> list[str]:
    lines = ["| # | action (actuator) | min | max |", "|---|---|---|---|"]
    lines += [
        f"| {i} | `{row.name}` | {row.minimum:g} | {row.maximum:g} |" for i, row in enumerate(rows)
    ]
    return lines


def gallery_markdown(entries: list[TaskEntry], seconds: float) -> str:
    """Returns the gallery page: a grid of thumbnails, then one section per task."""
    lines = [
        "# Task gallery",
        "",
        f"All {len(entries)} tasks of `manipulation.ALL`, each as the `{_CAMERA}` camera sees "
        f"it right after `manipulation.load(name, seed={_SEED}).reset()`. The pictures and "
        "the spec tables are produced from the real environments by `tools/docs/gallery.py` "
        f"every time the site is built (this build: {seconds:.0f} s for all of them).",
        "",
        "This is the camera the vision tasks observe, there as 84x84 images instead of the "
        "props' features; a vision task's scene is the same as its features variant's.",
        "",
        '<div class="gallery-grid" markdown>',
        "",
    ]
    for entry in entries:
        lines += [
            f"[![{entry.name}]({entry.image_file}){{ loading=lazy }}<br>"
            f"`{_breakable(entry.name)}`](#{entry.name})",
            "",
        ]
    lines += ["</div>", ""]
    for entry in entries:
        lines += [
            f"## {entry.name}",
            "",
            f"{entry.summary} Tags: {', '.join(f'`{tag}`' for tag in entry.tags)}.",
            "",
            '<div class="gallery-task" markdown>',
            "",
            f"![{entry.name} after reset]({entry.image_file}){{ loading=lazy "
            f"width={_SHOWN_WIDTH} height={_SHOWN_WIDTH * IMAGE_HEIGHT // IMAGE_WIDTH} }}",
            "",
            '<div class="gallery-specs" markdown>',
            "",
            *_observation_table(entry.observations),
            "",
            "</div>",
            "",
            "</div>",
            "",
            '<div class="gallery-specs" markdown>',
            "",
            *_action_table(entry.actions),
            "",
            "</div>",
            "",
        ]
    return "\n".join(lines)


def main() -> None:
    out = pathlib.Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    tags = _tags_by_name()
    entries = [render_task(name, out, tags[name]) for name in manipulation.ALL]
    (out / "gallery.md").write_text(gallery_markdown(entries, time.perf_counter() - start))
    print(f"gallery: {len(entries)} tasks in {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
