"""JSON has no NaN or infinity: results cross every boundary through :func:`json_safe`."""

from __future__ import annotations

import math

import numpy as np


def json_safe(value):
    """A copy with NaN/±inf replaced by None and numpy scalars by Python numbers."""
    if isinstance(value, dict):
        return {key: json_safe(item) for key, item in value.items()}
    if isinstance(value, list | tuple):
        return [json_safe(item) for item in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
