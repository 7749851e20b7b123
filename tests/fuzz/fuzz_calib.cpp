// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer: the calibration file reader (OpenCV and ROS YAML). Any bytes must load or end in
// a cylfe::Error; any other exception (cv::Exception, std::...) escaping is a finding.
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>

#include "cylfe/calibration.hpp"
#include "cylfe/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static std::string path = "/tmp/fuzz_calib_" + std::to_string(getpid()) + ".yaml";
    FILE *f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    std::fwrite(data, 1, size, f);
    std::fclose(f);
    try {
        cylfe::CameraCalibration c = cylfe::load_camera_calibration(path);
        // The contract (calibration.hpp): a file that loads has valid intrinsics; with its mount
        // fields present the whole camera passes cyl_camera_check.
        const cyl_camera &m = c.cam;
        if (!(m.fx_px > 0 && m.fy_px > 0 && m.width > 0 && m.height > 0)) __builtin_trap();
        if (c.mount_known && cyl_camera_check(&m) != CYL_OK) __builtin_trap();
    } catch (const cylfe::Error &) {
    }
    return 0;
}
