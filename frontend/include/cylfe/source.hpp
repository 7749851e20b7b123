// SPDX-License-Identifier: BSD-3-Clause
// Frame sources behind one interface: V4L2 devices, raw logs, image/video files, the synthetic scene.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cylfe/rawlog.hpp"

extern "C" {
#include "cyl/image.h"
}

namespace cylfe {

// One item from a source: a frame (with a libcyl view of its pixels, valid until the next call
// to next()), or odometry / ground truth passed through from sources that have them.
struct SourceEvent {
    RecordType kind = RecordType::Frame;
    RecordHeader header;            // seq, t_ns, flags (and payload size for frames)
    cyl_image image{};              // kind == Frame
    const uint8_t *data = nullptr;  // kind == Frame: the frame's bytes (header.size of them)
    Odometry odometry;              // kind == Odometry
    TruthPose truth_pose;           // kind == TruthPose
    TruthLandmark truth_landmark;   // kind == TruthLandmark
};

class Source {
public:
    virtual ~Source() = default;
    // Stream description (format, size, stride; flags such as kHasTruth).
    virtual const StreamInfo &info() const = 0;
    // Next event; false at the end of the stream (or when stopped).
    virtual bool next(SourceEvent &ev) = 0;
    // Frames dropped so far (sequence gaps reported by the driver); 0 for files.
    virtual uint64_t dropped() const { return 0; }
    // Progress in [0, 1] for finite sources, negative when unknown (live cameras).
    virtual double progress() const { return -1.0; }
};

} // namespace cylfe
