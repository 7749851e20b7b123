# SPDX-License-Identifier: BSD-3-Clause
"""The plot's ellipse magnification: chosen so the ellipses can be seen, stated in the legend."""
import math

import numpy as np

from cylslam import plot


def test_magnification_makes_small_ellipses_visible():
    # sigma 1 cm: 95 % semi-axis 2.45 cm; on a 10 m plot the target is 15 cm -> x10 (24.5 cm), not x5 (12.2 cm)
    covs = [np.diag([1e-4, 1e-4])] * 5
    assert plot.ellipse_magnification(covs, 10.0) == 10
    # the median decides, not one outlier
    assert plot.ellipse_magnification(covs + [np.diag([4.0, 4.0])], 10.0) == 10
    # already visible (sigma 0.5 m on a 10 m plot): drawn as they are
    assert plot.ellipse_magnification([np.diag([0.25, 0.01])], 10.0) == 1
    # tiny ones saturate at the largest factor; nothing to draw -> 1
    assert plot.ellipse_magnification([np.diag([1e-12, 1e-12])], 10.0) == plot.MAGNIFICATIONS[-1]
    assert plot.ellipse_magnification([], 10.0) == 1


def test_magnified_ellipse_is_the_scaled_ellipse():
    c = np.array([[4e-4, 1e-4], [1e-4, 1e-4]])
    m = 20
    e1 = plot.ellipse_points([1.0, 2.0], c) - [1.0, 2.0]
    e2 = plot.ellipse_points([1.0, 2.0], m * m * c) - [1.0, 2.0]
    np.testing.assert_allclose(e2, m * e1, atol=1e-12)
    # the semi-major axis of the 95 % ellipse: sqrt(chi2 * largest eigenvalue)
    assert math.isclose(np.max(np.hypot(e1[:, 0], e1[:, 1])),
                        math.sqrt(plot.CHI2_2_95 * np.linalg.eigvalsh(c)[-1]), rel_tol=1e-3)
