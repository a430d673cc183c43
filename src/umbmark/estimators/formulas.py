"""The paper's equations of Sec. 4, as printed, from the two centres of gravity.

- ``beta``  from x: ``(x_cw - x_ccw) / (-4L)`` (4.20a); from y: ``(y_cw + y_ccw) / (-4L)`` (4.20b)
- ``alpha`` from x: ``(x_cw + x_ccw) / (-4L)`` (4.24a); from y: ``(y_cw - y_ccw) / (-4L)`` (4.24b)
- ``E_d`` from ``beta`` by Eqs. 4.21 and 4.22 (chord ``L``, nominal ``b``); ``E_b`` from
  ``alpha`` by Eq. 4.27.

The printed forms multiply by ``180 / pi`` to give degrees; here angles stay in radians.
"""

from __future__ import annotations

from umbmark.core.arrays import FloatArray
from umbmark.estimators.base import SquareTest
from umbmark.model.systematic import E_b_from_alpha, E_d_from_beta

__all__ = ["paper_components"]


def paper_components(z: FloatArray, test: SquareTest) -> dict[str, float]:
    """Every figure of Sec. 4 from ``z = (x_cw, y_cw, x_ccw, y_ccw)`` [m]."""
    x_cw, y_cw, x_ccw, y_ccw = (float(v) for v in z)
    k = -4.0 * test.side_length
    alpha_x = (x_cw + x_ccw) / k  # Eq. 4.24a, in radians
    alpha_y = (y_cw - y_ccw) / k  # Eq. 4.24b
    beta_x = (x_cw - x_ccw) / k  # Eq. 4.20a
    beta_y = (y_cw + y_ccw) / k  # Eq. 4.20b
    L, b = test.side_length, test.wheelbase
    E_b_x, E_b_y = float(E_b_from_alpha(alpha_x)), float(E_b_from_alpha(alpha_y))
    E_d_x, E_d_y = float(E_d_from_beta(beta_x, L, b)), float(E_d_from_beta(beta_y, L, b))
    return {
        "alpha_x": alpha_x,
        "alpha_y": alpha_y,
        "beta_x": beta_x,
        "beta_y": beta_y,
        "E_b_x": E_b_x,
        "E_b_y": E_b_y,
        "E_d_x": E_d_x,
        "E_d_y": E_d_y,
        "alpha": 0.5 * (alpha_x + alpha_y),
        "beta": 0.5 * (beta_x + beta_y),
        "E_b": 0.5 * (E_b_x + E_b_y),
        "E_d": 0.5 * (E_d_x + E_d_y),
        "alpha_x_minus_y": alpha_x - alpha_y,
        "beta_x_minus_y": beta_x - beta_y,
    }
