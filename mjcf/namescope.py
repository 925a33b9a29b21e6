"""Identifier registry of one model: unique names per namespace, and the model's scope name."""

from __future__ import annotations

from mjcf import constants

UNNAMED_MODEL = "unnamed_model"


class NameScope:
    """Identifiers of one `RootElement`, per namespace ('body', 'geom', 'default', ...).

    Attributes:
      naming_stamp: a number that changes whenever an identifier, model name or attachment
        changes in this model or in any model attached below it (never to a value it had
        before, nor to one another scope's stamp had), so text with scoped names written for
        this model stays valid while the stamp is unchanged.
      mjcf_model: the RootElement this scope belongs to.
      model_dir: directory that relative file paths of this model are resolved against.
      assets: filename -> bytes given when the model was created, consulted before the disk.
    """

    __slots__ = (
        "mjcf_model",
        "model_dir",
        "assets",
        "_namespaces",
        "_unnamed_counts",
        "_unnamed",
        "naming_stamp",
    )

    # Source of naming stamps, shared by all scopes so that no two changes get the same one.
    _changes = 0

    def naming_changed(self) -> None:
        """Gives this scope, and the scopes of the models it is attached below, a new stamp."""
        NameScope._changes += 1
        stamp = NameScope._changes
        model = self.mjcf_model
        while model is not None:
            model._namescope.naming_stamp = stamp
            frame = model._frame
            model = frame._root if frame is not None else None

    def __init__(self, mjcf_model, model_dir: str = "", assets: dict | None = None):
        NameScope._changes += 1
        self.naming_stamp = NameScope._changes
        self.mjcf_model = mjcf_model
        self.model_dir = model_dir
        self.assets = dict(assets) if assets else {}
        self._namespaces: dict[str, dict[str, object]] = {}
        self._unnamed_counts: dict[str, int] = {}
        # Generated identifier -> element, per namespace; built on first lookup.
        self._unnamed: dict[str, dict[str, object]] | None = None

    @property
    def name(self) -> str:
        """The model name that scopes this model's identifiers when it is attached."""
        return self.mjcf_model._attributes["model"]

    @property
    def parent(self) -> NameScope | None:
        frame = self.mjcf_model._frame
        return frame._root._namescope if frame is not None else None

    @property
    def root(self) -> NameScope:
        scope = self
        while scope.parent is not None:
            scope = scope.parent
        return scope

    def full_prefix(self, prefix_root=None) -> str:
        """Prefix ('a/b/') of this scope's identifiers as seen from model `prefix_root`.

        `prefix_root` is a RootElement or its NameScope above this one; None gives ''.
        """
        if prefix_root is None:
            return ""
        if isinstance(prefix_root, NameScope):
            prefix_root = prefix_root.mjcf_model
        parts = []
        model = self.mjcf_model
        while model is not prefix_root and model._frame is not None:
            parts.append(model._namescope.name)
            model = model._frame._root
        if not parts:
            return ""
        parts.reverse()
        return constants.PREFIX_SEPARATOR.join(parts) + constants.PREFIX_SEPARATOR

    def get(self, namespace: str, identifier: str):
        """Returns the element named `identifier` in `namespace` of this model.

        Raises:
          KeyError: no element of this model has that identifier in that namespace.
        """
        found = self._namespaces.get(namespace, {}).get(identifier)
        if found is None:
            raise KeyError(f"model {self.name!r} has no {namespace!r} element named {identifier!r}")
        return found

    def find(self, namespace: str, identifier: str):
        """Returns the element named `identifier` in `namespace` of this model, or None."""
        return self._namespaces.get(namespace, {}).get(identifier)

    def has_identifier(self, namespace: str, identifier: str) -> bool:
        return identifier in self._namespaces.get(namespace, {})

    def add(self, namespace: str, identifier: str, element) -> None:
        """Registers `element` under `identifier`; a taken identifier is a ValueError."""
        names = self._namespaces.setdefault(namespace, {})
        existing = names.get(identifier)
        if existing is not None and existing is not element:
            raise ValueError(
                f"duplicate identifier {identifier!r} in namespace {namespace!r} of model "
                f"{self.name!r}: {_describe(element)} clashes with {_describe(existing)}"
            )
        names[identifier] = element
        self.naming_changed()

    def remove(self, namespace: str, identifier: str) -> None:
        names = self._namespaces.get(namespace)
        if names is not None:
            names.pop(identifier, None)
        self.naming_changed()

    def identifiers(self, namespace: str) -> list[str]:
        return list(self._namespaces.get(namespace, {}))

    def next_unnamed(self, namespace: str, element) -> str:
        """A fresh identifier for an unnamed element; cannot clash with user names."""
        counts = self._unnamed_counts
        count = counts.get(namespace, 0)
        counts[namespace] = count + 1
        identifier = f"/unnamed_{namespace}_{count}"
        if self._unnamed is not None:
            self.add_unnamed(namespace, identifier, element)
        return identifier

    def add_unnamed(self, namespace: str, identifier: str, element) -> None:
        if self._unnamed is None:
            return
        unnamed = self._unnamed.get(namespace)
        if unnamed is None:
            unnamed = self._unnamed[namespace] = {}
        unnamed[identifier] = element

    def get_unnamed(self, namespace: str, identifier: str):
        """The unnamed element that was given generated `identifier`, or None."""
        if self._unnamed is None:
            # Looking elements up by generated name is rare and generating names is frequent
            # (every XML write of a new model), so the index is built on first use.
            self._unnamed = {}
            for element in self.mjcf_model._iter_own_tree():
                if element._auto_id is not None:
                    self.add_unnamed(element._spec.namespace, element._auto_id, element)
        return self._unnamed.get(namespace, {}).get(identifier)

    def remove_unnamed(self, namespace: str, identifier: str) -> None:
        if self._unnamed is not None:
            self._unnamed.get(namespace, {}).pop(identifier, None)


def _describe(element) -> str:
    parent = element._parent
    where = f" in {parent._describe()}" if parent is not None else ""
    return f"{element._describe()}{where}"
