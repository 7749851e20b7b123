// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer: the raw frame log reader. Any bytes must end in records or a cylfe::Error.
#include <cstdint>
#include <cstdio>
#include <string>
#include <unistd.h>
#include <vector>

#include "cylfe/error.hpp"
#include "cylfe/rawlog.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static std::string path = "/tmp/fuzz_rawlog_" + std::to_string(getpid()) + ".cylraw";
    FILE *f = std::fopen(path.c_str(), "wb");
    if (!f) return 0;
    std::fwrite(data, 1, size, f);
    std::fclose(f);
    try {
        cylfe::RawLogReader r(path);
        cylfe::RecordHeader h;
        std::vector<uint8_t> p;
        while (r.next(h, p)) {
            if (h.type == cylfe::RecordType::Odometry) cylfe::RawLogReader::parse_odometry(p);
            if (h.type == cylfe::RecordType::TruthPose) cylfe::RawLogReader::parse_truth_pose(p);
            if (h.type == cylfe::RecordType::TruthLandmark) cylfe::RawLogReader::parse_truth_landmark(p);
        }
    } catch (const cylfe::Error &) {
    }
    return 0;
}
