"""Evaluation of structures that contain variations (see `base.evaluate`)."""

from composer.variation.base import evaluate

__all__ = ["evaluate"]
