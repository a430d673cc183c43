"""The array types of the package's signatures, named once: ``FloatArray`` (float64),
``IntArray`` (int64) and ``BoolArray``. Shapes are in each function's docstring."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["BoolArray", "FloatArray", "IntArray"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]
