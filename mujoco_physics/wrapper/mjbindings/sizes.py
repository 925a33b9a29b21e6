"""`array_sizes`: struct name ('mjmodel', 'mjdata') -> field -> its extents, such as
`('ngeom', 3)`, read from the installed `mujoco` (`mujoco.introspect`)."""

from mujoco_physics import field_layout

array_sizes: dict[str, dict[str, tuple]] = {
    "mjmodel": dict(field_layout.MODEL_EXTENTS),
    "mjdata": dict(field_layout.DATA_EXTENTS),
}
