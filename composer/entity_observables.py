"""`Observables`: the container of an entity's observables."""

import collections
import posixpath
import weakref

from composer import define

# Keys that `set_options` treats as one option dict meant for every observable.
_OPTION_KEYS = frozenset(
    ["update_interval", "buffer_size", "delay", "aggregator", "corruptor", "enabled"]
)


def _model_scope(entity) -> str:
    """The scope of the entity's model in the compiled model: '' for the top model, else the
    names of the attached models from the top down, each followed by '/' ('arm/hand/')."""
    try:
        model = entity.mjcf_model
        names = []
        while model.parent_model is not None:
            names.append(model.model)
            model = model.parent_model
    except AttributeError as exc:
        raise ValueError(f"cannot qualify observable names: {exc}") from exc
    return "".join(name + "/" for name in reversed(names))


class _ObservableKeys:
    """`observables.dict_keys.<name>`: the fully qualified key of observable `<name>`."""

    def __init__(self, entity, observables):
        self._entity = entity
        self._observables = observables

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return posixpath.join(_model_scope(self._entity), name)

    def __dir__(self):
        return sorted(set(self._observables) | set(super().__dir__()))


class Observables:
    """The observables of one entity, keyed by name.

    Subclasses declare observables as methods decorated with `@composer.observable`; they
    are built when the container is, listed in name order, and readable as attributes
    (`entity.observables.joint_positions`). Observables added with `add_observable` are
    readable as attributes too. Entity observables start disabled; a task enables the ones
    it uses (`enabled = True`, `enable_all()`).

    Fully qualified keys prefix each name with the scope of the entity's model in the
    compiled model, the names of the models it is attached under and its own:
    'jaco_arm/jaco_hand/pinch_site_pos'; a top-level entity's keys are its bare names.
    """

    def __init__(self, entity):
        self._entity = weakref.proxy(entity)
        self._observables = collections.OrderedDict()
        self._keys_helper = _ObservableKeys(self._entity, self._observables)
        cls = type(self)
        for name in sorted(dir(cls)):
            if isinstance(getattr(cls, name, None), define.observable):
                self._observables[name] = getattr(self, name)

    def __getattr__(self, name):
        # Only reached when normal look-up fails: observables added with `add_observable`.
        observables = self.__dict__.get("_observables")
        if observables is not None and name in observables:
            return observables[name]
        raise AttributeError(f"{type(self).__name__!r} has no observable or attribute {name!r}")

    @property
    def dict_keys(self) -> _ObservableKeys:
        """An object whose attribute `<name>` is the fully qualified key of `<name>`."""
        return self._keys_helper

    def as_dict(self, fully_qualified: bool = True) -> collections.OrderedDict:
        """Returns a new OrderedDict of this entity's observables.

        Args:
          fully_qualified: whether keys are prefixed with the scope of the entity's model.
        """
        if not fully_qualified:
            return self._observables.copy()
        prefix = _model_scope(self._entity)
        if not prefix:
            return self._observables.copy()
        # `posixpath.join(prefix, name)`, as the prefix ends with '/'; joined by hand as this
        # runs for every observable at every reset.
        return collections.OrderedDict(
            (name if name.startswith("/") else prefix + name, observable)
            for name, observable in self._observables.items()
        )

    def get_observable(self, name: str, name_fully_qualified: bool = False):
        """Returns the observable `name` (prefixed with the model's scope if
        `name_fully_qualified`)."""
        if name_fully_qualified:
            prefix = _model_scope(self._entity)
            if not name.startswith(prefix):
                raise KeyError(f"observable key {name!r} does not start with {prefix!r}")
            name = name[len(prefix) :]
        try:
            return self._observables[name]
        except KeyError:
            raise KeyError(
                f"no observable named {name!r}; available: {list(self._observables)}"
            ) from None

    def set_options(self, options) -> None:
        """Configures observables from a dict of per-observable option dicts.

        `options` maps observable names to dicts of options (`update_interval`,
        `buffer_size`, `delay`, `aggregator`, `corruptor`, `enabled`); a single dict of
        options applies to every observable; None does nothing.
        """
        if not options:
            return
        if set(options).issubset(_OPTION_KEYS):
            options = {name: options for name in self._observables}
        for name, observable_options in options.items():
            if name not in self._observables:
                raise KeyError(
                    f"set_options: no observable named {name!r}; available: "
                    f"{list(self._observables)}"
                )
            try:
                self._observables[name].configure(**observable_options)
            except (ValueError, TypeError, AttributeError) as exc:
                raise type(exc)(f"observable {name!r}: {exc}") from None

    def enable_all(self) -> None:
        """Enables every observable of this entity."""
        for observable in self._observables.values():
            observable.enabled = True

    def disable_all(self) -> None:
        """Disables every observable of this entity."""
        for observable in self._observables.values():
            observable.enabled = False

    def add_observable(self, name: str, observable, enabled: bool = True) -> None:
        """Adds (or replaces) observable `name`, enabled unless `enabled` is False."""
        self._observables[name] = observable
        observable.enabled = enabled
