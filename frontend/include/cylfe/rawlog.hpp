// SPDX-License-Identifier: BSD-3-Clause
// Raw frame log (*.cylraw, docs/formats.md): record any source, replay it later.
#pragma once
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "cylfe/output_file.hpp"

extern "C" {
#include "cyl/image.h"
}

namespace cylfe {

constexpr uint32_t fourcc(char a, char b, char c, char d)
{
    return (uint32_t)(uint8_t)a | ((uint32_t)(uint8_t)b << 8) | ((uint32_t)(uint8_t)c << 16) |
           ((uint32_t)(uint8_t)d << 24);
}

// V4L2 fourcc <-> libcyl pixel format. pixfmt_from_fourcc returns 0 for unsupported codes.
uint32_t fourcc_from_pixfmt(cyl_pixfmt f);
cyl_pixfmt pixfmt_from_fourcc(uint32_t fcc);
std::string fourcc_str(uint32_t fcc);

enum class RecordType : uint32_t { Frame = 1, Odometry = 2, TruthPose = 3, TruthLandmark = 4 };

struct StreamInfo {
    uint32_t fourcc = 0;       // V4L2 fourcc of the frames
    uint32_t width = 0;        // px
    uint32_t height = 0;       // px
    uint32_t stride = 0;       // bytes per line of plane 0
    uint32_t frame_bytes = 0;  // bytes of one frame payload
    uint32_t flags = 0;        // kMonotonic | kHasTruth
    std::string source;        // free text, <= 23 bytes stored
    static constexpr uint32_t kMonotonic = 1u, kHasTruth = 2u;
};

struct RecordHeader {
    RecordType type = RecordType::Frame;
    uint64_t seq = 0;          // frame sequence number
    int64_t t_ns = 0;          // timestamp, ns
    uint32_t size = 0;         // payload bytes
    uint32_t flags = 0;        // frames: bit 0 = driver flagged the buffer corrupt
};

struct Odometry {
    double dx_m = 0, dy_m = 0, dtheta_rad = 0;  // increment in the previous pose's frame
    double cov[6] = {0, 0, 0, 0, 0, 0};         // upper triangle xx xy xt yy yt tt (m^2, m rad, rad^2)
};

struct TruthPose {
    double x_m = 0, y_m = 0, theta_rad = 0;     // world frame
};

struct TruthLandmark {
    uint32_t id = 0, cls = 0;                    // landmark id, colour class index
    double x_m = 0, y_m = 0, diameter_m = 0, height_m = 0;
};

// Writes to "<path>.part", flushing every record, and renames it to <path> on close(): a good
// file is never replaced by a partial one, and a killed recording leaves its complete records
// in the .part file. A device node or FIFO is written directly and a symlink is written through
// (cylfe/output_file.hpp): only a regular file is ever replaced.
class RawLogWriter {
public:
    RawLogWriter(const std::string &path, const StreamInfo &info);
    ~RawLogWriter();
    RawLogWriter(const RawLogWriter &) = delete;
    RawLogWriter &operator=(const RawLogWriter &) = delete;

    void frame(uint64_t seq, int64_t t_ns, const uint8_t *data, size_t n, uint32_t flags = 0);
    void odometry(uint64_t seq, int64_t t_ns, const Odometry &o);
    void truth_pose(uint64_t seq, int64_t t_ns, const TruthPose &p);
    void truth_landmark(int64_t t_ns, const TruthLandmark &l);
    void close();                 // flush, rename; throws on I/O error
    uint64_t records() const { return records_; }
    const std::string &written_to() const { return part_; }  // the .part file, or the path itself

private:
    void record(RecordType type, uint64_t seq, int64_t t_ns, const void *payload, uint32_t n, uint32_t flags);
    std::string path_;
    OutputPlan plan_;
    std::string part_;  // where the bytes go (plan_.write_to)
    FILE *f_ = nullptr;
    StreamInfo info_;
    uint64_t records_ = 0;
};

// Sequential reader. Throws Error naming the file on a bad header; a truncated last record
// ends the stream (truncated() tells).
class RawLogReader {
public:
    explicit RawLogReader(const std::string &path);
    ~RawLogReader();
    RawLogReader(const RawLogReader &) = delete;
    RawLogReader &operator=(const RawLogReader &) = delete;

    const StreamInfo &info() const { return info_; }
    // Next record into h and payload; false at the end of the file.
    bool next(RecordHeader &h, std::vector<uint8_t> &payload);
    bool truncated() const { return truncated_; }
    uint64_t file_size() const { return size_; }
    uint64_t offset() const { return offset_; }
    void rewind();
    static Odometry parse_odometry(const std::vector<uint8_t> &p);
    static TruthPose parse_truth_pose(const std::vector<uint8_t> &p);
    static TruthLandmark parse_truth_landmark(const std::vector<uint8_t> &p);

private:
    std::string path_;
    FILE *f_ = nullptr;
    StreamInfo info_;
    bool truncated_ = false;
    uint64_t size_ = 0, offset_ = 0;
};

} // namespace cylfe
