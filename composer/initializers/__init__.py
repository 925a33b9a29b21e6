"""Episode initializers: safe prop placement and arm placement by inverse kinematics."""

from composer.initializers.prop_initializer import PropPlacer
from composer.initializers.tcp_initializer import ToolCenterPointInitializer

__all__ = ["PropPlacer", "ToolCenterPointInitializer"]
