// SPDX-License-Identifier: BSD-3-Clause
// Motion-JPEG frames (what most USB webcams deliver at their useful resolutions) decoded straight
// to planar YUV with libjpeg(-turbo)'s raw-data output: no RGB round trip, so the colour table sees
// the camera's own Y, Cb, Cr. Every frame comes out as YUYV (4:2:2 packed): a 4:2:2 JPEG (what
// webcams send) exactly as sampled, so that it segments as the camera's own YUYV would; 4:2:0 and
// 4:4:0 with each chroma sample repeated down its rows, 4:4:4 with each pixel pair's mean. JPEG's
// YCbCr is full range (JFIF): train the colour table on frames of the same path (cyl record from
// the same camera in MJPG).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace cylfe {

class MjpegDecoder {
public:
    // Decode one JPEG into `out` (YUYV, 2*width bytes a row). The frame must be width x height
    // (width even); throws Error naming `what` on a corrupt frame, another size, a colour space
    // other than YCbCr, or another sampling.
    void decode(const uint8_t *jpeg, size_t size, uint32_t width, uint32_t height, std::vector<uint8_t> &out,
                const std::string &what);
    // The JPEG's chroma sampling of the last frame: "4:2:2", "4:2:0", "4:4:4" or "4:4:0".
    const std::string &last_sampling() const { return sampling_; }

private:
    std::vector<uint8_t> plane_[3];  // padded planes as libjpeg writes them
    std::string sampling_;
};

// YUYV payload size for width x height (even width; libcyl's layout, stride 2*width).
size_t yuyv_size(uint32_t width, uint32_t height);

} // namespace cylfe
