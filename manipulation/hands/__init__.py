"""Hands of the manipulation suite."""

from manipulation.hands.jaco_hand import JacoHand

__all__ = ["JacoHand"]
