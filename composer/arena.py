"""The arena: the root entity of a scene, holding global settings and the other entities."""

import numpy as np

import mjcf
from composer.entity import BuiltAttribute, Entity


class Arena(Entity):
    """An empty world to attach robots and props to.

    The model sets the global options every Composer scene shares: radian angles,
    elliptic friction cones with noslip iterations, a 2 ms timestep, a soft
    headlight and small visual scales. It has no floor, walls or cameras; a subclass
    adds its own in `_build`, after calling `super()._build(name=...)` to create the
    model (`self.mjcf_model`). The docs page "Write your own task" shows one.

    Args (to the constructor):
      name: the model name, which scopes nothing (the arena is the root) but names
        the scene; defaults to 'base', as in dm_control.
      xml_path: an MJCF file to start from instead of the built-in model, as in
        dm_control; relative asset paths in the arena then resolve against its folder.

    Relative asset paths added to an arena built in code resolve against the working
    directory, like any `mjcf.RootElement`'s; when this class serves
    `dm_control.composer.Arena` (the dm_control redirect, with dm_control installed), against
    dm_control's `composer` folder, where dm_control's own arena model lives and relative to
    which its arenas name their textures (`compiler texturedir='../locomotion/...'`).
    """

    _mjcf_root = BuiltAttribute(
        "{cls} has no MJCF model ({name!r}): {build_owner}._build did not call "
        "super()._build(). Start {build_owner}._build with super()._build(name=...), which "
        "creates the arena's model and its shared settings, then add to self.mjcf_model"
    )

    def _build(self, name: str | None = None, xml_path: str | None = None) -> None:
        if xml_path is not None:
            self._mjcf_root = mjcf.from_path(xml_path)
            if name:
                self._mjcf_root.model = name
            return
        # Imported here: `python -m composer.dm_control_compat` must find that module not yet
        # imported when the `composer` package is.
        from composer import dm_control_compat

        model_dir = dm_control_compat.real_package_dir("composer") or ""
        self._mjcf_root = mjcf.RootElement(model=name or "base", model_dir=model_dir)
        root = self._mjcf_root
        root.compiler.set_attributes(angle="radian", boundmass=1e-5, boundinertia=1e-11)
        root.option.set_attributes(
            timestep=0.002, cone="elliptic", noslip_iterations=5, noslip_tolerance=0
        )
        root.visual.map.znear = 0.01
        root.visual.headlight.set_attributes(
            ambient=[0.3, 0.3, 0.3], diffuse=[0.6, 0.6, 0.6], specular=[0, 0, 0]
        )
        root.visual.scale.set_attributes(
            forcewidth=0.01,
            contactwidth=0.06,
            contactheight=0.01,
            jointwidth=0.01,
            framewidth=0.01,
            framelength=0.3,
        )

    @property
    def mjcf_model(self):
        return self._mjcf_root

    def add_free_entity(self, entity: Entity):
        """Attaches `entity` so that it moves freely and returns its attachment frame.

        The joints come from `entity.create_root_joints` (a free joint by default).
        """
        frame = self.attach(entity)
        entity.create_root_joints(frame)
        return frame

    def attach_offset(self, entity: Entity, offset, attach_site=None):
        """Attaches `entity` rigidly at `offset` and returns its attachment frame.

        Args:
          entity: the entity to attach.
          offset: a position (3 values) or a position and quaternion (7 values).
          attach_site: as for `attach`.

        Raises:
          ValueError: if `offset` does not have 3 or 7 values.
        """
        offset = np.asarray(offset, dtype=np.float64).ravel()
        if offset.size not in (3, 7):
            raise ValueError(
                f"offset: expected 3 values (position) or 7 (position and quaternion), "
                f"got {offset.size}"
            )
        frame = self.attach(entity, attach_site=attach_site)
        frame.pos = offset[:3]
        if offset.size == 7:
            frame.quat = offset[3:]
        return frame
