"""The registry of the suite: environment names, their task constructors and tags.

Each task family registers a constructor under a base name; the registry names it
'<base>_features' (ground-truth features) and, unless told otherwise, '<base>_vision'
(camera images), and tags each name 'features' or 'vision' plus the family's own tags.
"""

import collections
import difflib
from collections.abc import Callable, Sequence

import composer
from manipulation.tasks import observation_settings

_CONSTRUCTORS: dict[str, Callable[[], composer.Task]] = {}
_TAGS: dict[str, list[str]] = collections.defaultdict(list)

_VARIANTS = (
    ("features", observation_settings.FEATURES),
    ("vision", observation_settings.VISION),
)


def add(
    base_name: str,
    constructor: Callable[[observation_settings.ObservationSettings], composer.Task],
    tags: Sequence[str] = (),
    vision: bool = True,
) -> None:
    """Registers `constructor(obs_settings)` as '<base_name>_features' and '_vision'.

    Raises:
      ValueError: if a name is registered already.
    """
    for variant, settings in _VARIANTS:
        if variant == "vision" and not vision:
            continue
        name = f"{base_name}_{variant}"
        if name in _CONSTRUCTORS:
            raise ValueError(f"environment {name!r} is registered already")
        _CONSTRUCTORS[name] = _bind(constructor, settings)
        for tag in (variant, *tags):
            _TAGS[tag].append(name)


def _bind(constructor, settings):
    def build() -> composer.Task:
        return constructor(settings)

    return build


def names() -> tuple[str, ...]:
    """Every registered environment name, in registration order."""
    return tuple(_CONSTRUCTORS)


def tags() -> tuple[str, ...]:
    """Every tag, in the order tags were first used."""
    return tuple(_TAGS)


def names_with_tag(tag: str) -> tuple[str, ...]:
    """The environment names tagged `tag`.

    Raises:
      ValueError: if no environment has that tag.
    """
    if tag not in _TAGS:
        raise ValueError(f"unknown tag {tag!r}; the tags are {', '.join(_TAGS)}")
    return tuple(_TAGS[tag])


def build_task(name: str) -> composer.Task:
    """Builds a fresh task for the environment `name`.

    Raises:
      ValueError: if `name` is not registered; the message lists close matches.
    """
    constructor = _CONSTRUCTORS.get(name)
    if constructor is None:
        close = difflib.get_close_matches(str(name), _CONSTRUCTORS, n=5, cutoff=0.5)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise ValueError(
            f"unknown environment name {name!r}{hint} (manipulation.ALL lists all "
            f"{len(_CONSTRUCTORS)} names)"
        )
    return constructor()
