// SPDX-License-Identifier: BSD-3-Clause
// Internal to frontend/src/synth/: corner points of the scene's rectangular objects (boxes, floor
// patches), shared by the renderer's screen boxes and the experiments' projections.
#pragma once
#include <array>
#include <cmath>
#include <initializer_list>
#include <vector>

namespace cylfe {
namespace synth {
namespace detail {

// Appends the corners of an sx x sy rectangle centred at (x, y) and turned by yaw, once per
// height in zs: for each height, k = 0..3 with k&1 choosing +-sx/2 and k&2 +-sy/2.
inline void append_rect_corners(double x, double y, double yaw, double sx, double sy,
                                std::initializer_list<double> zs, std::vector<std::array<double, 3>> &pts)
{
    const double ca = std::cos(yaw), sa = std::sin(yaw);
    for (double z : zs)
        for (int k = 0; k < 4; k++) {
            double lx = (k & 1 ? 0.5 : -0.5) * sx, ly = (k & 2 ? 0.5 : -0.5) * sy;
            pts.push_back({x + ca * lx - sa * ly, y + sa * lx + ca * ly, z});
        }
}

} // namespace detail
} // namespace synth
} // namespace cylfe
