"""Props of the manipulation suite: a Duplo-style brick, boxes, a pedestal and a cradle."""

from manipulation.props.boxes import BoxWithSites, LargeBox
from manipulation.props.cradle import Cradle
from manipulation.props.duplo import Duplo2x4
from manipulation.props.pedestal import Pedestal
from manipulation.props.prop import Prop, PropObservables

__all__ = ["BoxWithSites", "Cradle", "Duplo2x4", "LargeBox", "Pedestal", "Prop", "PropObservables"]
