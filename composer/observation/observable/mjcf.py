"""Observables addressed by MJCF elements rather than by compiled names."""

from collections.abc import Iterable

import mjcf
from composer.observation.observable import base
from composer.observation.observable.selection import MJCFSelection


def _check_element(obj, owner: str) -> None:
    if not isinstance(obj, mjcf.Element):
        raise ValueError(f"{owner}: expected an mjcf.Element, got {type(obj).__name__}: {obj!r}")


def _check_elements(obj, owner: str) -> None:
    if isinstance(obj, Iterable) and not isinstance(obj, str):
        for element in obj:
            _check_element(element, owner)
    else:
        _check_element(obj, owner)


#: dm_control's name for the error an MJCFCamera with both image kinds raises.
_BOTH_SEGMENTATION_AND_DEPTH_ENABLED = base._BOTH_SEGMENTATION_AND_DEPTH_ENABLED


class MJCFFeature(base.Observable):
    """An observable reading field `kind` of `physics.bind(mjcf_element)`.

    `mjcf_element` is one element or a list of elements (`MJCFFeature('xpos', site)`,
    `MJCFFeature('qpos', joints)`); `index`, when given, selects from the bound array.
    Indexing the observable (`MJCFFeature('xmat', site)[2:6]`) returns a new, disabled
    observable with the same options whose value is this one's value indexed by the key;
    indexing again applies the next key to that result.
    """

    def __init__(
        self,
        kind: str,
        mjcf_element,
        update_interval=1,
        buffer_size=None,
        delay=None,
        aggregator=None,
        corruptor=None,
        index=None,
    ):
        _check_elements(mjcf_element, f"MJCFFeature({kind!r})")
        self._selection = MJCFSelection(mjcf_element, kind, () if index is None else (index,))
        super().__init__(update_interval, buffer_size, delay, aggregator, corruptor)

    @property
    def selection(self) -> MJCFSelection:
        """What this observable reads: its element(s), the binding field and the index keys.

        Its value on the CPU is `selection.select(getattr(physics.bind(selection.element),
        selection.field))`; the batched reader reads the same entries in every world.
        `MJCFFeature('xpos', site, index=2)` selects (site, 'xpos', (2,)); indexing the
        observable appends its key to `indices`.
        """
        return self._selection

    def __getitem__(self, key) -> "MJCFFeature":
        selection = self._selection
        indexed = MJCFFeature(
            selection.field,
            selection.element,
            self.update_interval,
            self.buffer_size,
            self.delay,
            self.aggregator,
            self.corruptor,
        )
        indexed._selection = selection.indexed(key)
        return indexed

    def _callable(self, physics):
        return self._selection.reader(physics)

    def _live_source(self, physics):
        # A binding serves consecutive rows as a view of MuJoCo's array and gathers others
        # into a reused buffer on every read; only the former is live.
        return base.view_source(self._selection.reader(physics)())

    def __repr__(self) -> str:
        selection = self._selection
        keys = "".join(f"[{key!r}]" for key in selection.indices)
        return f"<MJCFFeature observable {selection.field!r}{keys} of {selection.element!r}>"


class MJCFCamera(base._ImageObservable):
    """Images rendered from the MJCF `<camera>` element `mjcf_element`."""

    def __init__(
        self,
        mjcf_element,
        height=240,
        width=320,
        update_interval=1,
        buffer_size=None,
        delay=None,
        aggregator=None,
        corruptor=None,
        depth=False,
        segmentation=False,
        scene_option=None,
        render_flag_overrides=None,
    ):
        _check_element(mjcf_element, "MJCFCamera")
        if mjcf_element.tag != "camera":
            raise ValueError(f"MJCFCamera: expected a <camera> element, got <{mjcf_element.tag}>")
        self._mjcf_element = mjcf_element
        super().__init__(
            height=height,
            width=width,
            update_interval=update_interval,
            buffer_size=buffer_size,
            delay=delay,
            aggregator=aggregator,
            corruptor=corruptor,
            depth=depth,
            segmentation=segmentation,
            scene_option=scene_option,
            render_flag_overrides=render_flag_overrides,
        )

    @property
    def mjcf_element(self):
        return self._mjcf_element

    def _callable(self, physics):
        return self._render_function(physics, self._mjcf_element.full_identifier)

    def __repr__(self) -> str:
        return f"<MJCFCamera observable of {self._mjcf_element!r}>"
