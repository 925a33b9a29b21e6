"""What a patch proof made on one model promises for a change on another: the context of a
change.

A proof shows that writing an attribute's compiled value gives a recompile's model in the
changes it made. Whether a write suffices can depend on more than the (tag, attribute)
pair: on where the value is set (an element, or a default-class template that several
elements take), on whether a value replaces another or is set where nothing was (then the
compiler may derive something from the attribute's presence: an actuator's `ctrllimited`
from its `ctrlrange`), and, for some pairs, on the element (a geom's type, for its size).
`PatchContext` is that key. A proof at first use (`mjcf.patching.first_use_proof`) proves
one context and promises nothing for another: a change in a context no proof covers is
proven again, on the model at hand. The corpus proof (`mjcf.patching.patch_proof`) proves a
pair over every context its models have, and its verdict stands for the pair.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from mjcf import attachment, traversal_utils
from mjcf.element import AttributeChange, AttributeChanges, Element

__all__ = ["ON_DEFAULT_CLASS", "ON_ELEMENT", "PatchContext", "context_of", "variety"]

#: Where a changed value is set: on the element itself, or on a default-class template.
ON_ELEMENT = "element"
ON_DEFAULT_CLASS = "default class"

# Pairs whose patch depends on the element beyond its tag (see `variety`).
_GEOM_SIZE = ("geom", "size")
_POSE = ("pos", "quat")


class PatchContext(NamedTuple):
    """The context of one attribute change, as proofs tell contexts apart.

    Attributes:
      tag: the changed element's tag (a template's own tag, `geom` under `<default>`).
      attribute: the XML attribute.
      where: `ON_ELEMENT` or `ON_DEFAULT_CLASS`.
      from_unset: whether nothing set the value before the change (MuJoCo's built-in
        default applied), where a value now is.
      variety: what else sets the change apart (see `variety`); empty for most pairs.
    """

    tag: str
    attribute: str
    where: str
    from_unset: bool
    variety: tuple[str, ...]

    @property
    def pair(self) -> tuple[str, str]:
        """(tag, attribute)."""
        return (self.tag, self.attribute)

    def describe(self) -> str:
        """'<geom> size on an element, type=box, ...' for messages."""
        parts = [f"on a {self.where}" if self.where != ON_ELEMENT else "on an element"]
        if self.from_unset:
            parts.append("set where nothing set it")
        parts.extend(self.variety)
        return f"<{self.tag}> {self.attribute!r} ({', '.join(parts)})"


def variety(element: Element, attribute: str) -> tuple[str, ...]:
    """What sets apart changes of `element`'s `attribute` beyond its tag and where it is set.

    For every pair, the compiler options the model sets (its angle unit, `autolimits`, mass
    bounds, ... change how a value compiles), and whether the model has a joint whose
    stiffness and damping come from `springdamper` (the compiler converts them with the
    inertia of the joint's tree, which many changes move: a joint's damping is a write in
    place only without it). Besides, for an element (not a template, whose elements may
    differ): a geom's size feeds its bounds, its body's bounding volumes and inertia, so its
    type, whether `fromto` gives it, and whether its body has an explicit inertial; a
    position or orientation, whether `fromto` gives it and whether the element is a body
    with a free joint. In a model with `springdamper`, a joint's change also tells whether
    the joint (for a template: one of the joints of its class) takes it, which replaces its
    own stiffness and damping.
    """
    root = element._root.root_model
    tag = element._spec.name
    template = traversal_utils.is_default_template(element)
    has_springdamper, compiler = _model_flags(root)
    if not has_springdamper:
        springs: tuple[str, ...] = (compiler, "no springdamper")
    elif tag == "joint":
        takes = _takes_springdamper(element, root) if template else _own_springdamper(element)
        springs = (
            compiler,
            "springdamper joints",
            "takes springdamper" if takes else "own damping",
        )
    else:
        springs = (compiler, "springdamper joints")
    if template:
        return springs
    if attribute in _POSE:
        segment = "fromto" in element._spec.attributes and _resolves(element, "fromto")
        free = tag == "body" and traversal_utils.get_freejoint(element) is not None
        return springs + (
            "given by fromto" if segment else "no fromto",
            "free body" if free else "no free joint",
        )
    if (tag, attribute) != _GEOM_SIZE:
        return springs
    type_source = traversal_utils.default_value_source(element, "type")
    body = element._parent
    explicit = body._spec.name == "body" and bool(body.get_children("inertial"))
    return springs + (
        f"type={type_source._attributes['type'] if type_source is not None else 'sphere'}",
        "given by fromto" if _resolves(element, "fromto") else "no fromto",
        "explicit inertial" if explicit else "inertia from geoms",
    )


# The last answer of `_model_flags`: (model, the modification count it holds at, answer).
# A reset's changes share one model and one count, and the next reset's changes (colours,
# poses) rarely touch what it answers.
_FLAGS: list = [None, -1, (False, "")]


def _model_flags(root) -> tuple[bool, str]:
    """Whether an element of `root` or of a model attached below it (a joint, a joint
    template) sets `springdamper`; and the compiler options the model sets ('compiler:
    angle=radian, ...'), which change how values compile (units, limits from ranges,
    bounds on masses)."""
    count = root.modification_count
    if _FLAGS[0] is root and _FLAGS[1] == count:
        return _FLAGS[2]
    if _FLAGS[0] is root:
        since = root.attribute_changes_since(_FLAGS[1])
        if since is not None and not any(_moves_flags(change) for change in since):
            _FLAGS[1] = count
            return _FLAGS[2]
    found = False
    models = [root]
    for model in models:
        if any("springdamper" in element._attributes for element in model._iter_own_tree()):
            found = True
            break
        models.extend(frame._attached for frame in model._frames)
    options = [
        f"{name}={_shown(value)}"
        for (path, name), value in sorted(attachment.global_options(root).items())
        if path == ("compiler",)
    ]
    compiler = "compiler: " + (", ".join(options) if options else "defaults")
    _FLAGS[:] = [root, count, (found, compiler)]
    return found, compiler


def _moves_flags(change: AttributeChange) -> bool:
    """Whether `change` may change what `_model_flags` answers."""
    return change.attribute == "springdamper" or change.element._spec.name == "compiler"


def _shown(value) -> str:
    if isinstance(value, np.ndarray):
        return " ".join(str(number) for number in value.tolist())
    return str(value)


def _own_springdamper(joint: Element) -> bool:
    return traversal_utils.default_value_source(joint, "springdamper") is not None


def _takes_springdamper(template: Element, root) -> bool:
    """Whether a joint of `root` whose default classes include `template`'s takes
    `springdamper`."""
    dclass = template._parent
    return any(
        dclass in traversal_utils.default_classes(joint) and _own_springdamper(joint)
        for joint in root.find_all("joint")
    )


def _resolves(element: Element, xml_name: str) -> bool:
    return traversal_utils.default_value_source(element, xml_name) is not None


def context_of(change: AttributeChange, changes: AttributeChanges) -> PatchContext:
    """The context of `change`, one of `changes` (which say what was set at their count)."""
    element, attribute = change
    template = traversal_utils.is_default_template(element)
    from_unset = not changes.was_set_before(change) and (
        template or traversal_utils.class_value_source(element, attribute) is None
    )
    return PatchContext(
        element._spec.name,
        attribute,
        ON_DEFAULT_CLASS if template else ON_ELEMENT,
        from_unset and attribute in element._attributes,
        variety(element, attribute),
    )
