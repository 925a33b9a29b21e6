"""Constants shared by Composer entities and tasks."""

#: MJCF `group` given to sites that only anchor sensors, so renderers can hide them.
SENSOR_SITES_GROUP = 4
