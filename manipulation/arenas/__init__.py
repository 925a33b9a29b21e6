"""Arenas of the manipulation suite."""

from manipulation.arenas.table import TableArena

__all__ = ["TableArena"]
