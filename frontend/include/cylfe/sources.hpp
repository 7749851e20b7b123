// SPDX-License-Identifier: BSD-3-Clause
// Sources other than V4L2 (v4l2.hpp) and the synthetic scene (synth.hpp), and a factory
// that opens any source from a command-line spec.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "cylfe/rawlog.hpp"
#include "cylfe/source.hpp"
#include "cylfe/v4l2.hpp"

namespace cylfe {

// Replays a raw frame log, at full speed or at the recorded pace.
class RawLogSource : public Source {
public:
    RawLogSource(const std::string &path, bool realtime);
    const StreamInfo &info() const override { return reader_.info(); }
    bool next(SourceEvent &ev) override;
    double progress() const override;
    bool truncated() const { return reader_.truncated(); }

private:
    RawLogReader reader_;
    bool realtime_;
    std::vector<uint8_t> payload_;
    int64_t first_t_ = 0, wall0_ = 0;
    bool started_ = false;
};

// Still images (one file, or several) and videos through OpenCV, converted to I420
// (BT.601 as cv::cvtColor(COLOR_BGR2YUV_I420)). Odd sizes are cropped to even.
class FileSource : public Source {
public:
    explicit FileSource(const std::vector<std::string> &paths, double fps = 30.0);
    ~FileSource() override;
    const StreamInfo &info() const override { return info_; }
    bool next(SourceEvent &ev) override;
    double progress() const override;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
    StreamInfo info_;
};

struct SourceOptions {
    V4L2Options v4l2;
    bool realtime = false;      // raw logs at the recorded pace
    uint64_t seed = 1;          // synthetic scene
    uint64_t frames = 0;        // synthetic scene: frame count (0 = its default)
    std::string scene;          // synthetic scene description file ("" = built-in default)
};

// "v4l2:/dev/video0" | "/dev/videoN" | "raw:F" | "F.cylraw" | "file:F" | image/video path |
// "synthetic" | "synthetic:SEED". Throws Error for unknown specs or unreadable sources.
std::unique_ptr<Source> open_source(const std::string &spec, const SourceOptions &opt);

} // namespace cylfe
