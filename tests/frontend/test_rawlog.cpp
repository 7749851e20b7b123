// SPDX-License-Identifier: BSD-3-Clause
// Raw frame log and observation log: round trips, the .part/rename guarantee, every malformation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

#include "cylfe/error.hpp"
#include "cylfe/pipeline.hpp"
#include "cylfe/rawlog.hpp"
#include "cylfe/sources.hpp"

using namespace cylfe;

namespace {

std::string tmp(const std::string &name)
{
    return "/tmp/cylfe_test_" + std::to_string(getpid()) + "_" + name;
}

bool exists(const std::string &p) { return access(p.c_str(), F_OK) == 0; }

std::vector<uint8_t> read_all(const std::string &p)
{
    std::ifstream f(p, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void write_all(const std::string &p, const std::vector<uint8_t> &b)
{
    std::ofstream f(p, std::ios::binary);
    f.write(reinterpret_cast<const char *>(b.data()), (std::streamsize)b.size());
}

StreamInfo yuyv_info(uint32_t w, uint32_t h)
{
    StreamInfo i;
    i.fourcc = fourcc('Y', 'U', 'Y', 'V');
    i.width = w;
    i.height = h;
    i.stride = 2 * w;
    i.frame_bytes = 2 * w * h;
    i.flags = StreamInfo::kHasTruth;
    i.source = "unit test";
    return i;
}

std::string write_sample(const std::string &path)
{
    RawLogWriter w(path, yuyv_info(8, 4));
    std::vector<uint8_t> f(64);
    TruthLandmark lm;
    lm.id = 7; lm.cls = 1; lm.x_m = 1.5; lm.y_m = -2.25; lm.diameter_m = 0.1; lm.height_m = 0.3;
    w.truth_landmark(0, lm);
    for (int k = 0; k < 3; k++) {
        for (size_t i = 0; i < f.size(); i++) f[i] = (uint8_t)(i * 3 + k);
        w.frame(100 + k, 1000000000LL * k + 5, f.data(), f.size(), k == 1 ? 1u : 0u);
        Odometry o;
        o.dx_m = 0.1 * k; o.dtheta_rad = -0.01; o.cov[0] = 1e-4; o.cov[5] = 2e-4;
        w.odometry(100 + k, 1000000000LL * k + 5, o);
        TruthPose p;
        p.x_m = k; p.y_m = 2 * k; p.theta_rad = 0.5;
        w.truth_pose(100 + k, 1000000000LL * k + 5, p);
    }
    EXPECT_TRUE(exists(path + ".part"));
    EXPECT_FALSE(exists(path));
    w.close();
    EXPECT_FALSE(exists(path + ".part"));
    EXPECT_TRUE(exists(path));
    return path;
}

} // namespace

TEST(RawLog, RoundTrip)
{
    std::string p = write_sample(tmp("rt.cylraw"));
    RawLogReader r(p);
    EXPECT_EQ(r.info().width, 8u);
    EXPECT_EQ(r.info().source, "unit test");
    EXPECT_EQ(r.info().flags, StreamInfo::kHasTruth);
    RecordHeader h;
    std::vector<uint8_t> pl;
    ASSERT_TRUE(r.next(h, pl));
    EXPECT_EQ(h.type, RecordType::TruthLandmark);
    TruthLandmark lm = RawLogReader::parse_truth_landmark(pl);
    EXPECT_EQ(lm.id, 7u);
    EXPECT_EQ(lm.y_m, -2.25);
    int frames = 0;
    while (r.next(h, pl)) {
        if (h.type == RecordType::Frame) {
            EXPECT_EQ(h.seq, 100u + frames);
            EXPECT_EQ(h.t_ns, 1000000000LL * frames + 5);
            EXPECT_EQ(h.flags, frames == 1 ? 1u : 0u);
            EXPECT_EQ(pl[10], (uint8_t)(30 + frames));
            frames++;
        } else if (h.type == RecordType::Odometry) {
            Odometry o = RawLogReader::parse_odometry(pl);
            EXPECT_DOUBLE_EQ(o.dx_m, 0.1 * (frames - 1));
            EXPECT_EQ(o.cov[5], 2e-4);
        }
    }
    EXPECT_EQ(frames, 3);
    EXPECT_FALSE(r.truncated());
    std::remove(p.c_str());
}

TEST(RawLog, TruncatedTailKeepsCompleteRecords)
{
    std::string p = write_sample(tmp("tr.cylraw"));
    std::vector<uint8_t> b = read_all(p);
    b.resize(b.size() - 30);  // cut into the last truth pose record
    write_all(p, b);
    RawLogReader r(p);
    RecordHeader h;
    std::vector<uint8_t> pl;
    int n = 0;
    while (r.next(h, pl)) n++;
    EXPECT_EQ(n, 1 + 3 * 3 - 1);
    EXPECT_TRUE(r.truncated());
    std::remove(p.c_str());
}

TEST(RawLog, BadFilesNameTheProblem)
{
    std::string p = write_sample(tmp("bad.cylraw"));
    std::vector<uint8_t> good = read_all(p), b;
    auto error_of = [&](const std::vector<uint8_t> &bytes) {
        write_all(p, bytes);
        try {
            RawLogReader r(p);
            RecordHeader h;
            std::vector<uint8_t> pl;
            while (r.next(h, pl)) {}
        } catch (const Error &e) {
            return std::string(e.what());
        }
        return std::string();
    };
    b = good; b[0] = 'X';
    EXPECT_NE(error_of(b).find("bad magic"), std::string::npos);
    b = good; b[8] = 9;
    EXPECT_NE(error_of(b).find("version 9"), std::string::npos);
    b = good; b[32] = 1;  // frame size field
    EXPECT_NE(error_of(b).find("frame size field"), std::string::npos);
    b = good; b[16] = 'Z';  // fourcc
    EXPECT_NE(error_of(b).find("pixel format"), std::string::npos);
    b = good; b[64] = 'Q';  // first record's magic
    EXPECT_NE(error_of(b).find("corrupt record header at byte 64"), std::string::npos);
    b = good; b[64 + 24] = 41;  // truth landmark payload size
    EXPECT_NE(error_of(b).find("payload size 41"), std::string::npos);
    b.assign(good.begin(), good.begin() + 20);
    EXPECT_NE(error_of(b).find("truncated or malformed header"), std::string::npos);
    EXPECT_NE(error_of({}).find("bad magic"), std::string::npos);
    std::remove(p.c_str());
    try {
        RawLogReader r(tmp("missing.cylraw"));
        FAIL() << "no error for a missing file";
    } catch (const Error &e) {
        EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
    }
}

TEST(RawLog, WriterRejectsWrongFrameSize)
{
    std::string p = tmp("ws.cylraw");
    RawLogWriter w(p, yuyv_info(8, 4));
    std::vector<uint8_t> f(63);
    EXPECT_THROW(w.frame(0, 0, f.data(), f.size()), Error);
    w.close();
    std::remove(p.c_str());
}

TEST(RawLog, ReplaySourceWrapsFrames)
{
    std::string p = write_sample(tmp("src.cylraw"));
    RawLogSource s(p, false);
    SourceEvent ev;
    int frames = 0, odo = 0, truth = 0, lms = 0;
    while (s.next(ev)) {
        if (ev.kind == RecordType::Frame) {
            EXPECT_EQ(ev.image.format, CYL_FMT_YUYV);
            EXPECT_EQ(ev.image.width, 8u);
            EXPECT_EQ(ev.image.stride[0], 16u);
            frames++;
        }
        odo += ev.kind == RecordType::Odometry;
        truth += ev.kind == RecordType::TruthPose;
        lms += ev.kind == RecordType::TruthLandmark;
    }
    EXPECT_EQ(frames, 3);
    EXPECT_EQ(odo, 3);
    EXPECT_EQ(truth, 3);
    EXPECT_EQ(lms, 1);
    EXPECT_NEAR(s.progress(), 1.0, 1e-12);
    std::remove(p.c_str());
}

TEST(ObservationLog, LinesAreJsonAndRenamedOnClose)
{
    std::string p = tmp("obs.jsonl");
    cyl_colortable t;
    cyl_colortable_init(&t);
    cyl_colortable_set_class(&t, 0, "or\"ange", 1, 2, 3);
    cyl_camera cam;
    cyl_camera_init(&cam);
    ObservationLog::Header h;
    h.source = "test";
    h.model = "exact";
    h.estimator = "local";
    h.table = &t;
    h.camera = &cam;
    {
        ObservationLog log(p, h);
        cyl_observation o{};
        o.cls = 0;
        o.range_m = 2.5;
        o.bearing_rad = -0.25;
        o.cov_rb[0][0] = 0.01;
        o.cov_rb[0][1] = o.cov_rb[1][0] = 1e-4;
        o.cov_rb[1][1] = 4e-4;
        o.var_u_px2 = std::nan("");
        log.frame(3, 1500000000LL, {o, o});
        Odometry od;
        od.dx_m = 0.125;
        log.odometry(3, 1500000000LL, od);
        EXPECT_TRUE(exists(p + ".part"));
        EXPECT_FALSE(exists(p));
        log.close();
    }
    EXPECT_TRUE(exists(p));
    std::ifstream f(p);
    std::vector<std::string> lines;
    for (std::string l; std::getline(f, l);) lines.push_back(l);
    ASSERT_EQ(lines.size(), 5u);
    EXPECT_NE(lines[0].find("\"format\":\"cyl-observations\",\"version\":2"), std::string::npos);
    EXPECT_NE(lines[0].find("\"or\\\"ange\""), std::string::npos);  // escaped quote
    EXPECT_NE(lines[1].find("{\"type\":\"frame\",\"seq\":3,\"t\":1.500000000,\"n_obs\":2}"), std::string::npos);
    EXPECT_NE(lines[2].find("\"range_m\":2.5,\"bearing_rad\":-0.25,\"cov_rr\":0.01,\"cov_rb\":0.0001,\"cov_bb\":0.0004"),
              std::string::npos);
    EXPECT_NE(lines[2].find("\"var_u_px2\":null"), std::string::npos);  // NaN is not JSON
    EXPECT_NE(lines[4].find("\"dx_m\":0.125"), std::string::npos);
    for (const std::string &l : lines) {
        EXPECT_EQ(l.front(), '{');
        EXPECT_EQ(l.back(), '}');
    }
    std::remove(p.c_str());
}
